"""The batch spec: a base case spec plus sweeps and speed ramps, validated once, expanded to a
plan of cases.

A batch spec is a TOML file under ``runs/`` (``runs/NAME.toml``; ``ehlfoam batch`` writes its
cases under ``runs/NAME/``)::

    name = "regime"                    # label (default: the file's stem)
    description = "..."

    [base]                             # a case spec (generator/case_spec.py), SI units
    mesh = { resolution = "coarse" }
    run = { transits_max = 2.0 }

    [sweep]                            # the cartesian product of the lists below
    speed_mm_s = [5, 8, 12, 17, 25]    # mm/s  (or a range: {start = 5, stop = 25, num = 5})
    temperature_C = [40]               # C
    load_N = [20]                      # N
    supply = [1, 2, 4, "flooded"]      # um of oil on disc and ball each, "flooded", "submerged",
                                       # or {disc_um = 1, ball_um = 2}
    resolution = ["coarse"]            # coarse | medium | fine

    [[sweep]]                          # more [[sweep]] tables: their union (same ids merge)
    ...

    [[ramp]]                           # speed ramp: each step starts from the previous
    name = "A"                         # step's final fields
    speed_mm_s = [5, 8, 12, 17, 25]    # strictly increasing
    branches = "up-down"               # up-down (default), up, down, down-up
    supply = 2                         # single values; default: the base's
    temperature_C = 40
    load_N = 20
    resolution = "coarse"
    start_from = "runs/u8"             # optional: the first step starts from this run
                                       # case's final fields (a converged state), or from
                                       # the oil of a thin-film state (a .npz file)

A dimension not swept takes the base's value. Units: mm/s, um, N and C in this file only;
everything inside is SI. Every expanded case is validated by the case spec itself
(:func:`ehlfoam.spec.case.make_case_spec`), so the valid ranges have one source of truth; an
error names the batch key, its value and the case spec's own message with the valid range.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError, model_validator

from ehlfoam.errors import SpecError, format_validation_error

from ehlfoam._io import read_toml
from ehlfoam.spec.case import CaseSpec, make_case_spec

__all__ = ["BatchSpec", "PlannedCase", "Ramp", "SpecError", "SupplyChoice", "Sweep",
           "est_cpu_s", "expand", "load_batch_spec", "load_plan", "parse_batch_spec"]

_STRICT = ConfigDict(extra="forbid", frozen=True)

#: Keys of a planned case's ``params`` (plan.json, results.csv), in order.
PARAM_KEYS = ("speed_mm_s", "temperature_C", "load_N", "supply", "disc_layer_um",
              "ball_layer_um", "resolution")

#: Rough cost model for ordering (longest first) and the first ETA: CPU seconds per simulated
#: millisecond per resolution level with the time-step defaults of 2026-11-23 (docs/cases.md,
#: "Time-step limits": coarse 0.14-0.17 s at 8 mm/s, medium 0.65-0.84 s; fine scaled from the
#: earlier defaults by the medium level's factor), plus a fixed build cost and the EHL precalc
#: of a new contact.
CPU_PER_SIMULATED_MS = {"coarse": 0.17, "medium": 0.75, "fine": 3.0}
BUILD_CPU_S = 5.0
PRECALC_CPU_S = 60.0

RANGE_HELP = ("a list [5, 8] or a range {start = 5, stop = 25, num = 5} "
              "(or step = 5; spacing = \"log\")")


# ------------------------------------------------------------------ values
#: supplies given by their mode alone (no layer thicknesses)
WHOLE_GAP_SUPPLIES = ("flooded", "submerged")

@dataclass(frozen=True)
class SupplyChoice:
    """One oil supply: ``mode`` "layers" (disc and ball layers [m]), "flooded" or
    "submerged" (ehlfoam.spec.case.Supply)."""

    mode: Literal["layers", "flooded", "submerged"]
    disc_layer: float | None = None
    ball_layer: float | None = None

    @property
    def label(self) -> str:
        """"2um", "1+2um" (disc+ball), "flooded" or "submerged"."""
        if self.mode in WHOLE_GAP_SUPPLIES:
            return self.mode
        d, b = _um(self.disc_layer), _um(self.ball_layer)
        return f"{d}um" if d == b else f"{d}+{b}um"

    def overrides(self) -> dict[str, Any]:
        """Dotted case-spec overrides (SI)."""
        out: dict[str, Any] = {"supply.mode": self.mode}
        if self.mode == "layers":
            out["supply.disc_layer"] = self.disc_layer
            out["supply.ball_layer"] = self.ball_layer
        return out


def _um(metres: float) -> str:
    return f"{metres * 1e6:.6g}"


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _range_values(r: dict[str, Any]) -> list[float]:
    """Expand {start, stop, num | step, spacing} (stop included)."""
    allowed = {"start", "stop", "num", "step", "spacing"}
    unknown = set(r) - allowed
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


def _rounded(v: float) -> float:
    """Drop binary noise from ranges (0.1 + 0.2): 12 significant digits."""
    return float(f"{v:.12g}")


def _numbers(raw: Any) -> list[float]:
    """A sweep of numbers: a list, a range table or a single number."""
    if isinstance(raw, dict):
        values = _range_values(raw)
    elif isinstance(raw, list):
        values = raw
    else:
        values = [raw]
    if not values:
        raise ValueError(f"empty sweep: give at least one value ({RANGE_HELP})")
    bad = [v for v in values if not _number(v)]
    if bad:
        raise ValueError(f"{bad[0]!r} is not a number ({RANGE_HELP})")
    return [_rounded(float(v)) for v in values]


def _supply_item(raw: Any) -> SupplyChoice:
    if raw in WHOLE_GAP_SUPPLIES:
        return SupplyChoice(raw)
    if _number(raw):
        return SupplyChoice("layers", raw * 1e-6, raw * 1e-6)
    if isinstance(raw, dict) and set(raw) <= {"disc_um", "ball_um"} and raw:
        d, b = raw.get("disc_um", 0.0), raw.get("ball_um", 0.0)
        if _number(d) and _number(b):
            return SupplyChoice("layers", d * 1e-6, b * 1e-6)
    raise ValueError(f"supply item {raw!r}: valid are a layer thickness in um on disc and ball "
                     "(a number, e.g. 2), \"flooded\", \"submerged\", or "
                     "{disc_um = 1, ball_um = 2}")


def _supplies(raw: Any) -> list[SupplyChoice]:
    if isinstance(raw, dict) and "start" in raw:
        return [_supply_item(v) for v in _numbers(raw)]
    items = raw if isinstance(raw, list) else [raw]
    if not items:
        raise ValueError("empty sweep: give at least one supply, e.g. [1, 2, \"flooded\"]")
    return [_supply_item(v) for v in items]


def _resolutions(raw: Any) -> list[str]:
    items = raw if isinstance(raw, list) else [raw]
    if not items:
        raise ValueError("empty sweep: give at least one resolution (coarse, medium, fine)")
    return [str(v) if isinstance(v, str) else v for v in items]


Numbers = Annotated[list[float], BeforeValidator(_numbers)]
Supplies = Annotated[list[Any], BeforeValidator(_supplies)]
Resolutions = Annotated[list[Any], BeforeValidator(_resolutions)]


def _one_number(raw: Any) -> float:
    if not _number(raw):
        raise ValueError(f"{raw!r} is not a number (a ramp takes one value here)")
    return float(raw)


def _ramp_speeds(raw: Any) -> list[float]:
    if raw in ([], {}, None):
        raise ValueError("a ramp without speeds: give its speeds in mm/s, increasing, e.g. "
                         "speed_mm_s = [5, 8, 12, 17, 25]")
    values = _numbers(raw)
    if len(values) < 2:
        raise ValueError("a ramp needs at least two speeds, e.g. [5, 8, 12, 17, 25]")
    if any(b <= a for a, b in zip(values, values[1:])):
        raise ValueError("ramp speeds must be strictly increasing (the way down is generated "
                         "by branches = \"up-down\")")
    return values


OneNumber = Annotated[float, BeforeValidator(_one_number)]
OneSupply = Annotated[Any, BeforeValidator(_supply_item)]


# ------------------------------------------------------------------ models
class Sweep(BaseModel):
    """One cartesian product of swept values (units in the key names); unset: the base's."""

    model_config = _STRICT
    speed_mm_s: Numbers | None = None
    temperature_C: Numbers | None = None
    load_N: Numbers | None = None
    supply: Supplies | None = None
    resolution: Resolutions | None = None


