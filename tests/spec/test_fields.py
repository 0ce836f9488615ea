"""Every parameter of the case spec and the precalc spec says what it is and in which unit:
the field's ``description`` and ``json_schema_extra["unit"]``, which the spec reference in the
docs and the error messages read."""

from __future__ import annotations

import pytest
from pydantic import BaseModel

from ehlfoam.contact.spec import PrecalcSpec, make_spec, valid_range
from ehlfoam.errors import SpecError, unit_of
from ehlfoam.spec import CaseSpec, make_case_spec
from ehlfoam.spec.mesh import REFINE_KINDS
from tests.test_citations import REMOVED

#: The units a field may state: SI (volumes of oil in m3, a diffusivity in m2/s), the Hertzian radius a for in-plane
#: lengths, degrees, C.
UNITS = {"a", "deg", "C", "m", "s", "N", "Pa", "Pa s", "kg/m3", "m/s", "N/m", "1/s", "1/Pa",
         "1/(Pa s)", "m3", "m2/s"}


def _models(root: type[BaseModel]) -> list[type[BaseModel]]:
    """``root`` and every model its fields hold, the refinement kinds included."""
    seen: list[type[BaseModel]] = []

    def walk(model: type[BaseModel]) -> None:
        if model in seen:
            return
        seen.append(model)
        for field in model.model_fields.values():
            for arg in _classes(field.annotation):
                walk(arg)

    walk(root)
    for model in REFINE_KINDS.values():
        walk(model)
    return seen


def _classes(annotation) -> list[type[BaseModel]]:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [m for arg in getattr(annotation, "__args__", ()) for m in _classes(arg)]


FIELDS = [(model, name) for model in _models(CaseSpec) for name in model.model_fields]


def test_the_walk_reaches_every_table():
    names = {model.__name__ for model, _ in FIELDS}
    assert {"CaseSpec", "PrecalcSpec", "Supply", "Physics", "Domain", "Mesh", "Run",
            "RefineBox", "RefineBand", "Follow", "SideBox"} <= names


@pytest.mark.parametrize("model, name", FIELDS,
                         ids=[f"{m.__name__}.{n}" for m, n in FIELDS])
def test_every_field_has_a_description_and_a_known_unit(model, name):
    field = model.model_fields[name]
    assert field.description and len(field.description) >= 10, f"{model.__name__}.{name}"
    assert not [page for page in REMOVED if page in field.description]
    assert unit_of(field) in UNITS | {""}


@pytest.mark.parametrize("overrides, text", [
    ({"contact.speed": -0.01}, "valid range 0 < contact.speed <= 100 m/s"),
    ({"domain.side": 0.5}, "valid range 1 < domain.side <= 200 a"),
    ({"physics.contact_angle": 190.0}, "valid range 0 <= physics.contact_angle <= 180 deg"),
    ({"run.capillary_safety": 0.0}, "valid range 0 < run.capillary_safety <= 100)"),
])
def test_a_bad_value_is_refused_with_the_range_in_its_unit(overrides, text):
    with pytest.raises(SpecError) as err:
        make_case_spec({}, **overrides)
    assert text in str(err.value)


def test_the_precalc_reads_its_units_from_the_fields():
    assert valid_range("load") == "valid range 0 < load <= 100000 N"
    assert valid_range("tol_load") == "valid range 0 < tol_load < 1"
    # a custom oil has no table: the field's own range, in its unit
    with pytest.raises(SpecError,
                       match=r"temperature = 400.0: .*valid range -40 <= temperature <= 300 C"):
        make_spec(temperature=400.0, lubricant="custom", eta0=0.02, alpha=2e-8, rho0=870.0)
    # a tabulated oil: its table's range, not the field's (issue 77)
    with pytest.raises(SpecError, match=r"outside the HVI60 table: valid range 25 to 60 C"):
        make_spec(temperature=400.0)
    assert {unit_of(PrecalcSpec.model_fields[k]) for k in ("eta0", "alpha", "rho0")} \
        == {"Pa s", "1/Pa", "kg/m3"}
