"""A run whose monitor was killed (SIGKILL) before it ended: its ``metrics.json`` still says
``running`` while no process holds the case's run lock (:mod:`ehlfoam.case.ownership`). The
next run, report or batch that finds it rewrites it as that run's end: status
``interrupted``, end_reason ``monitor_killed``; the run's last write is kept."""

from __future__ import annotations

import os
from pathlib import Path

from ehlfoam.case.ownership import CaseBusy, hold_run_lock
from ehlfoam.metrics.record import MetricsRecord, read_metrics, write_metrics

__all__ = ["MONITOR_KILLED", "crashed_record", "settle_held", "settle_killed_run"]

#: end_reason of a run whose monitor was killed (found by the next reader)
MONITOR_KILLED = "monitor_killed"


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
            return settle_held(path) if lock is not None else None
    except (CaseBusy, OSError):
        return None


def settle_held(path: Path) -> MetricsRecord | None:
    """With the run lock held: a 'running' metrics.json rewritten as the killed run's end
    (:func:`crashed_record`); returns that record, or None."""
    crashed = crashed_record(path)
    if crashed is not None:
        write_metrics(path, crashed)
    return crashed