class Ramp(BaseModel):
    """A speed ramp: steps at ``speed_mm_s`` (strictly increasing) run one after the other,
    each starting from the previous step's final fields.

    Attributes:
        name: letters and digits, used in the case ids (``rampA_up03_...``).
        speed_mm_s: the speeds [mm/s], increasing.
        branches: "up-down" (up, then back down without repeating the top speed), "up",
            "down" (the speeds from the top) or "down-up".
        temperature_C, load_N, supply, resolution: single values (default: the base's).
        start_from: a run case folder (absolute, or relative to where the batch is started)
            whose final fields the first step starts from: a converged state to step the
            speed up from, instead of the standard start (the puddle); or a thin-film state
            (.npz, ``ehlfoam thin-film``) whose oil it starts from.
    """

    model_config = _STRICT
    name: str = Field(pattern=r"^[A-Za-z0-9]{1,16}$")
    speed_mm_s: Annotated[list[float], BeforeValidator(_ramp_speeds)]
    branches: Literal["up-down", "up", "down", "down-up"] = "up-down"
    start_from: str | None = None
    temperature_C: OneNumber | None = None
    load_N: OneNumber | None = None
    supply: OneSupply | None = None
    resolution: str | None = None

    def steps(self) -> list[tuple[float, str]]:
        """(speed [mm/s], "up" | "down") in run order."""
        up = [(v, "up") for v in self.speed_mm_s]
        down = [(v, "down") for v in reversed(self.speed_mm_s)]
        return {"up": up, "down": down, "up-down": up + down[1:],
                "down-up": down + up[1:]}[self.branches]


