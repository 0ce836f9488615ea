"""The spec reference (``docs/spec.md``), rendered from the pydantic models themselves.

Every key of the case spec and of the batch spec, one table per TOML table: its dotted key,
type or choices, default, valid range (as the error messages state it:
:func:`ehlfoam.errors.range_text`), unit (``Field(json_schema_extra={"unit": ...})``:
:func:`ehlfoam.errors.unit_of`) and description (``Field(description=...)``). The walk is
generic: nested models become tables of their own, lists and tuples of models ``key[i]``,
the members of a tagged union one table each, so whatever the models hold is what the
reference says::

    python -m ehlfoam.spec.reference            # print it
    python -m ehlfoam.spec.reference --write    # rewrite docs/spec.md (from the repository root)

The documents name their root models by dotted path (:data:`DOCUMENTS`) and import them only
when rendered: the batch spec lives above this layer, and the spec layer imports nothing
above it.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import types
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal, Union, get_args, get_origin

from pydantic import BaseModel, Tag
from pydantic.fields import FieldInfo
from pydantic_core import PydanticUndefined

from ehlfoam.errors import range_text, unit_of

__all__ = ["DOCUMENTS", "Document", "render", "render_document", "tables"]

#: Where ``--write`` puts the reference, relative to the repository root.
DEFAULT_PATH = Path("docs/spec.md")
COMMAND = "python -m ehlfoam.spec.reference --write"


@dataclass(frozen=True)
class Document:
    """One spec: a title, its root model as ``"module:Class"``, what it is for (markdown)."""

    title: str
    model: str
    intro: str

    def root(self) -> type[BaseModel]:
        module, name = self.model.split(":")
        return getattr(importlib.import_module(module), name)


DOCUMENTS: tuple[Document, ...] = (
    Document("Case spec", "ehlfoam.spec.case:CaseSpec",
             "A TOML file for `ehlfoam case SPEC --out DIR`; `--set KEY=VALUE` sets one key by "
             "its dotted name. Every key is optional. The `[contact]` table is also the EHL "
             "precalc's own spec (`ehlfoam precalc SPEC`: the same keys at the top level or "
             "under `[precalc]`)."),
    Document("Batch spec", "ehlfoam.batch.spec:BatchSpec",
             "A TOML file for `ehlfoam batch SPEC`: a base case spec (`[base]`, every key of "
             "the case spec above) plus sweeps and speed ramps. A single `[sweep]` table or "
             "several `[[sweep]]` tables (their union); `[[ramp]]` tables run their steps one "
             "after the other. Each expanded case is validated by the case spec itself."),
)


@dataclass(frozen=True)
class Row:
    """One key of a table, its cells as markdown."""

    key: str
    type: str
    default: str
    range: str
    unit: str
    description: str


@dataclass(frozen=True)
class Table:
    """The keys of one TOML table: ``where`` is its dotted name ('' for the top level),
    ``tag`` its kind among a tagged union's members ('' if none), ``note`` what it is."""

    where: str
    tag: str
    note: str
    rows: tuple[Row, ...]


# ---------------------------------------------------------------------- annotations
def _strip(annotation: Any) -> Any:
    """An annotation without Annotated's metadata."""
    while get_origin(annotation) is Annotated:
        annotation = get_args(annotation)[0]
    return annotation


def _is_union(annotation: Any) -> bool:
    return get_origin(annotation) in (Union, types.UnionType)


def _is_model(annotation: Any) -> bool:
    return isinstance(annotation, type) and issubclass(annotation, BaseModel)


def _members(annotation: Any) -> list[tuple[str, type[BaseModel]]]:
    """The models a field holds, directly or as items of a list or tuple, with the tag each
    has in a tagged union ('' where untagged): [(tag, model)]."""
    out: list[tuple[str, type[BaseModel]]] = []
    if get_origin(annotation) is Annotated:
        inner, *meta = get_args(annotation)
        tags = [m.tag for m in meta if isinstance(m, Tag)]
        inner = _strip(inner)
        if tags and _is_model(inner):
            return [(tags[0], inner)]
        return _members(inner)
    if _is_model(annotation):
        return [("", annotation)]
    for arg in get_args(annotation):
        if arg is not Ellipsis:
            out += _members(arg)
    return out


