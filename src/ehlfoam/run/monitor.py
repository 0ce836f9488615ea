"""Run a generated case to steady state and write ``DIR/metrics.json``.

interFoam runs as a child process (through :mod:`ehlfoam.foam.runtime`). Function objects fail in
Debian 13's OpenFOAM build, so the monitor watches from outside: it reads every time folder
the solver writes (oil volume, oil fluxes through the open boundaries, the flow pattern on the
mid-gap surface), keeps ``DIR/history.csv``, and stops the solver through controlDict when the
oil volume and the meniscus positions have changed by less than the tolerance over one transit
time. The steady-state test is applied to every write in turn, and a steady run ends at the
next scheduled write time (controlDict's ``endTime`` set to it): its last write, and the
metrics read from it, do not depend on the wall clock. A wall limit or an interrupt stops the
solver at once (``stopAt writeNow``). End reasons:

- ``steady``: a steady-state test passed (``steady_test`` in metrics.json: "last write", the
  last write within the tolerance of the one a transit earlier, or "window mean", the means
  over the last two transits within it: a statistically steady flow), and the oil volume's
  least-squares trend over the last transit is within the tolerance too;
- ``end_time``: the simulated time limit was reached first;
- ``wall_limit``: the wall-clock limit was reached first;
- ``diverged``: the solver failed after its first time step (non-zero exit, e.g. a
  floating-point trap) or its time step collapsed; the logs stay and metrics.json says
  ``status: failed``;
- ``start_failed``: the run failed before its first time step (decomposition, OpenFOAM
  refusing the case's path, a solver that cannot start); ``reason`` has the log's words
  (:mod:`ehlfoam.run.start`);
- ``case_removed``: the case folder was removed (or replaced) while it ran; the solver is
  stopped and nothing is written (there is no folder to write to);
- ``monitor_error``: the monitor itself failed; the solver is stopped, ``reason`` says why;
- ``interrupted``: Ctrl-C or SIGTERM; the solver is stopped with a final write;
- ``monitor_killed`` (status ``interrupted``): found by the next run (or report, or batch): a
  metrics.json left ``running`` by a monitor that was killed (SIGKILL), its run lock free.

One run per case: the run holds the case's run lock (``ehlfoam/run.lock``,
:mod:`ehlfoam.case.ownership`) and hands the lock's descriptor to its solver, so the lock stays
held while any process of the run lives; the solver dies with the monitor
(:mod:`ehlfoam.foam.lifetime`).
"""

from __future__ import annotations

import math
import os
import shutil
import signal
import subprocess
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import IO

from foamlib import FoamFile

from ehlfoam.case.geometry import META, CaseGeometry, load_geometry, load_spec_of
from ehlfoam.case.ownership import CaseBusy, hold_run_lock
from ehlfoam.case.thin_film import is_thin_film_case
from ehlfoam.foam.runtime import FoamError, FoamRuntime
from ehlfoam.metrics.record import MetricsRecord, read_metrics, write_metrics
from ehlfoam.run import fields as case_fields
from ehlfoam.run.balance import (OIL_FLUX_APPROXIMATE, OIL_FLUX_EXACT, dissolved_air_budget,
                                 mass_balance)
from ehlfoam.run.final import RunEnd, final_record
from ehlfoam.run.history import write_history
from ehlfoam.run.logtail import LogTail
from ehlfoam.run.start import (START_FAILED, StartFailed, failure_from_log, prepare_case,
                               reconstruct_new)
from ehlfoam.run.steady import steady_test
from ehlfoam.run.thin_film import run_thin_film_case
from ehlfoam.run.warnings import (CLEARANCE_WARNING, FRONT_CELL_WARNING, OFF_OUTLET_WARNING,
                                  REAR_CELL_WARNING, boundary_warnings, front_cell_warnings,
                                  rear_cell_warnings, rear_meniscus_cell)
from ehlfoam.spec.case import CaseSpec

