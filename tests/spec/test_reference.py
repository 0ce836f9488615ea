"""The spec reference: docs/spec.md is what the models say, key for key, range for range."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Annotated, Literal, Union

import pytest
from pydantic import BaseModel, ConfigDict, Discriminator, Field, Tag

from ehlfoam.errors import SpecError
from ehlfoam.spec.case import CaseSpec, make_case_spec
from ehlfoam.spec.reference import COMMAND, DOCUMENTS, main, render, render_document, tables

ROOT = Path(__file__).resolve().parents[2]
SPEC_MD = ROOT / "docs" / "spec.md"


def _keys(model: type[BaseModel], where: str = "") -> list[str]:
    """Every dotted key of a model, found independently of the generator's walk: nested
    models through their JSON schema's properties."""
    schema = model.model_json_schema()
    defs = schema.get("$defs", {})

    def walk(node: dict, prefix: str) -> list[str]:
        out = []
        for name, prop in node.get("properties", {}).items():
            name = prop.get("key", name)   # a table of any case-spec keys names a placeholder
            key = f"{prefix}.{name}" if prefix else name
            out.append(key)
            refs = [r["$ref"] for r in _refs(prop)]
            items = prop.get("items") or next((a.get("items") for a in prop.get("anyOf", [])
                                               if "items" in a), None)
            item_refs = [r["$ref"] for r in _refs(items or {})]
            for ref in dict.fromkeys(refs):
                if ref not in item_refs:
                    out += walk(defs[ref.split("/")[-1]], key)
            for ref in dict.fromkeys(item_refs):
                out += walk(defs[ref.split("/")[-1]], f"{key}[i]")
        return out

    return walk(schema, where)


def _refs(node: dict) -> list[dict]:
    """The {"$ref": ...} nodes inside a schema node (anyOf, oneOf, allOf, items)."""
    if "$ref" in node:
        return [node]
    out = []
    for key in ("anyOf", "oneOf", "allOf"):
        for sub in node.get(key, []):
            out += _refs(sub)
    if "items" in node and isinstance(node["items"], dict):
        out += _refs(node["items"])
    return out


def _row(text: str, key: str) -> str:
    """The table row of a key in the rendered reference."""
    rows = [line for line in text.splitlines() if line.startswith(f"| `{key}` |")]
    assert len(rows) == 1, f"{key}: {len(rows)} rows"
    return rows[0]


def test_the_committed_reference_is_the_generators_output():
    assert SPEC_MD.is_file(), f"docs/spec.md is missing: run `{COMMAND}` from the repository root"
    assert SPEC_MD.read_text() == render(), (
        f"docs/spec.md is stale (the spec models changed): run `{COMMAND}` from the "
        f"repository root and commit it")


@pytest.mark.parametrize("doc", DOCUMENTS, ids=lambda d: d.title)
def test_every_key_of_every_spec_has_its_row(doc):
    text = render_document(doc)
    keys = _keys(doc.root())
    assert len(keys) > 5
    missing = [k for k in keys if f"| `{k}` |" not in text]
    assert not missing


def _case_doc() -> str:
    return render_document(next(d for d in DOCUMENTS if d.root() is CaseSpec))


def test_the_case_specs_top_level_and_contact_tables_are_all_there():
    text = _case_doc()
    for name in CaseSpec.model_fields:
        _row(text, name)
    for name in CaseSpec.model_fields["contact"].annotation.model_fields:
        _row(text, f"contact.{name}")


@pytest.mark.parametrize("key, value", [("contact.speed", -0.01),
                                        ("physics.surface_tension", 0.0),
                                        ("mesh.n_layers", 0)])
def test_a_keys_range_reads_as_the_error_states_it(key, value):
    with pytest.raises(SpecError) as err:
        make_case_spec(**{key: value})
    stated = re.search(r"\(valid range (.+?)\)", str(err.value)).group(1)
    row = _row(_case_doc(), key)
    cells = [c.strip() for c in row.strip("|").split(" | ")]
    rng, unit = cells[3], cells[4]
    assert f"{rng} {unit}".strip() == stated


def test_a_configured_default_is_the_enclosing_models():
    """The case spec's contact runs at 8 mm/s where a precalc's default is 10 mm/s."""
    row = _row(_case_doc(), "contact.speed")
    assert f"| {CaseSpec().contact.speed:g} |" in row


# --------------------------------------------------------- the walk on a model of its own
class _Box(BaseModel):
    """A box."""

    model_config = ConfigDict(extra="forbid")
    size: float = Field(0.1, gt=0.0, le=1.0, json_schema_extra={"unit": "a"},
                        description="cell size in the box")


class _Band(BaseModel):
    """A band."""

    model_config = ConfigDict(extra="forbid")
    points: tuple[tuple[float, float], ...] = Field(min_length=2)


class _Inner(BaseModel):
    """Inner settings."""

    n: int = Field(3, ge=1, description="how many")


_Refine = Annotated[Union[Annotated[_Box, Tag("box")], Annotated[_Band, Tag("band")]],
                    Discriminator(lambda v: "band" if "points" in v else "box")]


class _Spec(BaseModel):
    """A spec to walk."""

    mode: Literal["a", "b"] = "a"
    refine: tuple[_Refine, ...] = ()
    inner: _Inner = _Inner(n=5)
    extra: _Inner | None = None
    speed: float = Field(0.01, gt=0.0, le=100.0, json_schema_extra={"unit": "m/s"},
                         description="rolling | speed")


def test_the_walk_renders_choices_units_descriptions_unions_and_nested_tables():
    ts = {(t.where, t.tag): t for t in tables(_Spec)}
    assert set(ts) == {("", ""), ("refine[i]", "box"), ("refine[i]", "band"), ("inner", ""),
                       ("extra", "")}
    top = {r.key: r for r in ts["", ""].rows}
    assert top["mode"].type == 'one of "a", "b"' and top["mode"].default == '"a"'
    assert top["refine"].type == "list of tables (box or band)"
    assert top["extra"].type == "table or none" and top["extra"].default == "none"
    assert (top["speed"].range, top["speed"].unit) == ("0 < speed <= 100", "m/s")
    box = ts["refine[i]", "box"].rows[0]
    assert (box.key, box.range, box.unit, box.description) == (
        "refine[i].size", "0 < refine[i].size <= 1", "a", "cell size in the box")
    band = ts["refine[i]", "band"].rows[0]
    assert (band.type, band.default, band.range) == ("list of [number, number]", "required",
                                                     "at least 2 items")
    assert ts["inner", ""].rows[0].default == "5"      # the enclosing default's, not 3
    assert ts["extra", ""].rows[0].default == "3"      # no instance: the model's own
    assert "optional table" in ts["extra", ""].note


def test_a_pipe_in_a_description_does_not_break_the_table(tmp_path, monkeypatch):
    from ehlfoam.spec import reference

    monkeypatch.setattr(reference, "DOCUMENTS", (
        reference.Document("Test", f"{__name__}:_Spec", "intro"),))
    text = reference.render(reference.DOCUMENTS)
    row = _row(text, "speed")
    assert row.count(" | ") == 5 and "rolling \\| speed" in row


def test_write_puts_the_reference_where_asked(tmp_path, capsys):
    out = tmp_path / "spec.md"
    assert main(["--write", str(out)]) == 0
    assert out.read_text() == render()
    assert main(["--write", str(tmp_path / "no" / "spec.md")]) == 2
    assert "repository root" in capsys.readouterr().err
