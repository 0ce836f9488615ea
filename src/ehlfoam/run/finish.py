"""The end of a 3D run, once its solver has exited: the writes past a steady stop removed, the
reason it ended (where the watch found none: the solver's exit says it), and what it leaves in
the case folder: ``outflow.csv`` (the layers its outlet's oil lays on the tracks,
:mod:`ehlfoam.run.outflow`) and ``metrics.json`` (:func:`ehlfoam.run.final.final_record`).
The end reasons are listed in :mod:`ehlfoam.run.monitor`."""

from __future__ import annotations

import re
import shutil
import signal
from pathlib import Path

from ehlfoam._io import tail_lines
from ehlfoam.case.geometry import CaseGeometry
from ehlfoam.metrics.record import MetricsRecord, write_metrics
from ehlfoam.run import fields as case_fields
from ehlfoam.run.final import RunEnd, final_record
from ehlfoam.run.history import write_history
from ehlfoam.run.outflow import write_outflow
from ehlfoam.run.start import START_FAILED, failure_from_log
from ehlfoam.spec.case import CaseSpec

__all__ = ["CASE_REMOVED", "CRASHED", "MONITOR_ERROR", "end_reason", "one_line",
           "removed_record", "trim_past_stop", "write_end"]

CASE_REMOVED = "case_removed"
CRASHED = "crashed"
MONITOR_ERROR = "monitor_error"
#: The signal the solver's log names: UCX's handler ("Caught signal 11 (Segmentation fault:
#: ...") in every solver of the runtime, mpirun ("exited on signal 11 (Segmentation fault)").
_SIGNAL_LINE = re.compile(r"(?:Caught|exited on) signal (\d+) \(([^:)]*)")
#: OpenFOAM's own handlers, in the second frame of the backtrace they print
_HANDLER_FRAME = re.compile(r"Foam::sig(Fpe|Segv|Quit)::sigHandler")
_HANDLED = {"Fpe": signal.SIGFPE, "Segv": signal.SIGSEGV, "Quit": signal.SIGQUIT}


def one_line(err: BaseException) -> str:
    """``err`` as one line of at most 500 characters, its type first."""
    return f"{type(err).__name__}: {' '.join(str(err).split())}"[:500]


def removed_record(case: Path, geom: CaseGeometry, time_steps: int,
                   wall_s: float) -> MetricsRecord:
    """The record of a run whose case folder was removed (or replaced) while it ran; nothing
    is written (there is no folder to write to). ``wall_s`` [s]."""
    return MetricsRecord(status="failed", end_reason=CASE_REMOVED, cells=geom.cells,
                         time_steps=time_steps, wall_s=wall_s,
                         reason=f"the case folder {case} was removed (or replaced) "
                                "while it ran: the solver was stopped, nothing written")


def trim_past_stop(case: Path, history: list[case_fields.Sample],
                   stop_at: float) -> list[case_fields.Sample]:
    """Remove the writes a solver faster than the poll made past the steady stop at
    ``stop_at`` [s] (before it saw the new endTime), from the history too (history.csv
    rewritten where that changed it): the run ends at the stop. Returns the history kept."""
    t = stop_at * (1.0 + 1e-9)
    past = [folder for u, folder in case_fields.time_folders(case) if u > t]
    for proc in sorted(case.glob("processor*")):
        past += [folder for u, folder in case_fields.time_folders(proc) if u > t]
    for folder in past:
        shutil.rmtree(folder, ignore_errors=True)
    kept = [s for s in history if s.time <= t]
    if len(kept) != len(history):
        write_history(case, kept)
    return kept


def end_reason(reason: str | None, detail: str | None, *, exit_code: int | None,
               logged_steps: int, case: Path, geom: CaseGeometry,
               hang_s: float | None = None) -> tuple[str, bool, str | None]:
    """The run's end reason, whether it failed, and the words that say why (``detail``
    unless the end is found only now). ``reason``: the one the watch found, or None: then
    the solver's exit says it (0: ``end_time``; no time step logged: ``start_failed``, with
    the log's words; killed by a signal other than a floating-point trap: ``crashed``, the
    signal named; otherwise ``diverged``, with the log's words). A solver the watch killed
    as hung, after ``hang_s`` [s] still, ended on the signal its log names (a crash handler
    that hung), not on the kill; ``crashed`` where the log names none."""
    if reason is None:
        if exit_code == 0:
            reason = "end_time"
        elif logged_steps == 0:
            reason = START_FAILED
            detail = (f"{geom.solver} stopped before its first time step (exit code "
                      f"{exit_code}): {_log_reason(case, geom)}")
        else:
            reason, detail = _failure(exit_code, logged_steps, case, geom, hang_s)
    failed = reason in ("diverged", CRASHED, START_FAILED, MONITOR_ERROR) or (
        exit_code not in (0, None, -9) and reason != "interrupted")
    return reason, failed, detail