#: run_case and CaseBusy; the rest is re-exported from the modules that now hold it
#: (ehlfoam.run.steady, .balance, .warnings) for the callers of this module
__all__ = ["CLEARANCE_WARNING", "FRONT_CELL_WARNING", "MONITOR_KILLED", "OFF_OUTLET_WARNING",
           "OIL_FLUX_APPROXIMATE", "OIL_FLUX_EXACT", "REAR_CELL_WARNING", "CaseBusy",
           "LogTail", "boundary_warnings", "crashed_record", "dissolved_air_budget",
           "front_cell_warnings", "mass_balance", "rear_cell_warnings", "rear_meniscus_cell",
           "run_case", "steady_test"]

POLL_S = 1.0
STOP_GRACE_S = 120.0
DT_COLLAPSE = 1e-4          # time step below this fraction of maxDeltaT counts as collapse
DT_COLLAPSE_STEPS = 200     # ... for this many consecutive logged steps
#: end_reason of a run whose monitor was killed (found by the next reader)
MONITOR_KILLED = "monitor_killed"
CASE_REMOVED = "case_removed"
MONITOR_ERROR = "monitor_error"

#: called with each new sample of the run and the case's geometry
OnSample = Callable[[case_fields.Sample, CaseGeometry], None]


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


def crashed_record(case: Path, old: MetricsRecord | None = None) -> MetricsRecord | None:
    """``old`` (default: the case's metrics.json) as the record of a run that was killed, when
    it says ``running`` (call it when the run lock is free, or held by the caller): status
    ``interrupted``, end_reason ``monitor_killed`` and the reason; None otherwise."""
    if old is None:
        try:
            old = read_metrics(case)
        except (OSError, ValueError):
            return None
    if old.status != "running":
        return None
    return old.updated(status="interrupted", end_reason=MONITOR_KILLED,
                       reason="the process running the case was killed before the run ended "
                              "(metrics.json said running, no process held its run lock); "
                              "its last write is kept")


def settle_killed_run(case: str | os.PathLike) -> MetricsRecord | None:
    """Rewrite a ``metrics.json`` that a killed run left saying ``running`` (its run lock is
    free) as that run's end: :func:`crashed_record`. Returns the new record, or None when
    there was nothing to settle (no record, another status, a run holding the lock, a folder
    that cannot be written)."""
    path = Path(case)
    try:
        with hold_run_lock(path) as lock:
            return _settle_held(path) if lock is not None else None
    except (CaseBusy, OSError):
        return None


def _settle_held(path: Path) -> MetricsRecord | None:
    """With the run lock held: a 'running' metrics.json rewritten as the killed run's end
    (:func:`crashed_record`); returns that record, or None."""
    crashed = crashed_record(path)
    if crashed is not None:
        write_metrics(path, crashed)
    return crashed


