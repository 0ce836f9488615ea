"""The plan of a batch: its batch spec expanded into cases, each with a readable id, its
parameters and its validated case spec.

A case's parameters (plan.json, the columns of results.csv) are the case spec's dotted keys
in SI (:data:`PARAM_KEYS`, then any other key the batch sweeps). Its id names them for a
reader, e.g. ``u08.0_s2um_T40_F20_coarse`` (speed in mm/s, the supply's layers in um, "flooded"
or "submerged", temperature in C, load in N, resolution; then ``_<key><value>`` for each other
swept key); a ramp step's id adds ``rampA_up03_``. The id is a name, not a quantity.
"""

from __future__ import annotations

import itertools
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ehlfoam.batch.spec import (DEFAULT_MAX_CASES, BatchSpec, check_max_cases, count_text,
                                load_batch_spec, overrides, rounded)
from ehlfoam.case.bounds import check_work
from ehlfoam.errors import SpecError
from ehlfoam.spec.case import CaseSpec, make_case_spec
from ehlfoam.spec.thin_film import thin_film_cpu_s
from ehlfoam.spec.ladder import rung_family

__all__ = ["PARAM_KEYS", "PlannedCase", "case_count", "case_id", "est_cpu_s", "expand",
           "load_plan"]

#: The parameters every planned case carries (plan.json, results.csv), in order: the case
#: spec's keys that name a case (SI; a layer is None unless the supply mode is "layers" or
#: "rig"). The rung of the model ladder names the family (scene) and level together.
PARAM_KEYS = ("contact.speed", "contact.temperature", "contact.load", "supply.mode",
              "supply.disc_layer", "supply.ball_layer", "mesh.resolution", "scene", "rung")
#: How a case id ends for each family of rungs (the level follows)
_RUNG_TAGS = {"thin-film": "tf-", "resolved": "res-", "3d": ""}
#: supplies given by their mode alone (no layer thicknesses)
WHOLE_GAP_SUPPLIES = ("flooded", "submerged")
_LAYERS = ("supply.disc_layer", "supply.ball_layer")

#: Rough cost model for ordering (longest first) and the first ETA: CPU seconds per simulated
#: millisecond per resolution level, measured with the time-step defaults of 2026-11-23 (fine
#: scaled from the earlier defaults by the medium level's factor), plus a fixed build cost and
#: the EHL precalc of a new contact (docs/batches.md#cost-model; 18 points over 5-30 N,
#: 25-60 C, 2-100 mm/s took 226 CPU s in all on one thread, 6-47 s each).
CPU_PER_SIMULATED_MS = {"coarse": 0.17, "medium": 0.75, "fine": 3.0}
BUILD_CPU_S = 5.0
PRECALC_CPU_S = 15.0


@dataclass(frozen=True)
class PlannedCase:
    """One case of the plan: its id, its parameters (dotted case-spec keys, SI), its ramp
    step (or None) and its validated case spec."""

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


def value_of(spec: CaseSpec, dotted: str) -> Any:
    """The value of a dotted key in a case spec (None for a layer of a supply that is not
    "layers" or "rig")."""
    if dotted in _LAYERS and spec.supply.mode not in ("layers", "rig"):
        return None
    node: Any = spec
    for part in dotted.split("."):
        node = node.get(part) if isinstance(node, dict) else getattr(node, part, None)
    return node


def _fmt(v: float, width: int = 0, decimals: int = 0) -> str:
    """A number for an id: zero-padded integer part, at least ``decimals`` decimals, more if
    needed to tell values apart, up to four significant digits (8.25 -> 08.25; a log
    range's 2.8541829945 -> 02.854)."""
    text = f"{v:.{decimals}f}"
    if float(text) != v:
        magnitude = math.floor(math.log10(abs(v))) + 1 if v else 1
        text = f"{v:.{max(decimals, 4 - magnitude, 0)}f}"
        text = text.rstrip("0").rstrip(".") if "." in text else text
    if "." in text:
        whole, frac = text.split(".")
        return f"{whole.zfill(width)}.{frac}" if frac else whole.zfill(width)
    return text.zfill(width)


def _um(metres: float) -> str:
    return f"{metres * 1e6:.6g}"


def supply_label(mode: str, disc_layer: float | None, ball_layer: float | None) -> str:
    """"2um", "1+2um" (disc+ball), "flooded" or "submerged"; "2um-rig" for the oil on the
    rig (the tracks' mean layers at the start)."""
    if mode in WHOLE_GAP_SUPPLIES:
        return mode
    d, b = _um(disc_layer), _um(ball_layer)
    return (f"{d}um" if d == b else f"{d}+{b}um") + ("-rig" if mode == "rig" else "")


def _id_value(value: Any) -> str:
    text = f"{value:g}" if isinstance(value, float) else str(value)
    return re.sub(r"[^A-Za-z0-9.+-]", "", text)


def case_id(spec: CaseSpec, extra_keys: tuple[str, ...] = ()) -> str:
    """A readable id, e.g. ``u08.0_s2um_T40_F20_coarse`` (``..._tf-medium`` on a thin-film
    rung, ``..._res-medium`` on a resolved one), with ``_<leaf><value>`` for each of
    ``extra_keys`` (other swept keys)."""
    s = spec.supply
    supply = supply_label(s.mode, s.disc_layer, s.ball_layer)
    c = spec.contact
    text = (f"u{_fmt(rounded(c.speed * 1e3), 2, 1)}_"
            f"{supply if supply in WHOLE_GAP_SUPPLIES else f's{supply}'}_"
            f"T{_fmt(c.temperature)}_F{_fmt(c.load)}_"
            f"{_RUNG_TAGS[rung_family(spec.rung)]}{spec.mesh.resolution}")
    return text + "".join(f"_{k.rsplit('.', 1)[-1]}{_id_value(value_of(spec, k))}"
                          for k in extra_keys)


def _with_mode(values: dict[str, Any], base: dict[str, Any] | None = None) -> dict[str, Any]:
    """Setting a layer without the supply mode means the layers mode, unless the base's
    supply is the oil on the rig (its layers are the tracks' at the start)."""
    supply = (base or {}).get("supply")
    if isinstance(supply, dict) and supply.get("mode") == "rig":
        return values
    if any(k in values for k in _LAYERS) and "supply.mode" not in values:
        return {"supply.mode": "layers", **values}
    return values


def _case_spec(base: dict[str, Any], values: dict[str, Any]) -> CaseSpec:
    return make_case_spec({**base, "name": "case"}, **_with_mode(values, base))


def _invalid(where: str, err: SpecError) -> SpecError:
    return SpecError(f"invalid batch spec: {where}: "
                     f"{str(err).removeprefix('invalid case spec: ')}")


def _check_values(batch: BatchSpec) -> None:
    """Each swept value alone on the base, so that an error names where it is given, its
    key and value."""
    checks: list[tuple[str, dict[str, Any]]] = []
    for k, sw in enumerate(batch.sweep):
        where = f"sweep[{k}]" if len(batch.sweep) > 1 else "sweep"
        for key, values in sw.root.items():
            for i, value in enumerate(values):
                table = isinstance(value, dict)
                checks.append((f"{where}.{key}[{i}]" if table else where,
                               overrides(key, value)))
    for r in batch.ramp:
        where = f"ramp {r.name!r}"
        checks += [(where, {"contact.speed": v}) for v in r.speeds]
        if r.fixed:
            checks.append((where, r.fixed))
    for r in (r for r in batch.ramp if r.start_from):
        from ehlfoam.seed.start import RampError, check_start

        try:
            check_start(r.start_from)
        except (RampError, OSError):
            raise SpecError(f"invalid batch spec: ramp {r.name!r} start_from = "
                            f"{r.start_from!r}: not a case folder with a written time "
                            f"(give a case that has run) nor a thin-film state (.npz)") from None
    for where, values in checks:
        try:
            _case_spec(batch.base, values)
        except SpecError as err:
            raise _invalid(where, err) from None


def _swept_keys(batch: BatchSpec) -> tuple[str, ...]:
    """The dotted keys the batch sets beyond the base (sweeps, ramps), first seen first."""
    keys: dict[str, None] = {}
    for sw in batch.sweep:
        for key, values in sw.root.items():
            for value in values:
                keys.update(dict.fromkeys(_with_mode(overrides(key, value), batch.base)))
    for r in batch.ramp:
        keys.update(dict.fromkeys(_with_mode(r.fixed, batch.base)))
    return tuple(keys)


def case_count(batch: BatchSpec) -> int:
    """How many cases ``batch`` asks for, from its value lists (not expanded): each sweep's
    product, each ramp's steps (a case met twice counts twice)."""
    return (sum(math.prod(len(v) for v in sw.root.values()) for sw in batch.sweep)
            + sum(len(r.steps()) for r in batch.ramp))


