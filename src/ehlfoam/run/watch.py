"""One run of a 3D case's solver, watched from outside (:func:`ehlfoam.run.monitor.run_case`
starts it; the end reasons are listed there).

The case is prepared and its solver started as a child process (:mod:`ehlfoam.run.start`);
every poll reads the time folders it has written into the history (``DIR/history.csv``),
applies the steady-state test to each new write in turn, and watches the wall limit, the
time step (:class:`~ehlfoam.run.logtail.LogTail`) and a solver that hangs. A steady run ends
at the next scheduled write (controlDict's ``endTime`` set to it); a wall limit or an
interrupt stops the solver at once (``stopAt writeNow``); a hung solver is killed
(:data:`HANG_POLLS`). Once the solver has exited, :mod:`ehlfoam.run.finish` writes what the
run leaves.
"""

from __future__ import annotations

import math
import os
import signal
import subprocess
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import IO

from foamlib import FoamFile

from ehlfoam.case.geometry import META, CaseGeometry
from ehlfoam.foam.cpu import tree_cpu_s
from ehlfoam.foam.runtime import FoamError, FoamRuntime
from ehlfoam.metrics.record import MetricsRecord, write_metrics
from ehlfoam.run import fields as case_fields
from ehlfoam.run.final import RunEnd
from ehlfoam.run.finish import (CASE_REMOVED, MONITOR_ERROR, end_reason, one_line,
                                removed_record, trim_past_stop, write_end)
from ehlfoam.run.history import write_history
from ehlfoam.run.logtail import LogTail
from ehlfoam.run.start import START_FAILED, StartFailed, prepare_case, reconstruct_new
from ehlfoam.run.steady import steady_test
from ehlfoam.spec.case import CaseSpec

__all__ = ["DT_COLLAPSE", "DT_COLLAPSE_STEPS", "HANG_POLLS", "OnSample", "POLL_S",
           "STOP_GRACE_S", "SolverWatch", "WatchedCase", "set_stop"]

POLL_S = 1.0
STOP_GRACE_S = 120.0
DT_COLLAPSE = 1e-4          # time step below this fraction of maxDeltaT counts as collapse
DT_COLLAPSE_STEPS = 200     # ... for this many consecutive logged steps
#: a solver still for this many polls in a row hangs, and is killed: its log did not grow,
#: and it either used no CPU or had begun a backtrace (a crash handler; printing one takes
#: well under a second). A signal that lands inside the C library (a write, a malloc) can
#: leave OpenFOAM's handler waiting forever on a lock the interrupted code holds, before or
#: while it prints; the solver would hold its case to the wall limit. Counted in polls, not
#: seconds: a watch stopped with its solver (Ctrl-Z) and resumed counts from where it was.
HANG_POLLS = 20
_CPU_ADVANCE_S = 0.02       # less CPU than this between two polls is none

#: called with each new sample of the run and the case's geometry
OnSample = Callable[[case_fields.Sample, CaseGeometry], None]


@dataclass(frozen=True)
class WatchedCase:
    """A generated case: its folder, spec, geometry and mesh structure."""

    path: Path
    spec: CaseSpec
    geom: CaseGeometry
    structure: case_fields.Structure


def set_stop(case: Path, value: str) -> None:
    """controlDict's ``stopAt`` set to ``value`` (``endTime``, ``writeNow``)."""
    with FoamFile(case / "system" / "controlDict") as f:
        f["stopAt"] = value


def _identity(path: Path) -> tuple[int, int] | None:
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_dev, st.st_ino


def _raise_interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


class SolverWatch:
    """One run of a case, from its start to its metrics.json (see
    :func:`ehlfoam.run.monitor.run_case`)."""

    def __init__(self, run: WatchedCase, *, runtime: FoamRuntime, wall_limit: float,
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
        self.hang_s: float | None = None
        self._still_polls, self._cpu_s = 0, None
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
            self.reason, self.detail = MONITOR_ERROR, one_line(err)
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
        set_stop(case, "endTime")
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
            if self.hang_s is None and self._hung():
                self.hang_s = HANG_POLLS * POLL_S
                self.proc.kill()      # the next poll finds it exited
            over_wall = time.monotonic() - self.t_start > self.wall_limit
            if self.reason is None:
                if self._steady():
                    self.reason = "steady"
                    self._end_at_next_write()
                elif over_wall:
                    self.reason = "wall_limit"
                    set_stop(case, "writeNow")
                    stopping_since = time.monotonic()
                elif self.tail.small_steps >= DT_COLLAPSE_STEPS:
                    self.reason = "diverged"
                    self.proc.kill()
            elif stopping_since is None and over_wall:   # a steady run still on its way
                set_stop(case, "writeNow")
                stopping_since = time.monotonic()
            elif stopping_since and time.monotonic() - stopping_since > STOP_GRACE_S:
                self.proc.kill()
            time.sleep(POLL_S)

    def _hung(self) -> bool:
        """The solver has been still for :data:`HANG_POLLS` polls in a row (this one
        included): its log did not grow, and it used no CPU or had begun a backtrace."""
        cpu, last = tree_cpu_s(self.proc.pid), self._cpu_s
        self._cpu_s = cpu
        idle = cpu is not None and last is not None and cpu - last < _CPU_ADVANCE_S
        still = not self.tail.grew and (self.tail.backtrace or idle)
        self._still_polls = self._still_polls + 1 if still else 0
        return self._still_polls >= HANG_POLLS

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

    def _stop_gracefully(self) -> None:
        if self.proc is None or self.proc.poll() is not None or self._removed():
            return
        set_stop(self.run_.path, "writeNow")
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
        """The solver has exited: its last writes sampled, and what the run leaves written
        (:mod:`ehlfoam.run.finish`)."""
        run, case, geom = self.run_, self.run_.path, self.run_.geom
        wall = time.monotonic() - self.t_start
        rc = self.proc.returncode if self.proc is not None else None
        if self._removed():
            self.reason = CASE_REMOVED
            return removed_record(case, geom, self.tail.steps, wall)
        try:
            self.tail.update(self.dt_floor)
            if self.proc is not None and run.spec.run.n_procs > 1:   # the last writes
                reconstruct_new(case, self.runtime)
            # one more sample pass: a run stopped by a signal left the loop before its last
            # writes
            self._collect(exited=True)
        except Exception as err:  # noqa: BLE001
            if self.reason is None:
                self.reason, self.detail = MONITOR_ERROR, one_line(err)
        steps, last_dt = self.tail.steps, self.tail.last_dt
        if self.reason == "steady" and rc == 0 and math.isfinite(self.stop_at):
            self.history = trim_past_stop(case, self.history, self.stop_at)
            steps, last_dt = self.tail.steps_until(self.stop_at)
        reason, failed, detail = end_reason(self.reason, self.detail, exit_code=rc,
                                            logged_steps=self.tail.steps, case=case, geom=geom,
                                            hang_s=self.hang_s)
        end = RunEnd(reason=reason, failed=failed, exit_code=rc, time_steps=steps,
                     last_delta_t=last_dt, wall_s=wall, steady_test=self.steady_kind)
        return write_end(case, run.spec, geom, run.structure, initial_oil=self.v0,
                         history=self.history, end=end, detail=detail,
                         logged_steps=self.tail.steps)