def _failure(exit_code: int | None, logged_steps: int, case: Path, geom: CaseGeometry,
             hang_s: float | None) -> tuple[str, str]:
    """(``crashed`` or ``diverged``, why) for a solver that failed after its first steps."""
    tail = "\n".join(tail_lines(case / geom.log_name))   # the signal, the error
    sig = _signal(None if hang_s else exit_code, tail)
    after = f"after {logged_steps} time steps"
    hung = (f"; it then hung in its crash handler: still for {hang_s:g} s, killed"
            if hang_s else "")
    if sig is not None and sig[0] != signal.SIGFPE:
        return CRASHED, (f"{geom.solver} was killed by signal {sig[0]} ({sig[1]}) {after}: "
                         "a crash (memory, MPI, a library), not a floating-point trap of the "
                         f"numerics; the log has its backtrace{hung}")
    if sig is None and hang_s:
        return CRASHED, (f"{geom.solver} hung {after}: its log and its CPU time were still "
                         f"for {hang_s:g} s (a crash handler waiting on a lock, a deadlock; "
                         "the signal, if any, is not known), killed")
    how = (f"signal {sig[0]} ({sig[1]}), a floating-point trap" if sig else
           _fatal_error(tail) or f"exit code {exit_code}")
    return "diverged", f"{geom.solver} failed {after}: {how}{hung}"


def _fatal_error(log: str) -> str | None:
    """The ``FOAM FATAL ERROR`` of the solver log's text ``log`` in one line, None without
    one."""
    return failure_from_log(log) if "FOAM FATAL" in log else None


def _signal(exit_code: int | None, log: str) -> tuple[int, str] | None:
    """The signal (number, name) that killed the solver: read from its log's text ``log``
    (its tail: a signal line, else the OpenFOAM handler in its backtrace), else from its exit
    code (negative: the signal; above 128: 128 + the signal, as a shell or mpirun passes it
    on). None for an error exit."""
    found = _SIGNAL_LINE.findall(log)
    if found:
        return int(found[0][0]), found[0][1].strip()
    handler = _HANDLER_FRAME.search(log)
    if handler:
        return _named(_HANDLED[handler.group(1)])
    if exit_code is not None and (exit_code < 0 or 128 < exit_code < 160):
        return _named(-exit_code if exit_code < 0 else exit_code - 128)
    return None


def _named(number: int) -> tuple[int, str]:
    """(``number``, the signal's name)."""
    try:
        return number, signal.strsignal(number) or f"signal {number}"
    except ValueError:
        return number, f"signal {number}"


def _log_reason(case: Path, geom: CaseGeometry) -> str:
    try:
        text = (case / geom.log_name).read_text(errors="replace")
    except OSError:
        return "no solver log"
    return failure_from_log(text) or "an empty solver log"


def write_end(case: Path, spec: CaseSpec, geom: CaseGeometry,
              structure: case_fields.Structure, *, initial_oil: float,
              history: list[case_fields.Sample], end: RunEnd, detail: str | None,
              logged_steps: int) -> MetricsRecord:
    """Write what the run leaves, whatever its end: ``outflow.csv`` where it wrote a time
    past the start (none without an outlet or a readable write), then ``metrics.json``, the
    record of its ``history`` (``initial_oil`` [m3, whole contact]; ``detail``, where given,
    its reason). A record that cannot be computed still says how the run ended
    (``logged_steps``: the time steps the solver log shows). Returns the record."""
    if history and history[-1].time > 0:
        try:
            write_outflow(case)
        except Exception:  # noqa: BLE001 - no outlet or no readable time: no profile,
            pass           # the record stands
    try:
        record = final_record(case, spec, geom, structure,
                              initial_oil=initial_oil, history=history, end=end)
    except Exception as err:  # noqa: BLE001 - still say how the run ended
        record = MetricsRecord(status=end.status, end_reason=end.reason, cells=geom.cells,
                               solver_exit_code=end.exit_code, time_steps=logged_steps,
                               wall_s=end.wall_s,
                               reason=f"metrics could not be computed: {one_line(err)}")
    if detail:
        record = record.updated(reason=detail)
    write_metrics(case, record)
    return record
