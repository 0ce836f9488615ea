"""Run a generated case to steady state and write ``DIR/metrics.json``.

interFoam runs as a child process (through :mod:`ehlfoam.foam.runtime`). Function objects fail in
Debian 13's OpenFOAM build, so the monitor watches from outside: it reads every time folder
the solver writes (oil volume, oil fluxes through the open boundaries, the flow pattern on the
mid-gap surface), keeps ``DIR/history.csv``, and stops the solver through controlDict
(``stopAt writeNow``) when the oil volume and the meniscus positions have changed by less than
the tolerance over one transit time. End reasons:

- ``steady``: a steady-state test passed (``steady_test`` in metrics.json: "last write", the
  last write within the tolerance of the one a transit earlier, or "window mean", the means
  over the last two transits within it: a statistically steady flow), and the oil volume's
  least-squares trend over the last transit is within the tolerance too;
- ``end_time``: the simulated time limit was reached first;
- ``wall_limit``: the wall-clock limit was reached first;
- ``diverged``: the solver failed (non-zero exit, e.g. a floating-point trap) or its time
  step collapsed; the logs stay and metrics.json says ``status: failed``;
- ``interrupted``: Ctrl-C or SIGTERM; the solver is stopped with a final write.
"""

from __future__ import annotations

import csv
import fcntl
import io
import math
import re
import shutil
import signal
import statistics
import subprocess
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from foamlib import FoamFile

from ehlfoam._io import atomic_write_json, atomic_write_text
from ehlfoam.spec.case import CaseSpec
from ehlfoam.case.writer import (META, CaseGeometry, load_geometry, load_spec_of, mesh_warnings, size_function)

from ehlfoam.run import fields as case_fields
from ehlfoam.foam.runtime import FoamRuntime

POLL_S = 1.0
STOP_GRACE_S = 120.0
DT_COLLAPSE = 1e-4          # time step below this fraction of maxDeltaT counts as collapse
DT_COLLAPSE_STEPS = 200     # ... for this many consecutive logged steps
#: share of the outflow leaving off the outlet above which a run is flagged: the region (or a
#: wall film) reached the side or upstream boundary, e.g. a width of 15.5 a against a side at
#: 8 a (docs/cases.md, "The films decide the width")
OFF_OUTLET_WARNING = 0.05
#: flooded region nearer an open boundary than this (units a) is flagged: its meniscus feels
#: the boundary's fixed pressure, and at the outlet the oil leaves in bulk instead of as the
#: films the rear meniscus lays (a film-resolving run's rear reached 13.5 a against a 14 a
#: outlet, docs/cases.md "What the films converge to")
CLEARANCE_WARNING = 1.0
#: in-plane cells at the rear meniscus coarser than this (units a) are flagged: they lay wall
#: films thicker than Landau-Levich's (1.6-2.1 times at 0.55 a, 1.0 at 0.1 a on the 2D strip),
#: and the flooded width comes out short (the default levels' 0.4-0.8 a cells by 16-20 %
#: against a run at 0.1 a, 11-16 % against one at 0.05 a on the rear arc; docs/cases.md, "One
#: step finer at the rear meniscus")
REAR_CELL_WARNING = 0.15
#: The in-plane cells over the wall cell's height along the flooded region's front off the
#: track, where dry walls run into it, above which a run warns: in the contact-line strip the
#: meniscus holds no capillary suction beyond some 15 (docs/cases.md, "The region's sides are
#: moving contact lines").
FRONT_CELL_WARNING = 15.0


class CaseBusy(RuntimeError):
    """Another process is running this case."""


#: Pattern positions the steady-state tests follow (units a).
_POSITIONS = ("inlet_meniscus_distance_over_a", "flooded_length_over_a", "flooded_width_over_a",
              "wake_gas_length_over_a", "bubble_length_over_a")


