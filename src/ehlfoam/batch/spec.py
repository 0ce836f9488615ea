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
                                       # (with it, one speed is allowed: one seeded case)

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
                      ValidationError, ValidationInfo, model_validator)

from ehlfoam._io import read_toml
from ehlfoam.errors import SpecError, format_validation_error

__all__ = ["DEFAULT_MAX_CASES", "BatchSpec", "Confirm", "Ramp", "SpecError", "Sweep", "count_cases",
           "load_batch_spec", "parse_batch_spec"]

#: unknown keys refused, frozen, strict types (no true or "25" for a number); the swept
#: values are validated by the case spec itself, strictly too
_STRICT = ConfigDict(extra="forbid", frozen=True, strict=True)

RANGE_HELP = ("a list [0.005, 0.008] or a range {start = 0.005, stop = 0.025, num = 5} "
              "(or step = 0.005; spacing = \"log\")")
#: Keys of a range table
RANGE_KEYS = ("start", "stop", "num", "step", "spacing")
#: The most cases a batch may ask for unless raised (``ehlfoam batch --max-cases N``,
#: ``BatchOptions(max_cases=N)``): counted from the spec's lists and ranges before any case
#: is made, so that a sweep of 10^6 cases or a range of 10^9 values is refused at once.
DEFAULT_MAX_CASES = 2000


# ------------------------------------------------------------------ values
def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _is_range(value: Any) -> bool:
    return isinstance(value, dict) and bool({"start", "stop"} & set(value))


def _range_length(r: dict[str, Any]) -> int | float:
    """How many values the range {start, stop, num | step, spacing} gives (stop included),
    counted without making them (``math.inf`` where the count overflows); ValueError naming
    what is wrong with the range."""
    unknown = set(r) - set(RANGE_KEYS)
    if unknown:
        raise ValueError(f"unknown range key(s) {', '.join(sorted(unknown))} "
                         f"(valid: start, stop, num or step, spacing)")
    if "start" not in r or "stop" not in r or ("num" in r) == ("step" in r):
        raise ValueError(f"a range needs start, stop and one of num or step ({RANGE_HELP})")
    start, stop = r["start"], r["stop"]
    if not (_number(start) and _number(stop)) or not math.isfinite(stop - start):
        raise ValueError("range start and stop must be finite numbers")
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
        return num
    step = r["step"]
    if not _number(step) or not step > 0 or not math.isfinite(step):
        raise ValueError(f"range step = {step!r}: must be a finite number > 0")
    if spacing == "log":
        raise ValueError("a log range takes num, not step")
    steps = (stop - start) / step
    return int(math.floor(steps + 1e-9)) + 1 if math.isfinite(steps) else math.inf


def _range_values(r: dict[str, Any], max_values: int | None = None) -> list[float]:
    """Expand {start, stop, num | step, spacing} (stop included), counted first: a range of
    more than ``max_values`` values is refused before any is made."""
    n = _range_length(r)
    if max_values is not None and n > max_values:
        raise ValueError(f"the range {_range_text(r)} gives {count_text(n)} values, more than "
                         f"max_cases = {max_values:,} cases in all (raise it with --max-cases)")
    start, stop = r["start"], r["stop"]
    if n == 0:
        return []
    if n == 1:
        return [float(start)]
    if "num" in r:
        if r.get("spacing", "linear") == "log":
            lo, hi = math.log(start), math.log(stop)
            return [math.exp(lo + (hi - lo) * k / (n - 1)) for k in range(n)]
        return [start + (stop - start) * k / (n - 1) for k in range(n)]
    return [start + k * r["step"] for k in range(n)]


def _range_text(r: dict[str, Any]) -> str:
    return "{" + ", ".join(f"{k} = {v!r}" for k, v in r.items()) + "}"


def count_text(n: int | float) -> str:
    """A count for a message: 1,000,000 up to 10^12, then its power of ten."""
    if n == math.inf:
        return "more than 10^308"
    n = int(n)
    return f"{n:,}" if n < 10**12 else f"about 10^{len(str(n)) - 1}"


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


