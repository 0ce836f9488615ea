"""The batch folder: its layout, its file locks, and each case's status from its metrics.json.

Layout of a batch folder (``runs/NAME/`` for ``runs/NAME.toml``)::

    batch.toml          verbatim copy of the batch spec
    plan.json           the expanded plan: [{"id", "params", "ramp"}, ...]; params: the case
                        spec's dotted keys in SI (ehlfoam.batch.plan)
    cases/<id>/         one case each (ehlfoam.case.writer.write_case + ehlfoam.run.monitor.run_case):
                        metrics.json (the single source of truth), history.csv, log.interFoam
    results.csv         one row per planned case, rebuilt atomically from the metrics.json files
                        (ehlfoam.batch.results)
    regime/             regime.json: the regime analysis (ehlfoam.batch.regime), SI
    report/             the batch report (ehlfoam.report), with the regime pictures
    starts/<id>/        the thin-film balance a 3D case with run.start = "thin-film" starts
                        from (ehlfoam.seed.ladder; reused when the batch resumes)
    locks/<id>.lock     held by the process that builds and runs the case
    batch.lock          held by the ``ehlfoam batch`` process
"""

from __future__ import annotations

import fcntl
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from ehlfoam.case.ownership import lock_held
from ehlfoam.metrics.record import MetricsRecord, read_metrics

SPEC_COPY, PLAN, RESULTS, CASES, LOCKS, STARTS = (
    "batch.toml", "plan.json", "results.csv", "cases", "locks", "starts")
BATCH_LOCK = "batch.lock"
STATUSES = ("pending", "running", "finished", "failed", "interrupted")


def batch_folder(spec_path: Path, out: Path | None) -> Path:
    """``--out``, else ``runs/STEM/`` in the working directory for a spec ``STEM.toml``
    (outputs never land beside the spec, which may sit in the package's examples)."""
    return Path(out) if out else Path("runs") / spec_path.stem


@contextmanager
def file_lock(path: Path, timeout: float = 0.0, shared: bool = False) -> Iterator[bool]:
    """Hold an flock on ``path`` (created if needed); yields False if it stayed busy for
    ``timeout`` seconds."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fh = open(path, "a+")
    mode = (fcntl.LOCK_SH if shared else fcntl.LOCK_EX) | fcntl.LOCK_NB
    deadline = time.monotonic() + timeout
    try:
        while True:
            try:
                fcntl.flock(fh, mode)
                break
            except BlockingIOError:
                if time.monotonic() >= deadline:
                    yield False
                    return
                time.sleep(0.2)
        yield True
    finally:
        fh.close()


def lock_is_held(path: Path) -> bool:
    """True if another process holds an flock on ``path`` (probe, released at once)."""
    return lock_held(path)


def metrics_or_none(case: Path) -> MetricsRecord | None:
    """The case's metrics record, or None (no metrics.json, or not a readable record)."""
    try:
        return read_metrics(case)
    except (FileNotFoundError, ValueError):
        return None


def case_status(case: Path, live: bool = False) -> str:
    """pending / running / finished / failed / interrupted, from metrics.json.

    ``live``: this batch process has the case in flight (its lock is not probed then, so
    that a probe can never collide with the worker taking it)."""
    m = metrics_or_none(case)
    status = m.status if m else None
    if status in ("finished", "failed"):
        return status
    if live:
        return "running"
    if status == "running":
        from ehlfoam.case.geometry import META

        return "running" if lock_is_held(case / META / "run.lock") else "interrupted"
    return "interrupted" if status == "interrupted" else "pending"