def _steady_now(history: list[case_fields.Sample], window: float, tol: float,
                length_scale: float) -> bool:
    """Oil volume and bubble volume within ``tol`` (relative to the oil volume), meniscus
    and bubble-tip positions within ``tol * length_scale`` (units a) of their values one
    ``window`` ago."""
    if not history or history[-1].time - history[0].time < window * (1 - 1e-9):
        return False
    now = history[-1]
    then = min(history, key=lambda s: abs(s.time - (now.time - window)))
    if now.time - then.time < 0.5 * window:
        return False
    if abs(now.oil_volume - then.oil_volume) > tol * max(now.oil_volume, 1e-300):
        return False
    if now.pattern.get("state") != then.pattern.get("state"):
        return False
    for key in _POSITIONS:
        a, b = now.pattern.get(key), then.pattern.get(key)
        if (a is None) != (b is None):
            return False
        if a is not None and abs(a - b) > tol * length_scale:
            return False
    # the bubble's volume, relative to the oil volume (a vanishing bubble is steady)
    a, b = now.pattern.get("bubble_volume_m3"), then.pattern.get("bubble_volume_m3")
    if a is not None and b is not None and abs(a - b) > tol * max(now.oil_volume, 1e-300):
        return False
    return True


def _steady_in_mean(history: list[case_fields.Sample], window: float, tol: float,
                    length_scale: float) -> bool:
    """Statistically steady: over the last ``window`` and the one before it, the flow kept one
    state at every write, and the window means of the oil volume (and bubble volume) agree
    within ``tol`` of the oil volume and those of the positions within ``tol * length_scale``.

    A flooded region fed with ample oil keeps shedding fingers at its sides and rear: its
    width jumps by 5-10 % from write to write around a fixed mean, so the test on the last
    write alone never passes although the oil volume has stopped growing.
    """
    if not history or history[-1].time - history[0].time < 2 * window * (1 - 1e-9):
        return False
    now = history[-1].time
    last = [s for s in history if now - window < s.time <= now]
    before = [s for s in history if now - 2 * window < s.time <= now - window]
    if len(last) < 3 or len(before) < 3:
        return False
    if len({s.pattern.get("state") for s in last + before}) != 1:
        return False

    def mean(samples, value):
        vals = [value(s) for s in samples]
        return None if any(v is None for v in vals) else sum(vals) / len(vals)

    volume = mean(last, lambda s: s.oil_volume)
    if abs(volume - mean(before, lambda s: s.oil_volume)) > tol * max(volume, 1e-300):
        return False
    for key in _POSITIONS + ("bubble_volume_m3",):
        a = mean(last, lambda s: s.pattern.get(key))
        b = mean(before, lambda s: s.pattern.get(key))
        if (a is None) != (b is None):
            return False
        limit = tol * (max(volume, 1e-300) if key == "bubble_volume_m3" else length_scale)
        if a is not None and abs(a - b) > limit:
            return False
    return True


def _oil_trend_within(history: list[case_fields.Sample], window: float, tol: float) -> bool:
    """The oil volume's least-squares trend over the last ``window`` changes it by less than
    ``tol`` of itself per window.

    Both tests below compare two points or two means a window apart; a flooded region that
    had settled and then starts to fill again can pass them while the oil still rises (a run
    of 2026-11-24 passed "window mean" rising 1.75 % a transit, docs/cases.md). The trend
    over the last window sees that."""
    now = history[-1].time
    last = [s for s in history if s.time >= now - window * (1 + 1e-9)]
    if len(last) < 2:
        return False
    slope = statistics.linear_regression([s.time for s in last],
                                         [s.oil_volume for s in last]).slope
    return abs(slope) * window <= tol * max(history[-1].oil_volume, 1e-300)


def steady_test(history: list[case_fields.Sample], window: float, tol: float,
                length_scale: float) -> str | None:
    """Which steady-state test the run passes now: "last write" (the last write against the
    one a ``window`` earlier), "window mean" (:func:`_steady_in_mean`), or None; either only
    while the oil volume's trend over the last window is within the tolerance too
    (:func:`_oil_trend_within`)."""
    if not history or not _oil_trend_within(history, window, tol):
        return None
    if _steady_now(history, window, tol, length_scale):
        return "last write"
    if _steady_in_mean(history, window, tol, length_scale):
        return "window mean"
    return None


def _set_stop(case: Path, value: str) -> None:
    with FoamFile(case / "system" / "controlDict") as f:
        f["stopAt"] = value


_STEP = re.compile(r"^deltaT = ([-+0-9.eE]+)\s*$", re.M)
_TIME = re.compile(r"^Time = ([-+0-9.eE]+)\s*$", re.M)