def _max_cases(info: ValidationInfo | None) -> int:
    """The cap on the cases of a batch, from the validation's context (``max_cases``)."""
    context = info.context if info is not None else None
    return (context or {}).get("max_cases", DEFAULT_MAX_CASES)


def _values(raw: Any, info: ValidationInfo | None = None) -> list[Any]:
    """A swept key's values: a list, a range table or a single value; floats rounded. A
    range is counted before it is made (at most the cap on the batch's cases)."""
    if _is_range(raw):
        values = _range_values(raw, _max_cases(info))
    elif isinstance(raw, list):
        values = raw
    else:
        values = [raw]
    if not values:
        raise ValueError(f"empty sweep: give at least one value ({RANGE_HELP})")
    return [rounded(v) if isinstance(v, float) else v for v in values]


def _ramp_speeds(raw: Any, info: ValidationInfo) -> list[float]:
    if raw in ([], {}, None):
        raise ValueError("a ramp without speeds: give its speeds in m/s, increasing, e.g. "
                         "contact.speed = [0.005, 0.008, 0.012]")
    values = _values(raw, info)
    bad = [v for v in values if not _number(v)]
    if bad:
        raise ValueError(f"{bad[0]!r} is not a number ({RANGE_HELP})")
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


# ------------------------------------------------------------------ counting
def _value_count(raw: Any) -> int | float:
    """How many values a swept key's raw value gives, without making them (a range that is
    not valid counts 1: its validation says what is wrong)."""
    if _is_range(raw):
        try:
            return _range_length(raw)
        except (ValueError, TypeError):
            return 1
    return len(raw) if isinstance(raw, list) else 1


_RAMP_OWN = ("name", "branches", "start_from", "fixed", "speeds")


def count_cases(data: Any) -> tuple[int | float, list[str]]:
    """How many cases raw batch spec data asks for, and where they come from, counted from
    its lists and ranges without expanding them: each sweep's product of value counts, each
    ramp's steps (a case met twice counts twice: the plan may be smaller). Parts that are
    not valid count as little as they can; validation reports them."""
    if not isinstance(data, dict):
        return 0, []
    sweeps = data.get("sweep", [])
    sweeps = [sweeps] if isinstance(sweeps, dict) else sweeps
    total: int | float = 0
    parts: list[str] = []
    for k, table in enumerate(sweeps if isinstance(sweeps, list) else []):
        try:
            flat = flatten(table) if isinstance(table, dict) else {}
        except (ValueError, TypeError):
            continue
        counts = {key: _value_count(v) for key, v in flat.items()}
        n = math.prod(counts.values()) if counts else 0
        total += n
        factors = [f"{count_text(c)} {key}" for key, c in counts.items() if c != 1]
        where = f"sweep[{k}]" if len(sweeps) > 1 else "sweep"
        parts.append(f"{where}: " + (" x ".join(factors) if factors else "1")
                     + (f" = {count_text(n)}" if len(factors) > 1 else ""))
    ramps = data.get("ramp", [])
    for r in ramps if isinstance(ramps, list) else []:
        if not isinstance(r, dict):
            continue
        try:
            flat = flatten({k: v for k, v in r.items() if k not in _RAMP_OWN})
        except (ValueError, TypeError):
            flat = {}
        speeds = _value_count(flat.get("contact.speed", r.get("speeds", [])))
        n = speeds if r.get("branches") in ("up", "down") else max(2 * speeds - 1, 0)
        total += n
        parts.append(f"ramp {r.get('name', '?')!s}: {count_text(n)} steps")
    return total, parts