class BatchSpec(BaseModel):
    """A batch: ``base`` case spec data, ``sweep`` products and ``ramp`` sequences."""

    model_config = _STRICT
    name: str | None = None
    description: str = ""
    base: dict[str, Any] = {}
    sweep: list[Sweep] = []
    ramp: list[Ramp] = []

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
                             "(e.g. speed_mm_s = [5, 8, 12]) or a [[ramp]]")
        for k, s in enumerate(self.sweep):
            if all(getattr(s, f) is None for f in Sweep.model_fields):
                raise ValueError(f"empty sweep (sweep[{k}] has no values): give e.g. "
                                 f"speed_mm_s = [5, 8, 12] (valid keys: "
                                 f"{', '.join(Sweep.model_fields)})")
        names = [r.name for r in self.ramp]
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise ValueError(f"ramp name = {sorted(dup)[0]!r} is used twice (names must differ)")
        return self


# ------------------------------------------------------------------ errors
_HINTS = {"speed_mm_s": "a ramp needs its speeds, e.g. speed_mm_s = [5, 8, 12, 17, 25]"}


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


# ------------------------------------------------------------------ the plan
@dataclass(frozen=True)
class PlannedCase:
    """One case of the plan: its id, its parameters (batch units), its ramp step (or None)
    and its validated case spec (SI)."""

    id: str
    params: dict[str, Any]
    ramp: dict[str, Any] | None
    spec: CaseSpec = field(compare=False, repr=False)

    def to_json(self) -> dict[str, Any]:
        """The plan.json entry: {"id", "params", "ramp"}."""
        return {"id": self.id, "params": dict(self.params),
                "ramp": dict(self.ramp) if self.ramp else None}

    @property
    def n_procs(self) -> int:
        """MPI ranks (CPU cores) the case's run uses."""
        return self.spec.run.n_procs