def _is_sequence(annotation: Any) -> bool:
    """Does the annotation (or a member of its union) hold a list or tuple?"""
    annotation = _strip(annotation)
    if _is_union(annotation):
        return any(_is_sequence(a) for a in get_args(annotation))
    return get_origin(annotation) in (list, tuple)


def type_text(annotation: Any) -> str:
    """An annotation in words: 'number', 'one of "a", "b"', 'list of numbers', 'table',
    '... or none'."""
    annotation = _strip(annotation)
    origin, args = get_origin(annotation), get_args(annotation)
    if annotation is type(None):
        return "none"
    if origin is Literal:
        return "one of " + ", ".join(_value_text(a) for a in args)
    if _is_union(annotation):
        parts = [type_text(a) for a in args if a is not type(None)]
        tags = [t for t, _ in _members(annotation) if t]
        if tags and len(tags) == len(parts):
            parts = [f"table ({' or '.join(tags)})"]
        text = " or ".join(dict.fromkeys(parts))
        return text + (" or none" if type(None) in args else "")
    if origin in (list, tuple):
        if origin is tuple and args and args[-1] is not Ellipsis:
            return "[" + ", ".join(type_text(a) for a in args) + "]"
        item = type_text(args[0]) if args else "any"
        if item.startswith("table"):
            return f"list of tables{item[5:]}"
        plural = {"number": "numbers", "integer": "integers", "string": "strings",
                  "boolean": "booleans", "any": "values"}
        return "list of " + plural.get(item, item)
    if origin is dict or annotation is dict:
        return "table"
    if _is_model(annotation):
        return "table"
    return {bool: "boolean", int: "integer", float: "number", str: "string"}.get(
        annotation, "any")


def _value_text(value: Any) -> str:
    """A default or a choice as a TOML reader writes it."""
    if value is None:
        return "none"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_value_text(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {_value_text(v)}" for k, v in value.items()) + "}"
    if isinstance(value, BaseModel):
        return "(table below)"
    return str(value)


# ---------------------------------------------------------------------- cells
def _cell(text: str) -> str:
    """Text fit for a markdown table cell: one line, pipes escaped."""
    return " ".join(str(text).split()).replace("|", "\\|")


def _default(field: FieldInfo, value: Any) -> str:
    if field.default is PydanticUndefined and field.default_factory is None:
        return "required"
    return _value_text(value)


def _constraints(key: str, field: FieldInfo) -> str:
    """The valid range as the errors state it (without "valid range "), and any length or
    pattern constraint."""
    parts = []
    rng = range_text(key, field)
    if rng:
        parts.append(rng.removeprefix("valid range "))
    for m in field.metadata:
        for attr, text in (("min_length", "at least {} items"), ("max_length",
                                                                 "at most {} items"),
                           ("pattern", "matches `{}`")):
            if getattr(m, attr, None) is not None:
                parts.append(text.format(getattr(m, attr)))
    return "; ".join(parts)


def _summary(model: type[BaseModel]) -> str:
    """A model docstring's first sentence, without reStructuredText roles."""
    doc = (model.__doc__ or "").strip().split("\n\n")[0]
    first = " ".join(doc.split()).split(". ")[0].rstrip(".")
    for role in (":class:", ":data:", ":func:", ":attr:", ":mod:"):
        first = first.replace(role, "")
    return (first.replace("``", "`") + ".") if first else ""


# ---------------------------------------------------------------------- the walk
def _name_in_file(name: str, field: FieldInfo) -> str:
    """The key as a spec file writes it: the field's alias, or a placeholder the field names
    (``json_schema_extra={"key": "<case-spec key>"}``: a table of any case-spec keys)."""
    extra = field.json_schema_extra if isinstance(field.json_schema_extra, dict) else {}
    return str(extra.get("key") or field.alias or name)


def tables(root: type[BaseModel], where: str = "", note: str = "",
           instance: BaseModel | None = None, tag: str = "") -> Iterator[Table]:
    """The tables of ``root`` and of every model nested in it, depth first. ``instance``
    gives the defaults where the enclosing field's default is a configured model; ``tag``
    names the kind of a tagged union's member."""
    rows, nested = [], []
    for name, field in root.model_fields.items():
        key = f"{where}.{_name_in_file(name, field)}" if where else _name_in_file(name, field)
        value = getattr(instance, name) if instance is not None else field.get_default(
            call_default_factory=True)
        rows.append(Row(key=key, type=type_text(field.annotation),
                        default=_default(field, value), range=_constraints(key, field),
                        unit=unit_of(field), description=field.description or ""))
        members = _members(field.annotation)
        seq = _is_sequence(field.annotation)
        for tag, model in members:
            sub = f"{key}[i]" if seq else key
            kind = "A list of tables" if seq else (
                "A table" if field.is_required() or value is not None else "An optional table")
            label = f"*{kind}" + (f", this kind: {tag}" if tag else "") + ".* " + _summary(model)
            nested.append((model, sub, tag, label, value if isinstance(value, model) else None))
    yield Table(where=where, tag=tag, note=note or _summary(root), rows=tuple(rows))
    for model, sub, tag, label, value in nested:
        yield from tables(model, sub, label, value, tag)


def render_document(doc: Document) -> str:
    """One document: its title, intro and tables."""
    out = [f"## {doc.title}", "", doc.intro, ""]
    for t in tables(doc.root()):
        title = f"`{t.where}`" + (f" ({t.tag})" if t.tag else "") if t.where else "Top level"
        out += [f"### {title}", "", t.note, "",
                "| key | type | default | valid range | unit | description |",
                "|---|---|---|---|---|---|"]
        out += ["| " + " | ".join(_cell(c) for c in (f"`{r.key}`", r.type, r.default, r.range,
                                                      r.unit, r.description)) + " |"
                for r in t.rows]
        out.append("")
    return "\n".join(out)


def render(documents: tuple[Document, ...] = DOCUMENTS) -> str:
    """The whole reference (markdown)."""
    head = ["# Spec reference", "",
            f"<!-- Generated from the pydantic models by `{COMMAND}`; do not edit. -->", "",
            "Every key of the specs, as the code validates it. A key `a.b` is key `b` of TOML "
            "table `[a]` (or `--set a.b=VALUE`); `key[i]` is an item of a list of tables "
            "(`[[key]]`). Values are in SI units unless the unit column says otherwise; the "
            "valid range is written as an error message states it. A value outside it stops "
            "the command before anything is written, with a message naming the key, the value "
            "and the range.", "",
            "Types are strict: a number is a number (an integer serves where a number is "
            "wanted: TOML writes `20` for `20.0`), never `true` or a string (`load = \"25\"` "
            "and `n_layers = true` are refused); an integer is an integer (`n_layers = 3`, not "
            "`3.0`). `--set KEY=VALUE` reads VALUE as TOML: a number, `true`/`false`, a quoted "
            "string (`\"0.02\"` is a string, refused where a number is wanted), a `[list]`, "
            "an `{inline table}`, or a bare word that is not TOML, which is a string "
            "(`--set mesh.resolution=coarse`); `none` clears an optional key. An inline table "
            "merges key by key into the spec's table: `--set 'mesh={n_layers = 4}'` changes "
            "`mesh.n_layers` and keeps the file's other `[mesh]` keys.", ""]
    return "\n".join(head + [render_document(d) for d in documents]).rstrip() + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m ehlfoam.spec.reference",
        description="Print the spec reference rendered from the pydantic models, or rewrite "
                    "docs/spec.md with it (--write, from the repository root).",
        epilog=f"example: {COMMAND}")
    parser.add_argument("--write", nargs="?", const=str(DEFAULT_PATH), metavar="PATH",
                        help=f"write it to PATH (default {DEFAULT_PATH})")
    args = parser.parse_args(argv)
    text = render()
    if args.write is None:
        sys.stdout.write(text)
        return 0
    path = Path(args.write)
    if not path.parent.is_dir():
        print(f"reference: {path.parent}/ does not exist: run this from the repository root "
              f"or give --write PATH", file=sys.stderr)
        return 2
    path.write_text(text)
    print(f"reference: wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