def check_count(data: Any, max_cases: int) -> None:
    """Refuse batch spec data that asks for more than ``max_cases`` cases (counted, not
    expanded), naming the count and where it comes from."""
    n, parts = count_cases(data)
    if n > max_cases:
        raise ValueError(
            f"the batch asks for {count_text(n)} cases ({'; '.join(parts)}), more than "
            f"max_cases = {max_cases:,} (valid: at most max_cases cases, counted before any is "
            f"made): sweep fewer values, or raise the cap with --max-cases N "
            f"(BatchOptions(max_cases=N))")


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

    @model_validator(mode="after")
    def _two_speeds_or_a_start(self) -> "Ramp":
        if len(self.speeds) < 2 and self.start_from is None:   # one step: a seeded case
            raise ValueError(f"contact.speed = {self.speeds}: a ramp needs at least two "
                             f"speeds, e.g. [0.005, 0.008, 0.012], or a start_from (a ramp "
                             f"of one speed is one case started from that run or state)")
        return self

    def steps(self) -> list[tuple[float, str]]:
        """(speed [m/s], "up" | "down") in run order."""
        up = [(v, "up") for v in self.speeds]
        down = [(v, "down") for v in reversed(self.speeds)]
        return {"up": up, "down": down, "up-down": up + down[1:],
                "down-up": down + up[1:]}[self.branches]


class Confirm(BaseModel):
    """3D confirmations of a thin-film map (ehlfoam.batch.confirm): the two points either
    side of each thin-film line's transition run again on a 3D rung, each from the thin-film
    case's state."""

    model_config = _STRICT
    rung: Literal["coarse", "medium", "fine", "resolved-coarse", "resolved-medium",
                  "resolved-fine"] = Field(
        "coarse", description="The 3D rung of the confirmations (docs/ladder.md)",
        json_schema_extra={"unit": ""})
    scene: Literal["interface", "gas-release", "cavitating"] = Field(
        "gas-release", description="The 3D scene: gas-release is the thin-film outlet's "
                                   "counterpart (gas below physics.cavitation_pressure); "
                                   "interface has no gas, so no bubble to break through",
        json_schema_extra={"unit": ""})
    set: dict[str, Any] = Field(
        {"run.transits_max": 3.0},
        description="Case-spec keys (dotted) for the confirmations on top of the thin-film "
                    "case's point (its grid and run limits are left behind)",
        json_schema_extra={"unit": "the case spec's unit of each key",
                           "key": "<case-spec key>"})
    only: dict[str, Any] = Field(
        {}, description="Confirm only the lines whose thin-film cases have these case-spec "
                        "values (dotted keys; default: every line)",
        json_schema_extra={"unit": "the case spec's unit of each key",
                           "key": "<case-spec key>"})


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
    confirm: Confirm | None = Field(None, description="3D confirmations of the thin-film "
                                                      "map's transitions ([confirm] table)",
                                    json_schema_extra={"unit": ""})

    @model_validator(mode="before")
    @classmethod
    def _sweep_table_or_list(cls, data: Any, info: ValidationInfo) -> Any:
        check_count(data, _max_cases(info))    # before any list or range is made
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


def check_max_cases(max_cases: Any) -> int:
    """``max_cases`` as the cap on a batch's cases: an integer >= 1."""
    if isinstance(max_cases, bool) or not isinstance(max_cases, int) or max_cases < 1:
        raise SpecError(f"--max-cases = {max_cases!r}: valid range max_cases >= 1 (an integer;"
                        f" default {DEFAULT_MAX_CASES})")
    return max_cases


def parse_batch_spec(data: dict[str, Any], source: str = "batch spec",
                     max_cases: int = DEFAULT_MAX_CASES) -> BatchSpec:
    """Validate batch spec data; :class:`SpecError` naming the key, value and valid range.
    A batch of more than ``max_cases`` cases is refused, counted before it is expanded
    (:func:`count_cases`)."""
    max_cases = check_max_cases(max_cases)
    rename = _single_sweep if isinstance(data.get("sweep"), dict) else None
    try:
        return BatchSpec.model_validate(data, context={"max_cases": max_cases})
    except ValidationError as err:
        text = format_validation_error(err, BatchSpec, hints=_HINTS, rename=rename)
        raise SpecError(f"invalid {source}: {text}") from None


def load_batch_spec(path: str | Path, max_cases: int = DEFAULT_MAX_CASES) -> BatchSpec:
    """Read and validate a batch spec TOML file (at most ``max_cases`` cases)."""
    spec = parse_batch_spec(read_toml(path), source=f"batch spec {path}", max_cases=max_cases)
    if spec.name is None:
        spec = spec.model_copy(update={"name": Path(path).stem})
    return spec