class LogTail:
    """Incremental reader of the solver log: time steps and the last deltaT values."""

    def __init__(self, path: Path):
        self.path, self.offset, self.steps, self.small_steps = path, 0, 0, 0
        self.last_dt = math.nan

    def update(self, dt_floor: float) -> None:
        try:
            with open(self.path, "rb") as fh:
                fh.seek(self.offset)
                chunk = fh.read()
        except FileNotFoundError:
            return
        cut = chunk.rfind(b"\n") + 1
        self.offset += cut
        text = chunk[:cut].decode("utf-8", "replace")
        for m in _STEP.finditer(text):
            self.last_dt = float(m.group(1))
            self.small_steps = self.small_steps + 1 if self.last_dt < dt_floor else 0
        self.steps += len(_TIME.findall(text))


def _write_history(case: Path, history: list[case_fields.Sample]) -> None:
    if not history:
        return
    buf = io.StringIO()
    rows = [s.row() for s in history]
    writer = csv.DictWriter(buf, fieldnames=list(rows[0]))
    writer.writeheader()
    writer.writerows(rows)
    atomic_write_text(case / "history.csv", buf.getvalue())


def _balance(amount: list[float], ins: list[float], outs: list[float], t: np.ndarray,
             what: str, unit: str) -> dict:
    """``amount`` change against the time integral of the fluxes through the open boundaries,
    from the first to the last written time (trapezoid over the writes; before the first
    write the fluxes are not known). The error is relative to what came in over that window
    (or to the amount when almost nothing came in)."""
    carried_in = float(np.trapezoid(ins, t))
    carried_out = float(np.trapezoid(outs, t))
    residual = amount[-1] - amount[0] - (carried_in - carried_out)
    by_inflow = carried_in > 0.01 * amount[-1]
    scale = carried_in if by_inflow else amount[-1]
    return {f"{what}_carried_in_{unit}": carried_in, f"{what}_carried_out_{unit}": carried_out,
            f"{what}_mass_balance_residual_{unit}": residual,
            f"{what}_mass_balance_error": abs(residual) / scale if scale > 0 else None,
            f"{what}_mass_balance_reference": f"{what} carried in" if by_inflow else f"{what} amount",
            f"{what}_mass_balance_window_s": [float(t[0]), float(t[-1])]}


#: how the oil fluxes through the boundaries were read (``oil_flux_source`` in metrics.json)
OIL_FLUX_EXACT = "alphaPhi0: the oil flux the solver transported"
OIL_FLUX_APPROXIMATE = (
    "phi x face alpha at the writes (the solver writes no alphaPhi0): approximate. It closes "
    "within 1 % while no interface crosses an open boundary (state I); with an open wake it "
    "misses part of the outflow whatever the write density (6 % of it on a 20 mm/s window "
    "written every step; docs/cavitation.md)")


def mass_balance(history: list[case_fields.Sample]) -> dict:
    """The oil balance (volumes: the oil is incompressible or nearly so) and, in a compressible
    scene, the air's (masses)."""
    if len(history) < 2:
        return {"oil_carried_in_m3": None, "oil_carried_out_m3": None,
                "oil_mass_balance_error": None}
    t = np.array([s.time for s in history])
    out = _balance([s.oil_volume for s in history], [s.oil_in for s in history],
                   [s.oil_out for s in history], t, "oil", "m3")
    out["oil_flux_source"] = (OIL_FLUX_EXACT if all(s.oil_flux_exact for s in history)
                              else OIL_FLUX_APPROXIMATE)
    if all(s.gas_mass is not None for s in history):
        out |= _balance([s.gas_mass for s in history], [s.gas_in for s in history],
                        [s.gas_out for s in history], t, "gas", "kg")
    return out


def dissolved_air_budget(history: list[case_fields.Sample], air_solubility: float,
                         window: float) -> dict:
    """The gas-release scene's gas against the air its oil could give up. The scene has no
    budget of dissolved air (nothing in v1912 carries one without compiling), so this checks
    after the fact whether one would have bound it, two ways:

    - ``gas_release_over_dissolved_air``: the gas released between the first and the last
      write (trapezoid over the writes; m3 at the gas's ambient density) over the Bunsen
      coefficient ``air_solubility`` times all the oil that was in the gap at the first
      write or came in since;
    - ``gas_release_over_dissolved_inflow``: over the last ``window`` [s] (a transit), the
      mean release rate over the mean rate at which the supply brings dissolved air in
      (the steady-state budget; in a short run the first measure is diluted by the oil
      already in the gap).

    Above 1 the model made more gas than the oil could hold; below 1 is necessary, not
    sufficient (only the oil that passes the suction can give its air up). Empty for scenes
    that release nothing."""
    rates = [s.pattern.get("gas_release_m3_s") for s in history]
    if len(history) < 2 or any(r is None for r in rates):
        return {}
    t = np.array([s.time for s in history])
    rates, oil_in = np.asarray(rates, dtype=float), np.array([s.oil_in for s in history])
    released = float(np.trapezoid(rates, t))
    dissolved = air_solubility * (history[0].oil_volume + float(np.trapezoid(oil_in, t)))
    last = t >= t[-1] - window * (1.0 + 1e-9)
    inflow = air_solubility * float(oil_in[last].mean())
    rate = float(rates[last].mean())
    return {"gas_released_m3": released, "dissolved_air_m3": dissolved,
            "gas_release_over_dissolved_air": released / dissolved if dissolved > 0 else None,
            "gas_release_over_dissolved_inflow": rate / inflow if inflow > 0 else None}


def run_case(case: str | Path, runtime: FoamRuntime | None = None,
             wall_limit: float | None = None,
             on_sample: Callable[[case_fields.Sample, CaseGeometry], None] | None = None,
             extend_transits: float | None = None) -> dict:
    """Run the case in ``case`` to steady state (or a limit) and write ``metrics.json``.

    Restarts from the latest written time if the case ran before. With ``extend_transits``
    the run goes on for that many transit times past the latest written time whatever the
    steady-state tests say (to see whether a steady state lasts, or to go on after a time
    limit); it then ends at ``end_time``, the wall limit or divergence. Returns the metrics
    dict.
    """
    if extend_transits is not None and not extend_transits > 0:
        raise ValueError(f"extend_transits = {extend_transits!r} transits: it must be > 0")
    case = Path(case).absolute()
    spec, geom = load_spec_of(case), load_geometry(case)
    structure = case_fields.Structure.load(case)
    runtime = runtime or FoamRuntime.from_environment()
    wall_limit = wall_limit or spec.run.wall_limit
    lock = open(case / META / "run.lock", "w")
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        raise CaseBusy(f"case {case} is being run by another process") from None
    try:
        if extend_transits is not None:
            _extend_end_time(case, geom, extend_transits)
        return _run_locked(case, spec, geom, structure, runtime, wall_limit, on_sample,
                           check_steady=extend_transits is None)
    finally:
        lock.close()


def _extend_end_time(case: Path, geom: CaseGeometry, transits: float) -> None:
    """Set controlDict's endTime ``transits`` transit times past the latest written time, or
    past 0 for a case that has not run yet (a case seeded from another one's state runs
    ``transits`` from its start)."""
    folders = case_fields.time_folders(case)
    if folders:
        start = folders[-1][0]
    elif (case / "0.orig").is_dir() or (case / "0").is_dir():
        start = 0.0
    else:
        raise FileNotFoundError(f"{case} has no written time nor initial fields (0.orig/) "
                                "to extend from")
    with FoamFile(case / "system" / "controlDict") as f:
        f["endTime"] = start + transits * geom.transit_time


