"""One planned case of a batch, in this process: its EHL precalc (solved once per contact, a
file lock per contact guarding the cache across processes), its build, its ramp start, its run,
and its metrics.json completed with the batch's keys, or a failure record.

A case is built and run holding ``locks/<id>.lock``; its status is read again under that lock
before anything is touched. A finished case is never rebuilt; anything not finished or failed
is rebuilt from scratch and run from t = 0, so that a result never mixes two runs. Failures (a
build error, a diverged solver) are recorded in metrics.json (``status: failed``, ``reason``)
and the traceback in error.log; they never raise.
"""

from __future__ import annotations

import shutil
import time
import traceback
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from ehlfoam._io import atomic_write_text
from ehlfoam.batch.folder import (CASES, LOCKS, RESULTS, SPEC_COPY, STARTS, case_status,
                                  file_lock, metrics_or_none)
from ehlfoam.batch.plan import PlannedCase, load_plan
from ehlfoam.metrics.record import MetricsRecord, write_metrics

#: How long a worker waits for a case still held by a stopping process (the solver's
#: graceful stop takes up to ehlfoam.run.watch.STOP_GRACE_S = 120 s).
LOCK_WAIT_S = 180.0

_PLAN_CACHE: dict[str, tuple[tuple, dict[str, PlannedCase]]] = {}


def plan_index(batch_dir: Path, case_id: str | None = None) -> dict[str, PlannedCase]:
    """The batch folder's plan (from its batch.toml), by case id, with the 3D confirmations
    of its finished thin-film map (:mod:`ehlfoam.batch.confirm`); cached per process until
    batch.toml changes or ``case_id`` is not in it."""
    from ehlfoam.batch.confirm import confirm_plan
    from ehlfoam.batch.results import read_results

    path = Path(batch_dir) / SPEC_COPY
    st = path.stat()
    stamp = (st.st_mtime_ns, st.st_size)
    hit = _PLAN_CACHE.get(str(path))
    if hit and hit[0] == stamp and (case_id is None or case_id in hit[1]):
        return hit[1]
    batch, plan = load_plan(path)
    index = {pc.id: pc for pc in plan}
    if batch.confirm is not None and (Path(batch_dir) / RESULTS).is_file():
        rows = read_results(Path(batch_dir))
        index.update((pc.id, pc) for pc in confirm_plan(batch, plan, rows, Path(batch_dir)))
    _PLAN_CACHE[str(path)] = (stamp, index)
    return index


@contextmanager
def _precalc_lock(contact) -> Iterator[None]:
    """One process at a time solves a given contact (the cache is per machine)."""
    from ehlfoam.gap.source import spec_key
    from ehlfoam.paths import cache_dir

    with file_lock(cache_dir() / "precalc" / f".{spec_key(contact)}.lock", timeout=1e9):
        yield


def precalc_cached(contact) -> bool:
    """True if the contact's EHL precalc is in this machine's cache."""
    from ehlfoam.gap.source import spec_key
    from ehlfoam.paths import cache_dir

    return (cache_dir() / "precalc" / spec_key(contact) / "summary.json").is_file()


def ensure_precalc(batch_dir: Path, case_id: str) -> dict:
    """Solve (or find) the EHL precalc of a case's contact; a non-converged one is cached
    too (the case build then fails with the precalc's message)."""
    from ehlfoam.gap.source import precalc_dir

    contact = plan_index(batch_dir, case_id)[case_id].spec.contact
    t0 = time.monotonic()
    try:
        with _precalc_lock(contact):
            precalc_dir(contact, require_converged=False)
    except Exception as err:  # noqa: BLE001 - the case build reports it
        return {"id": case_id, "kind": "precalc", "status": "failed", "reason": oneline(err)}
    return {"id": case_id, "kind": "precalc", "status": "finished",
            "wall_s": time.monotonic() - t0}


def oneline(err: BaseException) -> str:
    """An exception as one line of at most 500 characters (for metrics.json and the log)."""
    text = " ".join(str(err).split())
    return f"{type(err).__name__}: {text}"[:500]


def _clean_stale_builds(case: Path) -> None:
    """Temporary folders of an interrupted write_case (``.ID.xxxx`` next to the case)."""
    for tmp in case.parent.glob(f".{case.name}.*"):
        if tmp.is_dir():
            shutil.rmtree(tmp, ignore_errors=True)


#: What a build that failed before its case was written leaves in the case's folder.
_FAILURE_FILES = {"metrics.json", "error.log"}


def _clear_failed_build(case: Path) -> None:
    """Remove the failure record of a build that never wrote its case (metrics.json and
    error.log alone), so that the folder can take the case; anything else stays (and the
    case writer refuses a folder that is not its own)."""
    from ehlfoam.case.ownership import is_own_case

    if not case.is_dir() or is_own_case(case):
        return
    entries = list(case.iterdir())
    if entries and all(p.is_file() and p.name in _FAILURE_FILES for p in entries):
        for p in entries:
            p.unlink()


def execute_case(batch_dir: Path, case_id: str, rerun_failed: bool = False) -> dict:
    """Build and run one case of the batch in this process (under its lock) and complete its
    metrics.json. A finished case is left alone; a failed one unless ``rerun_failed``."""
    from ehlfoam.case.writer import CaseBeingRun, write_case
    from ehlfoam.gap.source import precalc_dir
    from ehlfoam.run.monitor import CaseBusy, run_case

    from ehlfoam.seed.follow import following_spec
    from ehlfoam.seed.ladder import keep_start, thin_film_start
    from ehlfoam.seed.start import seed_case

    pc = plan_index(batch_dir, case_id)[case_id]
    case = batch_dir / CASES / case_id
    with file_lock(batch_dir / LOCKS / f"{case_id}.lock", timeout=LOCK_WAIT_S) as got:
        if not got:
            return {"id": case_id, "kind": "case", "status": "busy",
                    "reason": "held by another process"}
        status = case_status(case)
        if status == "finished" or (status == "failed" and not rerun_failed):
            return {"id": case_id, "kind": "case", "status": status, "skipped": True}
        if status == "running":   # an `ehlfoam run` outside the batch
            return {"id": case_id, "kind": "case", "status": "busy",
                    "reason": "run by another process"}
        _clean_stale_builds(case)
        t0 = time.monotonic()
        stage, build_s, seed = "build", None, None
        try:
            with _precalc_lock(pc.spec.contact):
                precalc_dir(pc.spec.contact, require_converged=False)
            source = None
            if pc.ramp and pc.ramp.get("previous"):
                stage = "ramp start"
                source = batch_dir / CASES / pc.ramp["previous"]
                if case_status(source) != "finished":
                    raise RuntimeError(f"the previous ramp step {source.name} is not "
                                       f"finished ({case_status(source)})")
            elif pc.ramp and pc.ramp.get("start_from"):   # the first step: a case or state
                source = pc.ramp["start_from"]
            kept = source is None and pc.spec.run.start == "thin-film" \
                and pc.spec.scene != "thin-film"
            if kept:   # the thin-film balance of the point (ehlfoam.seed.ladder)
                stage = "thin-film start"
                source = thin_film_start(pc.spec, batch_dir / STARTS / case_id)
            stage = "build"   # with mesh.follow, along the source's meniscus
            _clear_failed_build(case)
            seeded: list[dict] = []

            def start(tmp: Path) -> None:   # in the built case, before it is put in place
                nonlocal stage
                stage = "ramp start"
                seeded.append(seed_case(tmp, source))
                if kept:
                    keep_start(source, tmp)

            write_case(following_spec(pc.spec, source), case, overwrite=True,
                       prepare=None if source is None else start)
            seed = seeded[0] if seeded else None
            build_s = time.monotonic() - t0
            stage = "run"
            # the batch fitted run.n_procs to its cores (--cores, --jobs, --oversubscribe)
            # or to its Dask workers' CPU resources already
            metrics = run_case(case, oversubscribe=True)
        except (CaseBusy, CaseBeingRun) as err:   # an `ehlfoam run` outside the batch
            return {"id": case_id, "kind": "case", "status": "busy", "reason": str(err)}
        except Exception as err:  # noqa: BLE001 - recorded, the batch goes on
            metrics = _record_failure(case, case_id, stage, err, t0)
            return {"id": case_id, "kind": "case", "status": "failed",
                    "reason": metrics.reason}
        metrics = _complete_metrics(case, metrics, case_id, build_s, seed, t0)
        return {"id": case_id, "kind": "case", "status": metrics.status,
                "reason": metrics.reason or ""}


def _failed(old: MetricsRecord | None, **values) -> MetricsRecord:
    """A ``failed`` record: ``old``'s keys but its status, then ``values``."""
    kept = {k: v for k, v in old.to_json().items() if k != "status"} if old else {}
    return MetricsRecord.model_validate({**kept, "status": "failed", **values})


def _record_failure(case: Path, case_id: str, stage: str, err: Exception,
                    t0: float) -> MetricsRecord:
    """metrics.json ``failed`` with the reason, and the traceback in error.log."""
    case.mkdir(parents=True, exist_ok=True)
    atomic_write_text(case / "error.log", traceback.format_exc())
    old = metrics_or_none(case)
    keep = old if old is not None and old.status == "running" else None   # this attempt's
    metrics = _failed(keep, end_reason=f"{stage.replace(' ', '_').replace('-', '_')}_error",
                      reason=f"{stage}: {oneline(err)}", case_id=case_id,
                      case_wall_s=time.monotonic() - t0)
    write_metrics(case, metrics)
    return metrics


def _failure_reason(metrics: MetricsRecord) -> str:
    if metrics.status != "failed":
        return ""
    tail = [ln.strip() for ln in metrics.log_tail or [] if ln.strip()]
    last = tail[-1] if tail else ""
    return (f"solver {metrics.end_reason} (exit code {metrics.solver_exit_code})"
            + (f": {last[:300]}" if last else ""))


def _complete_metrics(case: Path, metrics: MetricsRecord, case_id: str,
                      build_s: float | None, seed: dict | None, t0: float) -> MetricsRecord:
    """Add the batch's keys to the run's metrics.json (written once, by its own worker)."""
    extra = {"case_id": case_id, "build_wall_s": build_s,
             "case_wall_s": time.monotonic() - t0}
    if seed:
        extra["ramp_start_method"] = seed["method"]
        extra["ramp_start_time_s"] = seed["previous_time_s"]
    reason = _failure_reason(metrics)
    if reason:
        extra["reason"] = reason
    metrics = metrics.updated(**extra)
    write_metrics(case, metrics)
    return metrics


def record_worker_lost(case: Path, case_id: str, reason: str) -> None:
    """metrics.json ``failed`` (``worker_lost``): the process running the case died."""
    case.mkdir(parents=True, exist_ok=True)
    write_metrics(case, _failed(metrics_or_none(case), end_reason="worker_lost",
                                reason=reason, case_id=case_id))

