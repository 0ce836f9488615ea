"""The one formatter of spec errors: keys named as the user wrote them, values, ranges, units."""

from __future__ import annotations

from typing import Annotated, Literal, Union

import pytest
from pydantic import BaseModel, ConfigDict, Discriminator, Field, Tag, ValidationError

from ehlfoam.errors import format_validation_error, range_text

_STRICT = ConfigDict(extra="forbid")


class Box(BaseModel):
    model_config = _STRICT
    kind: Literal["box"] = "box"
    size: float = Field(0.1, gt=0.0, le=1.0, json_schema_extra={"unit": "a"})


class Band(BaseModel):
    model_config = _STRICT
    kind: Literal["band"] = "band"
    width: float = Field(1.0, gt=0.0)


Refine = Annotated[Union[Annotated[Box, Tag("box")], Annotated[Band, Tag("band")]],
                   Discriminator(lambda v: v.get("kind", "box") if isinstance(v, dict) else v.kind)]


class Mesh(BaseModel):
    model_config = _STRICT
    refine: list[Refine] = []
    n: int = Field(3, ge=1)


class Spec(BaseModel):
    model_config = _STRICT
    mesh: Mesh = Mesh()
    speed: float = Field(0.01, gt=0.0, le=100.0)
    name: str


def _message(data: dict, **kw) -> str:
    with pytest.raises(ValidationError) as info:
        Spec(**data)
    return format_validation_error(info.value, Spec, **kw)


def test_a_value_out_of_range_names_the_key_its_value_and_the_range_with_its_unit():
    text = _message({"name": "x", "speed": -1.0}, units={"speed": "m/s"})
    assert text.startswith("speed = -1.0: Input should be greater than 0")
    assert "(valid range 0 < speed <= 100 m/s)" in text


def test_list_items_are_indexed_and_union_tags_left_out_the_fields_unit_wins():
    text = _message({"name": "x", "mesh": {"refine": [{}, {"kind": "box", "size": 2.0}]}})
    assert text.startswith("mesh.refine[1].size = 2.0:") and "valid range 0 < mesh.refine[1].size <= 1 a" in text


def test_an_unknown_key_lists_the_valid_keys_of_its_own_table():
    assert _message({"name": "x", "mesh": {"levels": 3}}) == \
        "mesh.levels: unknown key (valid here: refine, n)"
    assert "spd: unknown key (valid here: mesh, speed, name)" in _message({"name": "x", "spd": 1})


def test_a_missing_key_takes_its_hint_and_errors_are_joined():
    text = _message({"speed": 0.0}, hints={"name": "give the case a name"})
    clauses = text.split("; ")
    assert "name: missing: give the case a name" in clauses and len(clauses) == 2


def test_range_text_without_constraints_is_empty():
    assert range_text("name", Spec.model_fields["name"]) == ""