def _run_locked(case, spec, geom, structure, runtime, wall_limit, on_sample,
                check_steady: bool = True) -> dict:
    atomic_write_json(case / "metrics.json", {"status": "running", "cells": geom.cells})
    if not (case / "0").is_dir():
        shutil.copytree(case / "0.orig", case / "0")
    _set_stop(case, "endTime")
    v0 = case_fields.initial_oil_volume(case, structure, geom)
    history: list[case_fields.Sample] = []
    done: set[str] = set()
    for _, folder in case_fields.time_folders(case):   # a restart: earlier writes count
        history.append(case_fields.sample(folder, structure, geom))
        done.add(folder.name)
    log_path = case / geom.log_name
    if log_path.exists():
        log_path.rename(case / f"{geom.log_name}.{int(time.time())}")
    tail = LogTail(log_path)
    dt_floor = DT_COLLAPSE * geom.max_delta_t
    t_start = time.monotonic()
    n_procs = spec.run.n_procs
    if n_procs > 1 and not (case / "processor0").is_dir():   # a restart needs its latest time only
        runtime.run("decomposePar", ["-force", "-latestTime"], cwd=case,
                    log_path=case / "log.decomposePar")
    proc = runtime.popen(geom.solver, [], cwd=case, log_path=geom.log_name, n_procs=n_procs)
    reason, stopping_since, steady_kind = None, None, None
    previous = signal.getsignal(signal.SIGTERM)
    signal.signal(signal.SIGTERM, _raise_interrupt)
    try:
        while True:
            exited = proc.poll() is not None
            tail.update(dt_floor)
            if n_procs > 1:
                _reconstruct_new(case, runtime)
            _collect(case, structure, geom, history, done, exited, on_sample)
            if exited:
                break
            if reason is None:
                passed = check_steady and steady_test(
                    history, geom.transit_time, spec.run.steady_tolerance,
                    spec.run.transit_length)
                if passed:
                    reason, steady_kind = "steady", passed
                elif time.monotonic() - t_start > wall_limit:
                    reason = "wall_limit"
                elif tail.small_steps >= DT_COLLAPSE_STEPS:
                    reason = "diverged"
                    proc.kill()
                if reason in ("steady", "wall_limit"):
                    _set_stop(case, "writeNow")
                    stopping_since = time.monotonic()
            elif stopping_since and time.monotonic() - stopping_since > STOP_GRACE_S:
                proc.kill()
            time.sleep(POLL_S)
    except KeyboardInterrupt:
        reason = "interrupted"
        _set_stop(case, "writeNow")
        try:
            proc.wait(timeout=STOP_GRACE_S)
        except subprocess.TimeoutExpired:
            proc.kill()
    finally:
        signal.signal(signal.SIGTERM, previous)
        if proc.poll() is None:
            proc.kill()
        proc.wait()
    if n_procs > 1:   # the last writes
        _reconstruct_new(case, runtime)
    # one more sample pass: a run stopped by a signal left the loop before its last writes
    _collect(case, structure, geom, history, done, True, on_sample)
    wall = time.monotonic() - t_start
    rc = proc.returncode
    if reason is None:
        reason = "end_time" if rc == 0 else "diverged"
    failed = reason == "diverged" or (rc != 0 and reason not in ("interrupted",) and rc != -9)
    metrics = _final_metrics(spec, geom, structure, v0, history, reason, failed, rc, tail, wall,
                             case)
    metrics["steady_test"] = steady_kind
    atomic_write_json(case / "metrics.json", metrics)
    return metrics


def _collect(case: Path, structure, geom: CaseGeometry, history: list[case_fields.Sample],
             done: set[str], exited: bool, on_sample) -> None:
    """Sample the time folders not read yet into ``history`` and rewrite history.csv.

    While the solver runs, a folder is read only once the solver has moved on to the next one
    (a half-written field must never reach the parser) and a failed read is retried at the
    next poll; once it has exited, every folder is read once and unreadable ones are skipped.
    """
    folders = case_fields.time_folders(case)
    new = False
    for k, (_, folder) in enumerate(folders):
        if folder.name in done:
            continue
        if not exited and k == len(folders) - 1:
            break
        try:
            s = case_fields.sample(folder, structure, geom)
        except Exception:
            if exited:
                done.add(folder.name)
            continue   # still being written: next poll
        done.add(folder.name)
        history.append(s)
        new = True
        if on_sample:
            on_sample(s, geom)
    if new:
        _write_history(case, history)


def _reconstruct_new(case: Path, runtime: FoamRuntime) -> None:
    """Bring the times the ranks wrote into the case folder (reconstructPar -newTimes)."""
    written = {p.name for p in (case / "processor0").iterdir() if p.is_dir()} \
        if (case / "processor0").is_dir() else set()
    have = {p.name for _, p in case_fields.time_folders(case)} | {"0", "constant"}
    if written - have:
        runtime.run("reconstructPar", ["-newTimes"], cwd=case,
                    log_path=case / "log.reconstructPar", check=False)


def _raise_interrupt(signum, frame):
    raise KeyboardInterrupt


#: the spec key that moves each open boundary
_BOUNDARY_KEY = {"upstream": "domain.upstream", "outlet": "domain.downstream",
                 "side": "domain.side"}


def boundary_warnings(off_outlet: float | None, pattern: dict | None = None) -> list[str]:
    """Warnings when more than :data:`OFF_OUTLET_WARNING` of the oil leaving the domain
    (``off_outlet``, the share at the last write) did not leave through the outlet, and when
    the flooded region of the last write (``pattern``: its ``flooded_clearance_over_a`` and
    ``flooded_nearest_boundary``) is within :data:`CLEARANCE_WARNING` of an open boundary."""
    out = []
    if off_outlet is not None and off_outlet > OFF_OUTLET_WARNING:
        out.append(f"{off_outlet:.0%} of the outflow left through the side or upstream boundary "
                   f"(above {OFF_OUTLET_WARNING:.0%}): the flooded region or a wall film reached "
                   f"it, so the region is cut short; widen the domain (domain.side, "
                   f"domain.upstream)")
    clearance = (pattern or {}).get("flooded_clearance_over_a")
    if clearance is not None and clearance < CLEARANCE_WARNING:
        where = pattern["flooded_nearest_boundary"]
        out.append(f"the flooded region is {clearance:.2f} a from the {where} boundary (below "
                   f"{CLEARANCE_WARNING:g} a): the boundary may hold or cut it; move it out "
                   f"({_BOUNDARY_KEY[where]})")
    return out


def rear_meniscus_cell(spec: CaseSpec, pattern: dict | None) -> float | None:
    """In-plane cell size (units a) where the closed flooded region's rear meniscus crosses
    y = 0 (at ``flooded_x_max_over_a``): the cells that lay the wall films leaving the region,
    which decide how much oil it holds and how wide it grows. None for an open wake (state II)
    or no region."""
    x_rear = (pattern or {}).get("flooded_x_max_over_a")
    if x_rear is None or pattern.get("state") != "I":
        return None
    return float(size_function(spec)(x_rear * spec.a, 0.0) / spec.a)


def rear_cell_warnings(rear_cell: float | None) -> list[str]:
    """A warning when the rear meniscus sits in cells (``rear_cell``, units a) coarser than
    :data:`REAR_CELL_WARNING`, naming what refines them."""
    if rear_cell is None or rear_cell <= REAR_CELL_WARNING:
        return []
    return [f"the rear meniscus sits in {rear_cell:.2f} a cells (above {REAR_CELL_WARNING:g} a): "
            f"they lay wall films thicker than Landau-Levich's and set how much oil leaves the "
            f"region (0.7 -> 0.06 a there halved the coarse level's outflow), so the oil it holds "
            f"and its width are off (the default levels' width by 11-20 % against the finest "
            f"runs); refine over the rear (mesh.refine: a box as in runs/nominal_films.toml, or "
            f"a band along this run's meniscus from `ehlfoam band CASE`); "
            f"docs/cases.md, \"One step finer at the rear meniscus\", \"The oil goes to the "
            f"rear meniscus\""]


def front_contact_line_cells(spec: CaseSpec, geom: CaseGeometry,
                             structure: case_fields.Structure, case: Path,
                             pattern: dict | None) -> float | None:
    """The median, along the closed flooded region's edge where dry walls run into it off
    the track, of the in-plane cell size over the wall cell's height
    (:func:`case_fields.advancing_front_cells`, at the last write). None for an open wake, no
    region or no such edge."""
    folders = case_fields.time_folders(case)
    if (pattern or {}).get("state") != "I" or not folders:
        return None
    try:
        ratios = case_fields.advancing_front_cells(folders[-1][1], structure, geom,
                                                   spec.supply.track_half_width)
    except (OSError, ValueError, KeyError):     # a last write cut short: no figure
        return None
    return float(np.median(ratios)) if len(ratios) else None


def front_cell_warnings(front_cells: float | None,
                        isotropic_compression: float = 0.0) -> list[str]:
    """A warning when the region's front off the track, where dry walls run into it, sits in
    cells wider than :data:`FRONT_CELL_WARNING` wall cells; none with the compression taken
    from the local speed (``physics.isotropic_compression = 1``), with which the advancing
    line holds on any cells (docs/cases.md, "The advancing contact line and the interface
    compression")."""
    if front_cells is None or front_cells <= FRONT_CELL_WARNING or isotropic_compression == 1.0:
        return []
    return [f"the flooded region's front off the track, where dry walls run into it, sits in "
            f"in-plane cells {front_cells:.0f} times its wall cells (above "
            f"{FRONT_CELL_WARNING:g}): there interFoam gives the advancing contact line no "
            f"capillary suction, and neither the flooded width nor the inlet meniscus is "
            f"converged (on the coarse walls resolving it moved the inlet meniscus 12 % "
            f"downstream); take the interface compression from the local speed "
            f"(physics.isotropic_compression = 1), with which the line holds on any cells and "
            f"does not move with them (at some 30 deg, whatever the walls' angle; not for "
            f"resting menisci), or continue the run on a mesh with a band along its "
            f"meniscus (`ehlfoam band CASE --size S --half-width 1` into mesh.refine, S within "
            f"{FRONT_CELL_WARNING:g} wall cells); docs/cases.md, \"The advancing contact "
            f"line and the interface compression\", \"The region's sides are moving contact "
            f"lines\""]


def _final_metrics(spec, geom: CaseGeometry, structure, v0, history, reason, failed, rc, tail, wall,
                   case) -> dict:
    last = history[-1] if history else None
    pattern = dict(last.pattern) if last else {}
    off_outlet = case_fields.off_outlet_share(last.oil_out_by_boundary) if last else None
    # where oil fills the domain (single-phase scene, submerged supply) it meets every
    # boundary by design and lays no films: these warnings are for a region surrounded by air
    surrounded = geom.open_inflow_oil == 0.0
    rear_cell = rear_meniscus_cell(spec, pattern) if surrounded else None
    front_cells = (front_contact_line_cells(spec, geom, structure, case, pattern)
                   if surrounded and not failed else None)
    out = {
        "status": "failed" if failed else ("interrupted" if reason == "interrupted" else "finished"),
        "end_reason": reason,
        "steady": reason == "steady",
        "solver_exit_code": rc,
        "simulated_time_s": last.time if last else 0.0,
        "transit_time_s": geom.transit_time,
        **pattern,
        "oil_volume_m3": last.oil_volume if last else v0,
        "oil_volume_initial_m3": v0,
        "oil_inflow_m3_s": last.oil_in if last else None,
        "oil_outflow_m3_s": last.oil_out if last else None,
        "oil_outflow_by_boundary_m3_s": dict(last.oil_out_by_boundary) if last else None,
        "oil_outflow_off_outlet_fraction": off_outlet,
        **mass_balance(history),
        **dissolved_air_budget(history, geom.air_solubility, geom.transit_time),
        "contact_flow_m3_s": geom.contact_flow,
        "contact_flow_over_inflow": (geom.contact_flow / last.oil_in
                                     if last and last.oil_in > 0 else None),
        "cells": geom.cells,
        "time_steps": tail.steps,
        "last_delta_t_s": tail.last_dt,
        "max_delta_t_s": geom.max_delta_t,
        "wall_s": wall,
        "wall_s_per_simulated_ms": wall / (1e3 * last.time) if last and last.time > 0 else None,
        "a_m": geom.a,
        "speed_m_s": geom.speed,
        "mesh_gap_mismatch": geom.gap_mismatch,
        "ball_wall_steps": geom.ball_wall_steps,
        "rear_meniscus_cell_over_a": rear_cell,
        "front_contact_line_cells_over_wall_cell": front_cells,
        "warnings": "; ".join(
            mesh_warnings(geom) + rear_cell_warnings(rear_cell)
            + front_cell_warnings(front_cells, spec.physics.isotropic_compression)
            + (boundary_warnings(off_outlet, pattern) if surrounded else [])),
    }
    if failed:
        log = case / geom.log_name
        lines = log.read_text(errors="replace").splitlines()[-20:] if log.exists() else []
        out["log_tail"] = lines
    return out