def run_case(case: str | Path, runtime: FoamRuntime | None = None,
             wall_limit: float | None = None, on_sample: OnSample | None = None,
             extend_transits: float | None = None,
             on_note: Callable[[str], None] | None = None,
             oversubscribe: bool = False) -> MetricsRecord:
    """Run the case in ``case`` to steady state (or a limit) and write ``metrics.json``.

    Restarts from the latest written time if the case ran before. With ``extend_transits``
    the run goes on for that many transit times past the latest written time whatever the
    steady-state tests say (to see whether a steady state lasts, or to go on after a time
    limit); it then ends at ``end_time``, the wall limit or divergence. ``wall_limit`` [s]
    defaults to the spec's ``run.wall_limit``. ``on_note`` gets one line about anything
    found in the case before the run (an earlier run that was killed, a cut-short write
    removed). Returns the metrics record (as written). Raises :class:`CaseBusy` when another
    process runs the case, FileNotFoundError when ``case`` is no case folder.

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
    if not path.is_dir():
        raise FileNotFoundError(f"case folder {path} does not exist")
    if is_thin_film_case(path) and load_spec_of(path).supply.mode == "rig":
        from ehlfoam.run.cycle import run_cycle_case   # a cycle of passes (issue 75)
        return run_cycle_case(path, wall_limit=wall_limit, on_sample=on_sample, on_note=on_note,
                              extend_transits=extend_transits, crashed=crashed_record)
    if is_thin_film_case(path):   # the gap-averaged model, no solver (issue 74)
        return run_thin_film_case(path, wall_limit=wall_limit, on_sample=on_sample,
                                  extend_transits=extend_transits, crashed=crashed_record,
                                  on_note=on_note)
    run = _Case(path, load_spec_of(path), load_geometry(path),
                case_fields.Structure.load(path))
    check_n_procs(run.spec.run.n_procs, oversubscribe=oversubscribe)
    if extend_transits is not None:
        check_extension(run.spec, extend_transits, run.geom.transit_time,
                        run.geom.max_delta_t)
    with hold_run_lock(path) as lock:
        if _settle_held(path) is not None and on_note:
            on_note(f"the earlier run of {path} was killed before it ended (metrics.json "
                    f"said running, its run lock was free): marked interrupted "
                    f"({MONITOR_KILLED}); this run goes on from its latest write")
        if extend_transits is not None:
            _extend_end_time(path, run.geom, extend_transits)
        monitor = _Monitor(run, runtime=runtime or FoamRuntime.from_environment(),
                           wall_limit=wall_limit or run.spec.run.wall_limit,
                           on_sample=on_sample,
                           check_steady=extend_transits is None and run.spec.stop.at is None,
                           lock=lock, on_note=on_note)
        return monitor.run()


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


def _identity(path: Path) -> tuple[int, int] | None:
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_dev, st.st_ino


def _one_line(err: BaseException) -> str:
    return f"{type(err).__name__}: {' '.join(str(err).split())}"[:500]


class _Monitor:
    """One run of a case, from its start to its metrics.json (see :func:`run_case`)."""

    def __init__(self, run: _Case, *, runtime: FoamRuntime, wall_limit: float,
                 on_sample: OnSample | None, check_steady: bool, lock: IO[str] | None,
                 on_note: Callable[[str], None] | None = None):
        self.run_, self.runtime, self.wall_limit = run, runtime, wall_limit
        self.on_sample, self.check_steady, self.lock, self.on_note = (
            on_sample, check_steady, lock, on_note)
        self.history: list[case_fields.Sample] = []
        self.done: set[str] = set()
        self.reason: str | None = None
        self.detail: str | None = None
        self.steady_kind: str | None = None
        self.tested, self.steady_at, self.stop_at = 0, 0.0, math.nan
        self.proc: subprocess.Popen | None = None
        self.ident = _identity(run.path)
        geom = run.geom
        self.tail = LogTail(run.path / geom.log_name)
        self.dt_floor = DT_COLLAPSE * geom.max_delta_t
        self.t_start = time.monotonic()
        self.v0 = math.nan

    # ------------------------------------------------------------ the whole run
    def run(self) -> MetricsRecord:
        case, geom = self.run_.path, self.run_.geom
        write_metrics(case, MetricsRecord(status="running", cells=geom.cells))
        in_main = threading.current_thread() is threading.main_thread()
        previous = signal.getsignal(signal.SIGTERM) if in_main else None
        if in_main:
            signal.signal(signal.SIGTERM, _raise_interrupt)
        try:
            self._start()
            if self.proc is not None:
                self._watch()
        except KeyboardInterrupt:
            self.reason = "interrupted"
            try:
                self._stop_gracefully()
            except KeyboardInterrupt:   # a second Ctrl-C: stop waiting
                pass
        except Exception as err:  # noqa: BLE001 - the run ends failed, saying why
            self.reason, self.detail = MONITOR_ERROR, _one_line(err)
        finally:
            if in_main:
                signal.signal(signal.SIGTERM, previous if previous is not None
                              else signal.SIG_DFL)
            if self.proc is not None:
                if self.proc.poll() is None:
                    self.proc.kill()
                self.proc.wait()
        return self._finish()

    def _removed(self) -> bool:
        """The case folder is gone (or going: its spec or controlDict removed), or another
        folder now has its name."""
        case = self.run_.path
        return (_identity(case) != self.ident or not (case / META / "spec.json").is_file()
                or not (case / "system" / "controlDict").is_file())

    def _start(self) -> None:
        """Prepare the case and start the solver; a failure sets ``start_failed``."""
        run, case, geom = self.run_, self.run_.path, self.run_.geom
        _set_stop(case, "endTime")
        log_path = case / geom.log_name
        if log_path.exists():
            log_path.rename(case / f"{geom.log_name}.{int(time.time())}")
        try:
            self.history, self.done, removed = prepare_case(
                case, self.runtime, run.spec.run.n_procs, run.structure, geom)
            self.v0 = case_fields.initial_oil_volume(case, run.structure, geom)
        except StartFailed as err:
            self.reason, self.detail = START_FAILED, str(err)
            return
        if removed and self.on_note:
            self.on_note(f"removed the write(s) {', '.join(removed)} of {case}: cut short "
                         "(unreadable), the run goes on from the write before")
        self.tested = max(len(self.history) - 1, 0)
        keep = (self.lock.fileno(),) if self.lock is not None else ()
        try:
            self.proc = self.runtime.popen(geom.solver, [], cwd=case, log_path=geom.log_name,
                                           n_procs=run.spec.run.n_procs, keep_fds=keep)
        except FoamError as err:
            self.reason, self.detail = START_FAILED, " ".join(str(err).split())[:500]

    # ------------------------------------------------------------ watching
    def _watch(self) -> None:
        assert self.proc is not None
        spec, case = self.run_.spec, self.run_.path
        stopping_since: float | None = None
        n_procs = spec.run.n_procs
        while True:
            exited = self.proc.poll() is not None
            if self._removed():
                self.reason = CASE_REMOVED
                return
            self.tail.update(self.dt_floor)
            if n_procs > 1:
                reconstruct_new(case, self.runtime)
            self._collect(exited=exited)
            if exited:
                return
            over_wall = time.monotonic() - self.t_start > self.wall_limit
            if self.reason is None:
                if self._steady():
                    self.reason = "steady"
                    self._end_at_next_write()
                elif over_wall:
                    self.reason = "wall_limit"
                    _set_stop(case, "writeNow")
                    stopping_since = time.monotonic()
                elif self.tail.small_steps >= DT_COLLAPSE_STEPS:
                    self.reason = "diverged"
                    self.proc.kill()
            elif stopping_since is None and over_wall:   # a steady run still on its way
                _set_stop(case, "writeNow")
                stopping_since = time.monotonic()
            elif stopping_since and time.monotonic() - stopping_since > STOP_GRACE_S:
                self.proc.kill()
            time.sleep(POLL_S)

    def _steady(self) -> bool:
        """The steady-state test on every new write in turn (the first write that passes
        does not depend on how the polls fell)."""
        if not self.check_steady:
            return False
        spec, geom = self.run_.spec, self.run_.geom
        while self.tested < len(self.history):
            self.tested += 1
            passed = steady_test(self.history[:self.tested], geom.transit_time,
                                 spec.run.steady_tolerance, spec.run.transit_length)
            if passed:
                self.steady_kind = passed
                self.steady_at = self.history[self.tested - 1].time
                return True
        return False

    def _end_at_next_write(self) -> None:
        """controlDict's endTime at the write after the steady one (the solver stops at its
        next step): the run ends there, whenever the poll saw the steady write."""
        later = [t for t, _ in case_fields.time_folders(self.run_.path)
                 if t > self.steady_at * (1.0 + 1e-9)]
        self.stop_at = later[0] if later else self.steady_at
        with FoamFile(self.run_.path / "system" / "controlDict") as f:
            f["endTime"] = self.stop_at

    def _trim_past_stop(self) -> None:
        """Remove the writes a solver faster than the poll made past the steady stop (before
        it saw the new endTime), from the history too: the run ends at the stop."""
        t = self.stop_at * (1.0 + 1e-9)
        case = self.run_.path
        past = [folder for u, folder in case_fields.time_folders(case) if u > t]
        for proc in sorted(case.glob("processor*")):
            past += [folder for u, folder in case_fields.time_folders(proc) if u > t]
        for folder in past:
            shutil.rmtree(folder, ignore_errors=True)
        kept = [s for s in self.history if s.time <= t]
        if len(kept) != len(self.history):
            self.history = kept
            write_history(case, self.history)

    def _stop_gracefully(self) -> None:
        if self.proc is None or self.proc.poll() is not None or self._removed():
            return
        _set_stop(self.run_.path, "writeNow")
        try:
            self.proc.wait(timeout=STOP_GRACE_S)
        except subprocess.TimeoutExpired:
            self.proc.kill()

    def _collect(self, *, exited: bool) -> None:
        """Sample the time folders not read yet into the history and rewrite history.csv.

        While the solver runs, a folder is read only once the solver has moved on to the next
        one (a half-written field must never reach the parser) and a failed read is retried
        at the next poll; once it has exited, every folder is read once and unreadable ones
        are skipped.
        """
        run, case, geom = self.run_, self.run_.path, self.run_.geom
        folders = case_fields.time_folders(case)
        new = False
        for k, (_, folder) in enumerate(folders):
            if folder.name in self.done:
                continue
            if not exited and k == len(folders) - 1:
                break
            try:
                s = case_fields.sample(folder, run.structure, geom)
            except Exception:  # noqa: BLE001 - still being written: next poll
                if exited:
                    self.done.add(folder.name)
                continue
            self.done.add(folder.name)
            self.history.append(s)
            new = True
            if self.on_sample:
                self.on_sample(s, geom)
        if new:
            write_history(case, self.history)

    # ------------------------------------------------------------ the end
    def _finish(self) -> MetricsRecord:
        run, case, geom = self.run_, self.run_.path, self.run_.geom
        wall = time.monotonic() - self.t_start
        rc = self.proc.returncode if self.proc is not None else None
        if self._removed():
            self.reason = CASE_REMOVED
            return MetricsRecord(status="failed", end_reason=CASE_REMOVED, cells=geom.cells,
                                 time_steps=self.tail.steps, wall_s=wall,
                                 reason=f"the case folder {case} was removed (or replaced) "
                                        "while it ran: the solver was stopped, nothing written")
        try:
            self.tail.update(self.dt_floor)
            if self.proc is not None and run.spec.run.n_procs > 1:   # the last writes
                reconstruct_new(case, self.runtime)
            # one more sample pass: a run stopped by a signal left the loop before its last
            # writes
            self._collect(exited=True)
        except Exception as err:  # noqa: BLE001
            if self.reason is None:
                self.reason, self.detail = MONITOR_ERROR, _one_line(err)
        steps, last_dt = self.tail.steps, self.tail.last_dt
        if self.reason == "steady" and rc == 0 and math.isfinite(self.stop_at):
            self._trim_past_stop()
            steps, last_dt = self.tail.steps_until(self.stop_at)
        reason = self.reason
        if reason is None:
            if rc == 0:
                reason = "end_time"
            elif self.tail.steps == 0:
                reason = START_FAILED
                self.detail = (f"{geom.solver} stopped before its first time step (exit code "
                               f"{rc}): {self._log_reason()}")
            else:
                reason = "diverged"
        failed = reason in ("diverged", START_FAILED, MONITOR_ERROR) or (
            rc not in (0, None, -9) and reason != "interrupted")
        end = RunEnd(reason=reason, failed=failed, exit_code=rc, time_steps=steps,
                     last_delta_t=last_dt, wall_s=wall,
                     steady_test=self.steady_kind)
        try:
            record = final_record(case, run.spec, geom, run.structure,
                                  initial_oil=self.v0, history=self.history, end=end)
        except Exception as err:  # noqa: BLE001 - still say how the run ended
            record = MetricsRecord(status=end.status, end_reason=reason, cells=geom.cells,
                                   solver_exit_code=rc, time_steps=self.tail.steps, wall_s=wall,
                                   reason=f"metrics could not be computed: {_one_line(err)}")
        if self.detail:
            record = record.updated(reason=self.detail)
        write_metrics(case, record)
        return record

    def _log_reason(self) -> str:
        try:
            text = (self.run_.path / self.run_.geom.log_name).read_text(errors="replace")
        except OSError:
            return "no solver log"
        return failure_from_log(text) or "an empty solver log"


def _raise_interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt
