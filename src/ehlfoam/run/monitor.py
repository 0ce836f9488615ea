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

import fcntl
import math
import re
import shutil
import signal
import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from foamlib import FoamFile

from ehlfoam.case.geometry import META, CaseGeometry, load_geometry, load_spec_of
from ehlfoam.foam.runtime import FoamRuntime
from ehlfoam.metrics.record import MetricsRecord, write_metrics
from ehlfoam.run import fields as case_fields
from ehlfoam.run.balance import (OIL_FLUX_APPROXIMATE, OIL_FLUX_EXACT, dissolved_air_budget,
                                 mass_balance)
from ehlfoam.run.final import RunEnd, final_record
from ehlfoam.run.history import write_history
from ehlfoam.run.steady import steady_test
from ehlfoam.run.warnings import (CLEARANCE_WARNING, FRONT_CELL_WARNING, OFF_OUTLET_WARNING,
                                  REAR_CELL_WARNING, boundary_warnings, front_cell_warnings,
                                  rear_cell_warnings, rear_meniscus_cell)
from ehlfoam.spec.case import CaseSpec

#: run_case and CaseBusy; the rest is re-exported from the modules that now hold it
#: (ehlfoam.run.steady, .balance, .warnings) for the callers of this module
__all__ = ["CLEARANCE_WARNING", "FRONT_CELL_WARNING", "OFF_OUTLET_WARNING",
           "OIL_FLUX_APPROXIMATE", "OIL_FLUX_EXACT", "REAR_CELL_WARNING", "CaseBusy",
           "LogTail", "boundary_warnings", "dissolved_air_budget", "front_cell_warnings",
           "mass_balance", "rear_cell_warnings", "rear_meniscus_cell", "run_case",
           "steady_test"]

POLL_S = 1.0
STOP_GRACE_S = 120.0
DT_COLLAPSE = 1e-4          # time step below this fraction of maxDeltaT counts as collapse
DT_COLLAPSE_STEPS = 200     # ... for this many consecutive logged steps

#: called with each new sample of the run and the case's geometry
OnSample = Callable[[case_fields.Sample, CaseGeometry], None]


class CaseBusy(RuntimeError):
    """Another process is running this case."""


@dataclass(frozen=True)
class _Case:
    """A generated case: its folder, spec, geometry and mesh structure."""

    path: Path
    spec: CaseSpec
    geom: CaseGeometry
    structure: case_fields.Structure


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


def run_case(case: str | Path, runtime: FoamRuntime | None = None,
             wall_limit: float | None = None, on_sample: OnSample | None = None,
             extend_transits: float | None = None,
             oversubscribe: bool = False) -> MetricsRecord:
    """Run the case in ``case`` to steady state (or a limit) and write ``metrics.json``.

    Restarts from the latest written time if the case ran before. With ``extend_transits``
    the run goes on for that many transit times past the latest written time whatever the
    steady-state tests say (to see whether a steady state lasts, or to go on after a time
    limit); it then ends at ``end_time``, the wall limit or divergence. ``wall_limit`` [s]
    defaults to the spec's ``run.wall_limit``. Returns the metrics record (as written).

    Bounds (:mod:`ehlfoam.case.bounds`), checked before anything is written: ``wall_limit``
    and ``extend_transits`` positive and finite; ``run.n_procs`` within the cores this
    process may use unless ``oversubscribe``; an extension within ``run.max_steps``. A
    :class:`~ehlfoam.errors.SpecError` names the one that is not.
    """
    from ehlfoam.case.bounds import check_extension, check_limit, check_n_procs, check_wall_limit

    if wall_limit is not None:
        check_wall_limit(wall_limit)
    if extend_transits is not None:
        check_limit("extend_transits", extend_transits, "transits")
    path = Path(case).absolute()
    run = _Case(path, load_spec_of(path), load_geometry(path),
                case_fields.Structure.load(path))
    check_n_procs(run.spec.run.n_procs, oversubscribe=oversubscribe)
    if extend_transits is not None:
        check_extension(run.spec, extend_transits, run.geom.transit_time,
                        run.geom.max_delta_t)
    lock = open(path / META / "run.lock", "w")
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        raise CaseBusy(f"case {path} is being run by another process") from None
    try:
        if extend_transits is not None:
            _extend_end_time(path, run.geom, extend_transits)
        return _run_locked(run, runtime=runtime or FoamRuntime.from_environment(),
                           wall_limit=wall_limit or run.spec.run.wall_limit,
                           on_sample=on_sample, check_steady=extend_transits is None)
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


def _run_locked(run: _Case, *, runtime: FoamRuntime, wall_limit: float,
                on_sample: OnSample | None, check_steady: bool = True) -> MetricsRecord:
    case, spec, geom, structure = run.path, run.spec, run.geom, run.structure
    write_metrics(case, MetricsRecord(status="running", cells=geom.cells))
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
            _collect(run, history, done, exited=exited, on_sample=on_sample)
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
    _collect(run, history, done, exited=True, on_sample=on_sample)
    wall = time.monotonic() - t_start
    rc = proc.returncode
    if reason is None:
        reason = "end_time" if rc == 0 else "diverged"
    failed = reason == "diverged" or (rc != 0 and reason not in ("interrupted",) and rc != -9)
    end = RunEnd(reason=reason, failed=failed, exit_code=rc, time_steps=tail.steps,
                 last_delta_t=tail.last_dt, wall_s=wall, steady_test=steady_kind)
    record = final_record(case, spec, geom, structure, initial_oil=v0, history=history,
                          end=end)
    write_metrics(case, record)
    return record


def _collect(run: _Case, history: list[case_fields.Sample], done: set[str], *,
             exited: bool, on_sample: OnSample | None) -> None:
    """Sample the time folders not read yet into ``history`` and rewrite history.csv.

    While the solver runs, a folder is read only once the solver has moved on to the next one
    (a half-written field must never reach the parser) and a failed read is retried at the
    next poll; once it has exited, every folder is read once and unreadable ones are skipped.
    """
    case, geom = run.path, run.geom
    folders = case_fields.time_folders(case)
    new = False
    for k, (_, folder) in enumerate(folders):
        if folder.name in done:
            continue
        if not exited and k == len(folders) - 1:
            break
        try:
            s = case_fields.sample(folder, run.structure, geom)
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
        write_history(case, history)


def _reconstruct_new(case: Path, runtime: FoamRuntime) -> None:
    """Bring the times the ranks wrote into the case folder (reconstructPar -newTimes)."""
    written = {p.name for p in (case / "processor0").iterdir() if p.is_dir()} \
        if (case / "processor0").is_dir() else set()
    have = {p.name for _, p in case_fields.time_folders(case)} | {"0", "constant"}
    if written - have:
        runtime.run("reconstructPar", ["-newTimes"], cwd=case,
                    log_path=case / "log.reconstructPar", check=False)


def _raise_interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