def _fmt(v: float, width: int = 0, decimals: int = 0) -> str:
    """A number for an id: zero-padded integer part, at least ``decimals`` decimals, more if
    needed to tell values apart (8.25 -> 08.25)."""
    text = f"{v:.{decimals}f}"
    if float(text) != v:
        text = f"{v:.10f}".rstrip("0")
    if "." in text:
        whole, frac = text.split(".")
        return f"{whole.zfill(width)}.{frac}" if frac else whole.zfill(width)
    return text.zfill(width)


def case_id(params: dict[str, Any]) -> str:
    """A readable id, e.g. ``u08.0_s2um_T40_F20_coarse``."""
    supply = params["supply_label"]
    s = supply if supply in WHOLE_GAP_SUPPLIES else f"s{supply}"
    return (f"u{_fmt(params['speed_mm_s'], 2, 1)}_{s}_T{_fmt(params['temperature_C'])}"
            f"_F{_fmt(params['load_N'])}_{params['resolution']}")


def _params(speed: float, temperature: float, load: float, supply: SupplyChoice,
            resolution: str) -> dict[str, Any]:
    return {"speed_mm_s": speed, "temperature_C": temperature, "load_N": load,
            "supply": supply.mode,
            "disc_layer_um": float(_um(supply.disc_layer)) if supply.mode == "layers" else None,
            "ball_layer_um": float(_um(supply.ball_layer)) if supply.mode == "layers" else None,
            "resolution": resolution, "supply_label": supply.label}


def _overrides(p: dict[str, Any], supply: SupplyChoice) -> dict[str, Any]:
    return {"contact.speed": p["speed_mm_s"] * 1e-3, "contact.temperature": p["temperature_C"],
            "contact.load": p["load_N"], "mesh.resolution": p["resolution"],
            **supply.overrides()}


def _base_supply(base: CaseSpec) -> SupplyChoice:
    s = base.supply
    return SupplyChoice(s.mode, s.disc_layer, s.ball_layer)


def _case_spec(base: dict[str, Any], name: str, overrides: dict[str, Any]) -> CaseSpec:
    return make_case_spec({**base, "name": name}, **overrides)


def _check_values(batch: BatchSpec, base: CaseSpec) -> None:
    """Each swept value alone on the base, so that an error names the batch key and value."""
    checks = []
    for k, sw in enumerate(batch.sweep):
        where = f"sweep[{k}]" if len(batch.sweep) > 1 else "sweep"
        checks += [(f"{where}.speed_mm_s = {v:g} mm/s", {"contact.speed": v * 1e-3})
                   for v in sw.speed_mm_s or []]
        checks += [(f"{where}.temperature_C = {v:g} C", {"contact.temperature": v})
                   for v in sw.temperature_C or []]
        checks += [(f"{where}.load_N = {v:g} N", {"contact.load": v}) for v in sw.load_N or []]
        checks += [(f"{where}.supply = {s.label!r}", s.overrides()) for s in sw.supply or []]
        checks += [(f"{where}.resolution = {r!r}", {"mesh.resolution": r})
                   for r in sw.resolution or []]
    for r in batch.ramp:
        where = f"ramp {r.name!r}"
        checks += [(f"{where} speed_mm_s = {v:g} mm/s", {"contact.speed": v * 1e-3})
                   for v in r.speed_mm_s]
        for key, dotted in (("temperature_C", "contact.temperature"), ("load_N", "contact.load"),
                            ("resolution", "mesh.resolution")):
            if getattr(r, key) is not None:
                checks.append((f"{where} {key} = {getattr(r, key)!r}",
                               {dotted: getattr(r, key)}))
        if r.supply is not None:
            checks.append((f"{where} supply = {r.supply.label!r}", r.supply.overrides()))
    for r in (r for r in batch.ramp if r.start_from):
        from ehlfoam.seed.start import RampError, check_start

        try:
            check_start(r.start_from)
        except (RampError, OSError):
            raise SpecError(f"invalid batch spec: ramp {r.name!r} start_from = "
                            f"{r.start_from!r}: not a case folder with a written time "
                            f"(give a case that has run) nor a thin-film state (.npz)") from None
    for where, overrides in checks:
        try:
            _case_spec(batch.base, "check", overrides)
        except SpecError as err:
            raise SpecError(f"invalid batch spec: {where} gives an invalid case: "
                            f"{str(err).removeprefix('invalid case spec: ')}") from None


