"""The batch spec: a base case spec plus sweeps and speed ramps over the case spec's own keys.

A batch spec is a TOML file (``ehlfoam batch NAME.toml`` writes its cases under
``runs/NAME/``). Its keys are the case spec's, dotted, in its SI units::

    name = "regime"                    # label (default: the file's stem)
    description = "..."

    [base]                             # a case spec (ehlfoam.spec.case), SI units
    mesh = { resolution = "coarse" }
    run = { transits_max = 2.0 }

    [sweep]                            # the cartesian product of the lists below
    contact.speed = [0.005, 0.008, 0.012]           # m/s (or a range:
                                                    #   {start = 0.005, stop = 0.025, num = 5})
    contact.temperature = [40]                      # C
    supply = [{disc_layer = 1e-6, ball_layer = 1e-6}, {mode = "flooded"}]
    mesh.resolution = ["coarse"]

    [[sweep]]                          # more [[sweep]] tables: their union (same ids merge)
    ...

    [[ramp]]                           # speed ramp: each step starts from the previous
    name = "A"                         # step's final fields
    contact.speed = [0.005, 0.008, 0.012, 0.017, 0.025]   # m/s, strictly increasing
    branches = "up-down"               # up-down (default), up, down, down-up
    supply = { disc_layer = 1.5e-6, ball_layer = 1.5e-6 } # other keys: single values
    start_from = "runs/u8"             # optional: the first step starts from this run
                                       # case's final fields (a converged state), or from
                                       # the oil of a thin-film state (a .npz file)

Any case-spec key may be swept: a list of values, a range of numbers ``{start, stop, num
| step, spacing = "linear" | "log"}`` (stop included) or a single value; a table value (a
supply table) sets its keys on the base's table. ``contact.speed = [...]`` and
``"contact.speed" = [...]`` are the same key. Setting a supply layer (``supply.disc_layer``,
``supply.ball_layer``) without ``supply.mode`` means ``mode = "layers"``. The first key of a
sweep varies slowest. A key not swept takes the base's value.

Every expanded case is validated by the case spec itself
(:func:`ehlfoam.spec.case.make_case_spec`), so the valid ranges have one source of truth; an
error names the sweep or ramp, the key, its value and the case spec's valid range.
:mod:`ehlfoam.batch.plan` expands a batch spec into its cases.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import (BaseModel, BeforeValidator, ConfigDict, Field, RootModel,
                      ValidationError, model_validator)

from ehlfoam._io import read_toml
from ehlfoam.errors import SpecError, format_validation_error

__all__ = ["BatchSpec", "Ramp", "SpecError", "Sweep", "load_batch_spec", "parse_batch_spec"]

#: unknown keys refused, frozen, strict types (no true or "25" for a number); the swept
#: values are validated by the case spec itself, strictly too
_STRICT = ConfigDict(extra="forbid", frozen=True, strict=True)

RANGE_HELP = ("a list [0.005, 0.008] or a range {start = 0.005, stop = 0.025, num = 5} "
              "(or step = 0.005; spacing = \"log\")")
#: Keys of a range table
RANGE_KEYS = ("start", "stop", "num", "step", "spacing")


# ------------------------------------------------------------------ values
def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _is_range(value: Any) -> bool:
    return isinstance(value, dict) and bool({"start", "stop"} & set(value))


def _range_values(r: dict[str, Any]) -> list[float]:
    """Expand {start, stop, num | step, spacing} (stop included)."""
    unknown = set(r) - set(RANGE_KEYS)
    if unknown:
        raise ValueError(f"unknown range key(s) {', '.join(sorted(unknown))} "
                         f"(valid: start, stop, num or step, spacing)")
    if "start" not in r or "stop" not in r or ("num" in r) == ("step" in r):
        raise ValueError(f"a range needs start, stop and one of num or step ({RANGE_HELP})")
    start, stop = r["start"], r["stop"]
    if not (_number(start) and _number(stop)):
        raise ValueError("range start and stop must be numbers")
    spacing = r.get("spacing", "linear")
    if spacing not in ("linear", "log"):
        raise ValueError(f"range spacing = {spacing!r}: valid are 'linear' and 'log'")
    if stop < start:
        raise ValueError(f"range stop = {stop:g} is below start = {start:g}")
    if spacing == "log" and start <= 0:
        raise ValueError(f"a log range needs start > 0 (start = {start:g})")
    if "num" in r:
        num = r["num"]
        if not isinstance(num, int) or isinstance(num, bool) or num < 0:
            raise ValueError(f"range num = {num!r}: must be an integer >= 1")
        if num == 0:
            return []
        if num == 1:
            return [float(start)]
        if spacing == "log":
            lo, hi = math.log(start), math.log(stop)
            return [math.exp(lo + (hi - lo) * k / (num - 1)) for k in range(num)]
        return [start + (stop - start) * k / (num - 1) for k in range(num)]
    step = r["step"]
    if not _number(step) or step <= 0:
        raise ValueError(f"range step = {step!r}: must be a number > 0")
    if spacing == "log":
        raise ValueError("a log range takes num, not step")
    n = int(math.floor((stop - start) / step + 1e-9)) + 1
    return [start + k * step for k in range(n)]


def rounded(v: float) -> float:
    """Drop binary noise from ranges and unit conversions (0.1 + 0.2): 12 significant
    digits."""
    return float(f"{v:.12g}")


def flatten(table: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """A (nested) table as dotted keys: ``{"contact": {"speed": v}}`` and
    ``{"contact.speed": v}`` both give ``{"contact.speed": v}``; a range table is a value."""
    out: dict[str, Any] = {}
    for key, value in table.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict) and value and not _is_range(value):
            parts = flatten(value, f"{name}.")
        else:
            parts = {name: value}
        for dotted, v in parts.items():
            if dotted in out:
                raise ValueError(f"{dotted} is given twice")
            out[dotted] = v
    return out


def _values(raw: Any) -> list[Any]:
    """A swept key's values: a list, a range table or a single value; floats rounded."""
    if _is_range(raw):
        values = _range_values(raw)
    elif isinstance(raw, list):
        values = raw
    else:
        values = [raw]
    if not values:
        raise ValueError(f"empty sweep: give at least one value ({RANGE_HELP})")
    return [rounded(v) if isinstance(v, float) else v for v in values]


def _ramp_speeds(raw: Any) -> list[float]:
    if raw in ([], {}, None):
        raise ValueError("a ramp without speeds: give its speeds in m/s, increasing, e.g. "
                         "contact.speed = [0.005, 0.008, 0.012]")
    values = _values(raw)
    bad = [v for v in values if not _number(v)]
    if bad:
        raise ValueError(f"{bad[0]!r} is not a number ({RANGE_HELP})")
    if len(values) < 2:
        raise ValueError("a ramp needs at least two speeds, e.g. [0.005, 0.008, 0.012]")
    if any(b <= a for a, b in zip(values, values[1:])):
        raise ValueError("ramp speeds must be strictly increasing (the way down is generated "
                         "by branches = \"up-down\")")
    return [float(v) for v in values]


def overrides(key: str, value: Any) -> dict[str, Any]:
    """The dotted case-spec overrides of one value of ``key``: a table value sets its keys
    (``supply = {disc_layer = 1e-6}`` -> ``supply.disc_layer``)."""
    if isinstance(value, dict) and not _is_range(value):
        return flatten(value, f"{key}.")
    return {key: value}


#: The batch spec's keys before it took the case spec's: old key -> what to write now.
RENAMED = {"speed_mm_s": "contact.speed in m/s (e.g. [0.005, 0.008])",
           "temperature_C": "contact.temperature", "load_N": "contact.load",
           "resolution": "mesh.resolution"}
_SUPPLY_HELP = ("supply takes supply tables: [{disc_layer = 1e-6, ball_layer = 1e-6}, "
                "{mode = \"flooded\"}] (layers in m)")


def _case_keys(table: dict[str, Any]) -> dict[str, Any]:
    """A table of case-spec keys, dotted; the case name is not one of them (it is the id),
    and a key of the batch spec's old names says what it is now."""
    flat = flatten(table)
    if "name" in flat:
        raise ValueError("name: the case name is the case id, it cannot be set here")
    for key, value in flat.items():
        if key in RENAMED:
            raise ValueError(f"{key} = {value!r}: the batch spec takes the case spec's keys in "
                             f"SI: give {RENAMED[key]}")
        items = value if isinstance(value, list) else [value]
        if key == "supply" and any(not isinstance(v, dict) for v in items):
            raise ValueError(f"supply = {value!r}: {_SUPPLY_HELP}")
    return flat


# ------------------------------------------------------------------ models
Values = Annotated[list[Any], BeforeValidator(_values)]


class Sweep(RootModel[dict[str, Values]]):
    """One cartesian product: dotted case-spec keys and their values."""

    root: dict[str, Values] = Field(
        description="Case-spec keys (dotted, e.g. contact.speed) and the values to sweep: a "
                    "list, a range {start, stop, num | step, spacing} or a single value; a "
                    "table sets its keys (supply = [{disc_layer = 1e-6, ball_layer = 1e-6}, "
                    "{mode = \"flooded\"}])",
        json_schema_extra={"unit": "the case spec's unit of each key",
                           "key": "<case-spec key>"})

    @model_validator(mode="before")
    @classmethod
    def _dotted(cls, data: Any) -> Any:
        return _case_keys(data) if isinstance(data, dict) else data


class Ramp(BaseModel):
    """A speed ramp: steps at ``contact.speed`` (strictly increasing) run one after the
    other, each starting from the previous step's final fields; other case-spec keys at
    single values."""

    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=True, strict=True)
    name: str = Field(pattern=r"^[A-Za-z0-9]{1,16}$",
                      description="Letters and digits, used in the case ids (rampA_up03_...)",
                      json_schema_extra={"unit": ""})
    speeds: Annotated[list[float], BeforeValidator(_ramp_speeds)] = Field(
        alias="contact.speed", description="The ramp's rolling speeds, strictly increasing",
        json_schema_extra={"unit": "m/s"})
    branches: Literal["up-down", "up", "down", "down-up"] = Field(
        "up-down", description="up-down (up, then back down without repeating the top "
                               "speed), up, down (the speeds from the top) or down-up",
        json_schema_extra={"unit": ""})
    start_from: str | None = Field(
        None, description="A run case folder (absolute, or relative to where the batch is "
                          "started) whose final fields the first step starts from, or a "
                          "thin-film state (.npz) whose oil it starts from",
        json_schema_extra={"unit": ""})
    fixed: dict[str, Any] = Field(
        {}, description="Other case-spec keys (dotted) at single values for every step "
                        "(default: the base's)",
        json_schema_extra={"unit": "the case spec's unit of each key",
                           "key": "<case-spec key>"})

    @model_validator(mode="before")
    @classmethod
    def _dotted(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            return data
        own = {"name", "branches", "start_from", "fixed", "speeds"}
        flat = _case_keys({k: v for k, v in data.items() if k not in own})
        fixed = {k: v for k, v in flat.items() if k != "contact.speed"}
        out = {k: v for k, v in data.items() if k in own}
        if "contact.speed" in flat:
            out["contact.speed"] = flat["contact.speed"]
        return {**out, "fixed": {**out.get("fixed", {}), **fixed}}

    def steps(self) -> list[tuple[float, str]]:
        """(speed [m/s], "up" | "down") in run order."""
        up = [(v, "up") for v in self.speeds]
        down = [(v, "down") for v in reversed(self.speeds)]
        return {"up": up, "down": down, "up-down": up + down[1:],
                "down-up": down + up[1:]}[self.branches]


class BatchSpec(BaseModel):
    """A batch: ``base`` case spec data, ``sweep`` products and ``ramp`` sequences."""

    model_config = _STRICT
    name: str | None = Field(None, description="The batch's label (default: the file's stem)",
                             json_schema_extra={"unit": ""})
    description: str = Field("", description="What the batch is for",
                             json_schema_extra={"unit": ""})
    base: dict[str, Any] = Field({}, description="The case spec every case starts from",
                                 json_schema_extra={"unit": "the case spec's units (SI)"})
    sweep: list[Sweep] = Field([], description="Cartesian products of case-spec values (one "
                                               "[sweep] table or several [[sweep]] tables: "
                                               "their union)",
                               json_schema_extra={"unit": "the case spec's units (SI)"})
    ramp: list[Ramp] = Field([], description="Speed ramps ([[ramp]] tables)",
                             json_schema_extra={"unit": "m/s"})

    @model_validator(mode="before")
    @classmethod
    def _sweep_table_or_list(cls, data: Any) -> Any:
        if isinstance(data, dict) and isinstance(data.get("sweep"), dict):
            data = {**data, "sweep": [data["sweep"]]}
        return data

    @model_validator(mode="after")
    def _has_cases(self) -> "BatchSpec":
        if not self.sweep and not self.ramp:
            raise ValueError("the batch has no cases: give a [sweep] table "
                             "(e.g. contact.speed = [0.005, 0.008, 0.012]) or a [[ramp]]")
        for k, s in enumerate(self.sweep):
            if not s.root:
                raise ValueError(f"empty sweep (sweep[{k}] has no values): give e.g. "
                                 f"contact.speed = [0.005, 0.008, 0.012] (any case-spec key)")
        names = [r.name for r in self.ramp]
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise ValueError(f"ramp name = {sorted(dup)[0]!r} is used twice (names must differ)")
        return self


# ------------------------------------------------------------------ reading
_HINTS = {"contact.speed": "a ramp needs its speeds, e.g. contact.speed = [0.005, 0.008, 0.012]"}


def _single_sweep(loc: tuple) -> tuple:
    """A single ``[sweep]`` table is held as a list of one: name it as the user wrote it."""
    return loc[:1] + loc[2:] if loc[:2] == ("sweep", 0) else loc


def parse_batch_spec(data: dict[str, Any], source: str = "batch spec") -> BatchSpec:
    """Validate batch spec data; :class:`SpecError` naming the key, value and valid range."""
    rename = _single_sweep if isinstance(data.get("sweep"), dict) else None
    try:
        return BatchSpec(**data)
    except ValidationError as err:
        text = format_validation_error(err, BatchSpec, hints=_HINTS, rename=rename)
        raise SpecError(f"invalid {source}: {text}") from None


def load_batch_spec(path: str | Path) -> BatchSpec:
    """Read and validate a batch spec TOML file."""
    spec = parse_batch_spec(read_toml(path), source=f"batch spec {path}")
    if spec.name is None:
        spec = spec.model_copy(update={"name": Path(path).stem})
    return spec