def _check_work(plan: dict[str, PlannedCase]) -> None:
    """Each case within its mesh.max_cells and run.max_steps, estimated from its spec (cases
    of the same mesh and time step estimated once)."""
    seen: dict[str, str] = {}
    for pc in plan.values():
        key = pc.spec.model_dump_json(include={"contact", "mesh", "domain", "run", "physics",
                                               "scene", "thin_film"})
        if key in seen:
            continue
        try:
            check_work(pc.spec)
        except SpecError as err:
            raise _invalid(f"case {pc.id}", err) from None
        seen[key] = pc.id


def expand(batch: BatchSpec, max_cases: int = DEFAULT_MAX_CASES) -> list[PlannedCase]:
    """The plan: sweep cases (union of the products, first occurrence kept), then the ramps'
    steps in run order. Every case spec is validated; raises :class:`SpecError` before
    anything is built: a batch of more than ``max_cases`` cases (counted first), a case spec
    that is not valid, a case above its mesh.max_cells or run.max_steps."""
    n = case_count(batch)
    if n > check_max_cases(max_cases):
        raise SpecError(f"invalid batch spec: the batch asks for {count_text(n)} cases, more "
                        f"than max_cases = {max_cases:,}: sweep fewer values, or raise the cap "
                        f"with --max-cases N (BatchOptions(max_cases=N))")
    try:
        make_case_spec(batch.base)
    except SpecError as err:
        raise SpecError(f"invalid batch spec: base: {err}") from None
    _check_values(batch)
    extra = tuple(k for k in _swept_keys(batch) if k not in PARAM_KEYS)
    plan: dict[str, PlannedCase] = {}
    for sw in batch.sweep:
        columns = [[overrides(key, v) for v in values] for key, values in sw.root.items()]
        for combination in itertools.product(*columns):
            values = {k: v for part in combination for k, v in part.items()}
            _add(plan, batch, values, None, extra)
    for r in batch.ramp:
        previous = None
        for step, (u, direction) in enumerate(r.steps(), start=1):
            ramp = {"name": r.name, "step": step, "direction": direction, "previous": previous}
            if step == 1 and r.start_from:
                ramp["start_from"] = str(Path(r.start_from).absolute())
            previous = _add(plan, batch, {**r.fixed, "contact.speed": u}, ramp, extra)
    for pc in plan.values():
        if pc.spec.mesh.follow is not None and pc.spec.run.start != "thin-film" and not (
                pc.ramp and (pc.ramp.get("previous") or pc.ramp.get("start_from"))):
            raise SpecError(f"invalid batch spec: case {pc.id} has mesh.follow but no state to "
                            f"start from, whose meniscus its mesh would follow: a ramp's steps "
                            f"have one (its start_from, or the step before), or set run.start "
                            f"= \"thin-film\" (its point's thin-film balance)")
    _check_work(plan)
    return list(plan.values())


def _add(plan: dict[str, PlannedCase], batch: BatchSpec, values: dict[str, Any],
         ramp: dict[str, Any] | None, extra: tuple[str, ...]) -> str:
    try:
        spec = _case_spec(batch.base, values)
    except SpecError as err:
        where = ", ".join(f"{k} = {v!r}" for k, v in values.items())
        raise _invalid(f"the case {where}", err) from None
    cid = case_id(spec, extra)
    if ramp:
        cid = f"ramp{ramp['name']}_{ramp['direction']}{ramp['step']:02d}_{cid}"
    if cid in plan:
        if plan[cid].spec.model_dump(exclude={"name"}) != spec.model_dump(exclude={"name"}):
            raise SpecError(f"invalid batch spec: two different cases get the id {cid}: "
                            f"sweep the keys that tell them apart in one batch")
        return cid
    params = {k: value_of(spec, k) for k in PARAM_KEYS + extra}
    plan[cid] = PlannedCase(cid, params, ramp, spec.model_copy(update={"name": cid}))
    return cid


def load_plan(path: str | Path,
              max_cases: int = DEFAULT_MAX_CASES) -> tuple[BatchSpec, list[PlannedCase]]:
    """Read, validate and expand a batch spec file of at most ``max_cases`` cases (counted
    before they are expanded)."""
    batch = load_batch_spec(path, max_cases=max_cases)
    return batch, expand(batch, max_cases=max_cases)


def est_cpu_s(spec: CaseSpec) -> float:
    """A rough CPU cost [s] of building and running a case (for ordering and the first ETA):
    the level's CPU per simulated ms times the simulated time, plus the build; a thin-film
    case's from its cells and steps (:func:`ehlfoam.spec.thin_film.thin_film_cpu_s`)."""
    if spec.scene == "thin-film":
        return thin_film_cpu_s(spec)
    per_ms = CPU_PER_SIMULATED_MS.get(spec.mesh.resolution, 1.0)
    return BUILD_CPU_S + per_ms * spec.end_time * 1e3
