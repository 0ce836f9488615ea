"""Bad input, said once: :class:`SpecError` and the one formatter of spec validation errors.

Every spec (the contact's, the case's, the batch's) is a pydantic model; what goes wrong in
one is reported the same way, one clause per problem, joined by "; "::

    contact.speed = -0.01: Input should be greater than 0 (valid range 0 < contact.speed <= 100 m/s)
    mesh.levels: unknown key (valid here: resolution, polar_radius, ...)
    ramp[0].speed: missing

Locations name the key as the user wrote it: nested tables joined by dots, list items by
``[i]``, and the tags of a tagged union (``mesh.refine[0]`` is a box or a band) left out.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Annotated, Any, get_args, get_origin

from pydantic import BaseModel, Tag, ValidationError
from pydantic.fields import FieldInfo

__all__ = ["SpecError", "format_validation_error", "models_in", "range_text", "unit_of"]


class SpecError(ValueError):
    """An invalid input, with a message naming the parameter, its value and the valid range."""


def range_text(name: str, field: FieldInfo | None, unit: str = "") -> str:
    """'valid range 0 < name <= 1 unit' from a pydantic field's numeric constraints ('' if
    none)."""
    lo = hi = ""
    for m in getattr(field, "metadata", []):
        for attr, fmt in (("gt", "{} < "), ("ge", "{} <= ")):
            if getattr(m, attr, None) is not None:
                lo = fmt.format(f"{getattr(m, attr):g}")
        for attr, fmt in (("lt", " < {}"), ("le", " <= {}")):
            if getattr(m, attr, None) is not None:
                hi = fmt.format(f"{getattr(m, attr):g}")
    if not (lo or hi):
        return ""
    return f"valid range {lo}{name}{hi}" + (f" {unit}" if unit else "")


def unit_of(field: FieldInfo | None) -> str:
    """A field's unit, from ``Field(json_schema_extra={"unit": ...})`` ('' if none)."""
    extra = getattr(field, "json_schema_extra", None)
    return str(extra.get("unit", "")) if isinstance(extra, dict) else ""


def models_in(annotation: Any) -> list[type[BaseModel]]:
    """The model classes an annotation holds (itself, or inside a list, tuple, union,
    Annotated)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [m for arg in get_args(annotation) for m in models_in(arg)]


def _tags_in(annotation: Any) -> dict[str, type[BaseModel]]:
    """The tagged members of a tagged union inside an annotation: {tag: model}."""
    out: dict[str, type[BaseModel]] = {}
    if get_origin(annotation) is Annotated:
        inner, *meta = get_args(annotation)
        tags = [m.tag for m in meta if isinstance(m, Tag)]
        models = models_in(inner)
        if tags and len(models) == 1:
            out[tags[0]] = models[0]
    for arg in get_args(annotation):
        out.update(_tags_in(arg))
    return out


def _walk(root: type[BaseModel], loc: tuple) -> tuple[str, type[BaseModel] | None,
                                                      FieldInfo | None]:
    """Follow a pydantic error location through the models: (the location as the user names
    it, the model in which a further key would be looked up, the last key's field)."""
    name, model, field = "", root, None
    for part in loc:
        if isinstance(part, int):
            name += f"[{part}]"
            continue
        tags = _tags_in(field.annotation) if field is not None else {}
        if part in tags:                          # the tag of a union member: not a key
            model, field = tags[part], None
            continue
        field = model.model_fields.get(str(part)) if model is not None else None
        name += f".{part}" if name else str(part)
        inner = models_in(field.annotation) if field is not None else []
        model = inner[0] if len(inner) == 1 else None
    return name, model, field


def _as_written(value: Any) -> Any:
    """A value as the user wrote it: tuples (a strict model's arrays) as lists."""
    if isinstance(value, (tuple, list)):
        return [_as_written(v) for v in value]
    return value


def _strict_text(error: Mapping[str, Any]) -> str | None:
    """What a strict type error means, where pydantic's words do not say it: a boolean or a
    string given for a number, a fraction for an integer."""
    given, kind = error.get("input"), error.get("type")
    if kind not in ("float_type", "int_type", "int_from_float"):
        return None
    wanted = "a number" if kind == "float_type" else "an integer"
    if isinstance(given, bool):
        return f"a boolean is not {wanted} (types are strict)"
    if isinstance(given, str):
        return f"a string is not {wanted} (types are strict: write it without quotes)"
    if isinstance(given, float) and kind != "float_type":
        return f"{given!r} is not an integer (write {int(given)})" \
            if given.is_integer() else f"{given!r} is not an integer"
    return None


def format_validation_error(err: ValidationError, root: type[BaseModel], *,
                            units: Mapping[str, str] | None = None,
                            hints: Mapping[str, str] | None = None,
                            rename: Callable[[tuple], tuple] | None = None) -> str:
    """One clause per error of ``root``'s validation, joined by "; ".

    ``units``: the unit of a key (by its last part) for the valid range, where its field
    does not state one (``json_schema_extra={"unit": ...}``); ``hints``: text
    added to a missing key's clause (by its last part); ``rename``: maps a pydantic location
    to the one the user wrote (e.g. a single ``[sweep]`` table that the model holds as a
    list)."""
    units, hints = units or {}, hints or {}
    clauses = []
    for e in err.errors():
        loc = tuple(e["loc"])
        loc = rename(loc) if rename else loc
        name, _, field = _walk(root, loc)
        name = name or "spec"
        last = str(loc[-1]) if loc else ""
        msg = _strict_text(e) or e["msg"].removeprefix("Value error, ")
        if e["type"] == "extra_forbidden":
            holder = _walk(root, loc[:-1])[1]
            valid = ", ".join(holder.model_fields) if holder is not None else ""
            clauses.append(f"{name}: unknown key" + (f" (valid here: {valid})" if valid else ""))
        elif e["type"] == "missing":
            clauses.append(f"{name}: missing" + (f": {hints[last]}" if last in hints else ""))
        elif loc and "input" in e and not isinstance(e["input"], dict):
            rng = range_text(name, field, unit_of(field) or units.get(last, "")) if field else ""
            clauses.append(f"{name} = {_as_written(e['input'])!r}: {msg}" + (f" ({rng})" if rng else ""))
        else:
            clauses.append(f"{name}: {msg}" if loc else msg)
    return "; ".join(clauses)
