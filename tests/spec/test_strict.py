"""Strict types in every spec (issue 73): no boolean and no string for a number, no fraction
for an integer, an integer for a number; arrays for tuples; a written case's spec.json reads
back; a table override merges key by key; a dotted key below a value is named."""

from __future__ import annotations

import pytest
from ehlfoam.batch.plan import expand
from ehlfoam.batch.spec import parse_batch_spec
from ehlfoam.contact.spec import make_spec
from ehlfoam.errors import SpecError
from ehlfoam.spec import CaseSpec, make_case_spec
from tests.tiny import SMALL


@pytest.mark.parametrize("data, words", [
    ({"contact": {"load": True}}, "contact.load = True: a boolean is not a number"),
    ({"contact": {"load": "25"}}, "contact.load = '25': a string is not a number"),
    ({"contact": {"speed": "0.02"}}, "contact.speed = '0.02': a string is not a number"),
    ({"mesh": {"n_layers": True}}, "mesh.n_layers = True: a boolean is not an integer"),
    ({"mesh": {"n_layers": 3.0}}, "mesh.n_layers = 3.0: 3.0 is not an integer (write 3)"),
    ({"mesh": {"n_layers": "3"}}, "mesh.n_layers = '3': a string is not an integer"),
    ({"run": {"writes_per_transit": 2.5}}, "run.writes_per_transit = 2.5: 2.5 is not an integer"),
    ({"walls_moving": 1}, "walls_moving = 1: Input should be a valid boolean"),
    ({"name": 7}, "name = 7: Input should be a valid string"),
    ({"mesh": {"refine": [{"points": [["1", 2], [3, 4]], "half_width": 1, "size": 0.1}]}},
     "mesh.refine[0].points[0][0] = '1': a string is not a number"),
    ({"mesh": {"polar_radius": True}}, "mesh.polar_radius"),
])
def test_no_bool_or_string_for_a_number_in_a_case_spec(data, words):
    with pytest.raises(SpecError) as info:
        make_case_spec(data)
    assert words in str(info.value)


def test_an_integer_is_a_number_and_arrays_are_tuples():
    spec = make_case_spec({"contact": {"load": 20, "speed": 1}, "run": {"wall_limit": 60},
                           "mesh": {"refine": [{"points": [[1, 2], [3, 4]], "half_width": 1,
                                                "size": 0.1}]}})
    assert spec.contact.load == 20.0 and isinstance(spec.contact.load, float)
    assert spec.mesh.refine[0].points == ((1.0, 2.0), (3.0, 4.0))
    assert CaseSpec.model_validate_json(spec.model_dump_json()) == spec   # spec.json reads back


def test_the_precalc_and_batch_specs_are_strict_too():
    with pytest.raises(SpecError, match="load = True: a boolean is not a number"):
        make_spec(load=True)
    with pytest.raises(SpecError, match="grid = 129.0: 129.0 is not an integer"):
        make_spec(grid=129.0)
    base = {k: v for k, v in SMALL.items() if isinstance(v, dict)}
    with pytest.raises(SpecError, match="contact.speed = '0.02': a string is not a number"):
        expand(parse_batch_spec({"base": base, "sweep": {"contact.speed": ["0.02"]}}))
    with pytest.raises(SpecError, match="description = 3: Input should be a valid string"):
        parse_batch_spec({"description": 3, "sweep": {"contact.speed": [0.01]}})


def test_a_table_override_merges_into_the_files_table():
    spec = make_case_spec(SMALL, mesh={"resolution": "fine", "n_layers": 4})
    assert spec.mesh.resolution == "fine" and spec.mesh.n_layers == 4
    assert spec.mesh.size_rim == SMALL["mesh"]["size_rim"]         # the file's, kept
    assert spec.mesh.wall_grading == SMALL["mesh"]["wall_grading"]
    spec = make_case_spec(SMALL, **{"contact": {"load": 25}})
    assert spec.contact.load == 25 and spec.contact.speed == SMALL["contact"]["speed"]
    assert SMALL["mesh"]["n_layers"] == 3                             # the data untouched


@pytest.mark.parametrize("key, words", [
    ("contact.speed.x", "contact.speed.x: contact.speed is a value, not a table"),
    ("mesh.refine.x", "mesh.refine is a value, not a table"),
    ("contract.speed", "contract: unknown key (valid here: name, rung, scene, contact"),
    ("contact..speed", "is not a dotted key"),
])
def test_a_dotted_key_must_name_a_table_then_a_key(key, words):
    with pytest.raises(SpecError) as info:
        make_case_spec(SMALL, **{key: 1})
    assert words in str(info.value)
