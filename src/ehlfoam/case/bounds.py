"""Bounds on the work a case asks for, checked before any of it starts.

- **Cores**: ``run.n_procs`` MPI ranks within the cores this process may use
  (:func:`usable_cores`, ``os.sched_getaffinity``), unless the caller oversubscribes on
  purpose (``--oversubscribe``): 1024 ranks on 2 cores only thrash (and decomposePar writes
  1024 folders first).
- **Limits**: a wall-clock limit or an extension is a positive, finite number
  (:func:`check_limit`); NaN is not "no limit".
- **Cells and time steps**: a spec's mesh and time span are estimated from the spec alone,
  before the EHL precalc and the mesher run (:func:`estimate_cells`, :func:`estimate_steps`),
  and a case above ``mesh.max_cells`` or ``run.max_steps`` is refused with the estimate and
  the key to change (:func:`check_work`).

Every refusal is a :class:`~ehlfoam.errors.SpecError` naming the key, its value and what is
valid.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

from ehlfoam.case.timestep import capillary_time_step, write_interval
from ehlfoam.errors import SpecError
from ehlfoam.mesh.base import estimate_quads
from ehlfoam.mesh.sizing import mesh_params, size_function, smallest_cell_size
from ehlfoam.spec.case import CaseSpec
from ehlfoam.spec.sections import Run

__all__ = ["LIMIT_KEYS", "WALL_LIMIT_MAX", "WorkEstimate", "check_extension", "check_limit",
           "check_n_procs", "check_wall_limit", "check_work", "estimate_cells",
           "estimate_steps", "estimate_work", "usable_cores"]

#: The spec keys that bound the work of a case without changing its result (a finished case
#: built under another bound is still the same case).
LIMIT_KEYS = ("mesh.max_cells", "run.max_steps")


def usable_cores() -> int:
    """CPU cores this process may use (its affinity mask; all of the machine's otherwise)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def check_n_procs(n_procs: int, *, oversubscribe: bool = False, cores: int | None = None,
                  where: str = "run.n_procs", per: int = 1, context: str = "") -> None:
    """Refuse ``n_procs`` ranks (or cases of ``per`` cores each) above the usable cores
    unless ``oversubscribe``; the message names ``where`` (and ``context``)."""
    cores = usable_cores() if cores is None else cores
    if n_procs * per > cores and not oversubscribe:
        uses = f" x {per} cores (run.n_procs) = {n_procs * per} cores" if per > 1 else ""
        raise SpecError(f"{where} = {n_procs}{context}{uses} is more than the {cores} CPU "
                        f"cores this process may use (valid range 1 <= {where} <= "
                        f"{max(cores // per, 1)}; --oversubscribe runs it anyway, slowly)")


def check_limit(name: str, value: object, unit: str = "", upper: float | None = None) -> float:
    """``value`` as a positive, finite number (at most ``upper``), or a :class:`SpecError`
    naming ``name``: NaN and infinity are not limits."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SpecError(f"{name} = {value!r}: not a number (valid range 0 < {name}"
                        f"{f' <= {upper:g}' if upper is not None else ''}{f' {unit}' if unit else ''})")
    v = float(value)
    if not (math.isfinite(v) and v > 0 and (upper is None or v <= upper)):
        rng = f"0 < {name}" + (f" <= {upper:g}" if upper is not None else "")
        raise SpecError(f"{name} = {value!r}: valid range {rng}{f' {unit}' if unit else ''} "
                        f"(finite: NaN or infinity is not a limit)")
    return v


def _upper(field_name: str) -> float:
    """The upper bound (``le``) of a ``[run]`` key."""
    return next(float(m.le) for m in Run.model_fields[field_name].metadata
                if getattr(m, "le", None) is not None)


#: The longest wall-clock limit [s], the spec's (run.wall_limit) and the command line's.
WALL_LIMIT_MAX = _upper("wall_limit")


def check_wall_limit(value: object, name: str = "wall_limit") -> float:
    """A wall-clock limit [s]: positive, finite, at most :data:`WALL_LIMIT_MAX`."""
    return check_limit(name, value, "s", upper=WALL_LIMIT_MAX)


def check_extension(spec: CaseSpec, transits: float, transit_time: float,
                    max_delta_t: float, name: str = "--extend (extend_transits)") -> None:
    """Refuse an extension of ``transits`` transit times (of ``transit_time`` [s], in steps of
    at most ``max_delta_t`` [s]) that takes more than ``run.max_steps`` time steps."""
    steps = transits * transit_time / max_delta_t
    if steps > spec.run.max_steps:
        raise SpecError(
            f"{name} = {transits:g} transits takes at least {_count(steps)} time steps of at "
            f"most {max_delta_t:.3g} s, more than run.max_steps = {spec.run.max_steps:,} "
            f"(valid range 0 < --extend <= "
            f"{spec.run.max_steps * max_delta_t / transit_time:.4g} transits)")


@dataclass(frozen=True)
class WorkEstimate:
    """What a case spec asks for, estimated from the spec alone (no precalc, no mesh)."""

    quads: float          # in-plane cells of the base mesh (integral of 1 / size^2)
    n_layers: int         # cells across the gap
    end_time: float       # simulated time [s]
    max_delta_t: float    # the largest time step [s]: the capillary limit or a write interval
    min_cell_size: float  # the smallest in-plane cell [m]

    @property
    def cells(self) -> float:
        """Cells of the case's mesh (about)."""
        return self.quads * self.n_layers

    @property
    def steps(self) -> float:
        """Time steps to reach the end time, at least (the Courant limits add more)."""
        return self.end_time / self.max_delta_t


def estimate_work(spec: CaseSpec) -> WorkEstimate:
    """The cells and time steps of ``spec``'s case, from its mesh sizes and time span only:
    fast (milliseconds) whatever the spec asks for."""
    params = mesh_params(spec)
    dx = smallest_cell_size(spec)
    dt = min(capillary_time_step(spec, dx), write_interval(spec))
    return WorkEstimate(quads=estimate_quads(params, size_function(spec)),
                        n_layers=params.n_layers, end_time=spec.end_time, max_delta_t=dt,
                        min_cell_size=dx)


def estimate_cells(spec: CaseSpec) -> float:
    """About how many cells the case of ``spec`` has (in-plane quads x layers)."""
    return estimate_work(spec).cells


def estimate_steps(spec: CaseSpec) -> float:
    """At least how many time steps the case of ``spec`` takes to its end time."""
    return estimate_work(spec).steps


def _count(n: float) -> str:
    return f"{n:,.0f}" if n < 1e9 else f"{n:.3g}"


def check_work(spec: CaseSpec, estimate: WorkEstimate | None = None) -> WorkEstimate:
    """Refuse a spec whose case would exceed ``mesh.max_cells`` or ``run.max_steps``, with
    the estimate and the keys to change; returns the estimate."""
    est = estimate or estimate_work(spec)
    cap = spec.mesh.max_cells
    if est.cells > cap:
        raise SpecError(
            f"invalid case spec: mesh.max_cells = {cap:,}: the mesh would have about "
            f"{_count(est.cells)} cells ({_count(est.quads)} in-plane x {est.n_layers} "
            f"layers; smallest in-plane cell {est.min_cell_size:.3g} m), more than the cap: "
            f"coarsen mesh.size_rim, mesh.size_far or mesh.refine, take fewer mesh.n_layers "
            f"or a smaller domain, or raise mesh.max_cells if this machine can take it")
    cap_steps = spec.run.max_steps
    if est.steps > cap_steps:
        raise SpecError(
            f"invalid case spec: run.max_steps = {cap_steps:,}: reaching the end time "
            f"{est.end_time:.4g} s takes at least {_count(est.steps)} time steps of at most "
            f"{est.max_delta_t:.3g} s (run.capillary_limit on cells of "
            f"{est.min_cell_size:.3g} m, or the write interval), more than the cap: shorten "
            f"run.end_time or run.transits_max, coarsen the smallest cells, or raise "
            f"run.max_steps")
    return est