def expand(batch: BatchSpec) -> list[PlannedCase]:
    """The plan: sweep cases (union of the products, first occurrence kept), then the ramps'
    steps in run order. Every case spec is validated; raises :class:`SpecError` before
    anything is built."""
    try:
        base = make_case_spec(batch.base)
    except SpecError as err:
        raise SpecError(f"invalid batch spec: base: {err}") from None
    _check_values(batch, base)
    b = base.contact
    plan: dict[str, PlannedCase] = {}
    for sw in batch.sweep:
        for u in sw.speed_mm_s or [_rounded(b.speed * 1e3)]:
            for T in sw.temperature_C or [b.temperature]:
                for F in sw.load_N or [b.load]:
                    for s in sw.supply or [_base_supply(base)]:
                        for res in sw.resolution or [base.mesh.resolution]:
                            _add(plan, batch, _params(u, T, F, s, res), s, None)
    for r in batch.ramp:
        s = r.supply or _base_supply(base)
        T = r.temperature_C if r.temperature_C is not None else b.temperature
        F = r.load_N if r.load_N is not None else b.load
        res = r.resolution or base.mesh.resolution
        previous = None
        for step, (u, direction) in enumerate(r.steps(), start=1):
            p = _params(u, T, F, s, res)
            ramp = {"name": r.name, "step": step, "direction": direction, "previous": previous}
            if step == 1 and r.start_from:
                ramp["start_from"] = str(Path(r.start_from).absolute())
            previous = _add(plan, batch, p, s, ramp)
    for pc in plan.values():
        if pc.spec.mesh.follow is not None and not (
                pc.ramp and (pc.ramp.get("previous") or pc.ramp.get("start_from"))):
            raise SpecError(f"invalid batch spec: case {pc.id} has mesh.follow but no state to "
                            f"start from, whose meniscus its mesh would follow: only a ramp's "
                            f"steps have one (its start_from, or the step before)")
    return list(plan.values())


def _add(plan: dict[str, PlannedCase], batch: BatchSpec, p: dict[str, Any],
         supply: SupplyChoice, ramp: dict[str, Any] | None) -> str:
    cid = case_id(p)
    if ramp:
        cid = f"ramp{ramp['name']}_{ramp['direction']}{ramp['step']:02d}_{cid}"
    if cid in plan:
        return cid
    try:
        spec = _case_spec(batch.base, cid, _overrides(p, supply))
    except SpecError as err:
        raise SpecError(f"invalid batch spec: case {cid} is invalid: "
                        f"{str(err).removeprefix('invalid case spec: ')}") from None
    params = {k: p[k] for k in PARAM_KEYS}
    plan[cid] = PlannedCase(cid, params, ramp, spec)
    return cid


def load_plan(path: str | Path) -> tuple[BatchSpec, list[PlannedCase]]:
    """Read, validate and expand a batch spec file."""
    batch = load_batch_spec(path)
    return batch, expand(batch)


def est_cpu_s(spec: CaseSpec) -> float:
    """A rough CPU cost [s] of building and running a case (for ordering and the first ETA):
    the level's CPU per simulated ms times the simulated time, plus the build."""
    per_ms = CPU_PER_SIMULATED_MS.get(spec.mesh.resolution, 1.0)
    return BUILD_CPU_S + per_ms * spec.end_time * 1e3
