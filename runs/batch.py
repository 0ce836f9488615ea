"""Run a batch of cases: plan -> cases, on local processes or on Dask; resume; results.csv.

Layout of a batch folder (``runs/NAME/`` for ``runs/NAME.toml``)::

    batch.toml          verbatim copy of the batch spec
    plan.json           the expanded plan: [{"id", "params", "ramp"}, ...]
    cases/<id>/         one case each (generator.case_writer.write_case + runs.run_case.run_case):
                        metrics.json (the single source of truth), history.csv, log.interFoam
    results.csv         one row per planned case, rebuilt atomically from the metrics.json files
    regime/             regime-map PNGs and regime.json (runs/regime.py)
    locks/<id>.lock     held by the process that builds and runs the case
    batch.lock          held by the ``ehlfoam batch`` process

Rules:

- **Resume.** A case whose metrics.json says ``finished`` is never rebuilt or rewritten (and if
  the batch spec now gives it another case spec, the batch stops before anything is built).
  ``failed`` cases are re-run only with ``rerun_failed``. Everything else (no metrics.json,
  ``interrupted``, ``running`` without a live process) is rebuilt from scratch and run from
  t = 0, so that a result never mixes two runs.
- **Safety.** Each case is built and run in a worker process holding ``locks/<id>.lock``; the
  worker re-reads the case's status under that lock before touching it. results.csv is
  rewritten (temporary file + rename) from the metrics.json files after every case, so a kill
  can neither duplicate nor lose rows. Ctrl-C or SIGTERM stop the workers gracefully (the
  solver writes its last time, metrics.json says ``interrupted``); workers and solvers also
  stop when the batch process is killed (SIGKILL): a Linux parent-death signal and a
  watchdog thread in each worker.
- **Failures** (a build error, a diverged solver) are recorded in the case's metrics.json
  (``status: failed``, ``reason``) and do not stop the batch; a failed ramp step leaves its
  successors pending.
- **Ramps.** The steps of a ramp run one after the other, each from the previous step's final
  fields (runs/ramp.py); ramps and sweep cases run in parallel.
- **Local executor** (default): a ``ProcessPoolExecutor`` (spawn) running at most
  ``cores // run.n_procs`` cases at once, longest first; the EHL precalcs of new contacts are
  solved first, each once (a file lock per contact guards the cache across processes).
- **Dask executor**: each case is a task with ``resources={"CPU": run.n_procs}``, run in a
  child process of the worker (the solver's signal handling and gmsh need a process of their
  own). Workers must offer the resource: ``dask worker ADDRESS --resources CPU=<cores>``.
"""

from __future__ import annotations

import csv
import ctypes
import fcntl
import io
import json
import math
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
import traceback
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ehl_precalc.outputs import atomic_write_json, atomic_write_text

from .batch_spec import PRECALC_CPU_S, BatchSpec, PlannedCase, SpecError, est_cpu_s, load_plan

SPEC_COPY, PLAN, RESULTS, CASES, LOCKS, REGIME = (
    "batch.toml", "plan.json", "results.csv", "cases", "locks", "regime")
BATCH_LOCK = "batch.lock"
LOG = "log.interFoam"

#: results.csv: these columns first, then every other scalar of metrics.json.
FIXED_COLUMNS = ("case_id", "speed_mm_s", "temperature_C", "load_N", "supply", "disc_layer_um",
                 "ball_layer_um", "resolution", "ramp", "ramp_step", "ramp_direction", "status",
                 "end_reason", "reason", "state", "wall_s", "cells", "case_dir", "log")
STATUSES = ("pending", "running", "finished", "failed", "interrupted")

#: How long a worker waits for a case still held by a stopping process (the solver's
#: graceful stop takes up to runs.run_case.STOP_GRACE_S = 120 s).
LOCK_WAIT_S = 180.0
POLL_S = 0.5
#: Without a progress bar (--quiet, not a terminal): a status line after this long in silence.
STATUS_EVERY_S = 300.0
PR_SET_PDEATHSIG = 1


class BatchError(RuntimeError):
    """The batch cannot start (busy folder, a finished case with another spec, no CPU)."""


# =========================================================================== file helpers
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
    try:
        fh = open(path)
    except FileNotFoundError:
        return False
    try:
        fcntl.flock(fh, fcntl.LOCK_SH | fcntl.LOCK_NB)
        return False
    except BlockingIOError:
        return True
    finally:
        fh.close()


def read_metrics(case: Path) -> dict[str, Any] | None:
    """The case's metrics.json, or None (absent or unreadable)."""
    try:
        return json.loads((case / "metrics.json").read_text())
    except (FileNotFoundError, json.JSONDecodeError):
        return None


def case_status(case: Path, live: bool = False) -> str:
    """pending / running / finished / failed / interrupted, from metrics.json.

    ``live``: this batch process has the case in flight (its lock is not probed then, so
    that a probe can never collide with the worker taking it)."""
    m = read_metrics(case)
    status = (m or {}).get("status")
    if status in ("finished", "failed"):
        return status
    if live:
        return "running"
    if status == "running":
        from generator.case_writer import META

        return "running" if lock_is_held(case / META / "run.lock") else "interrupted"
    return "interrupted" if status == "interrupted" else "pending"


# =========================================================================== worker side
_WORKER: dict[str, Any] = {"busy": False, "stopping": False, "parent": None}


def _on_stop_signal(signum, frame) -> None:
    """SIGUSR1 (the batch asks to stop, or the parent died) and SIGTERM: a busy worker stops
    its case once (KeyboardInterrupt: the solver writes and stops); an idle one exits only
    when orphaned (a live pool ends it with its own sentinel)."""
    if _WORKER["busy"]:
        if not _WORKER["stopping"]:
            _WORKER["stopping"] = True
            raise KeyboardInterrupt
        return
    if signum == signal.SIGTERM or os.getppid() != _WORKER["parent"]:
        os._exit(0)


def _die_with_parent(parent: int) -> None:
    """SIGUSR1 when the parent dies (Linux prctl), and a watchdog thread as a backstop."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGUSR1), 0, 0, 0)
    except (OSError, AttributeError):
        pass

    def watch() -> None:
        while True:
            if os.getppid() != parent:
                os.kill(os.getpid(), signal.SIGUSR1)
                if not _WORKER["busy"]:
                    os._exit(0)
            time.sleep(1.0)

    threading.Thread(target=watch, daemon=True, name="ehlfoam-parent-watchdog").start()
    if os.getppid() != parent:       # the parent died before prctl took effect
        os.kill(os.getpid(), signal.SIGUSR1)


def _worker_init(parent: int) -> None:
    """Initializer of every worker process."""
    _WORKER["parent"] = parent
    signal.signal(signal.SIGINT, signal.SIG_IGN)     # Ctrl-C reaches the batch process
    signal.signal(signal.SIGUSR1, _on_stop_signal)
    signal.signal(signal.SIGTERM, _on_stop_signal)
    _die_with_parent(parent)


def _set_threads(n: int) -> None:
    """Threads of the numba kernels (EHL precalc) in this process."""
    try:
        import numba

        numba.set_num_threads(max(1, min(n, numba.config.NUMBA_NUM_THREADS)))
    except Exception:
        pass


_PLAN_CACHE: dict[str, tuple[tuple, dict[str, PlannedCase]]] = {}


def plan_index(batch_dir: Path) -> dict[str, PlannedCase]:
    """The batch folder's plan (from its batch.toml), by case id; cached per process."""
    path = Path(batch_dir) / SPEC_COPY
    st = path.stat()
    stamp = (st.st_mtime_ns, st.st_size)
    hit = _PLAN_CACHE.get(str(path))
    if hit and hit[0] == stamp:
        return hit[1]
    _, plan = load_plan(path)
    index = {pc.id: pc for pc in plan}
    _PLAN_CACHE[str(path)] = (stamp, index)
    return index


def run_task(batch_dir: str, kind: str, key: str, rerun_failed: bool, cpu: int) -> dict:
    """A worker's job: ``kind`` "precalc" (solve the contact of case ``key`` into the cache)
    or "case" (build and run case ``key``). Never raises for a case's own failure."""
    if _WORKER["stopping"]:
        return {"id": key, "kind": kind, "status": "interrupted"}
    _WORKER["busy"] = True
    try:
        _set_threads(cpu)
        if kind == "precalc":
            return ensure_precalc(Path(batch_dir), key)
        return execute_case(Path(batch_dir), key, rerun_failed)
    except KeyboardInterrupt:
        return {"id": key, "kind": kind, "status": "interrupted"}
    finally:
        _WORKER["busy"] = False


@contextmanager
def _precalc_lock(contact) -> Iterator[None]:
    """One process at a time solves a given contact (the cache is per machine)."""
    from generator.gap_source import cache_root, spec_key

    with file_lock(cache_root() / "precalc" / f".{spec_key(contact)}.lock", timeout=1e9):
        yield


def precalc_cached(contact) -> bool:
    """True if the contact's EHL precalc is in this machine's cache."""
    from generator.gap_source import cache_root, spec_key

    return (cache_root() / "precalc" / spec_key(contact) / "summary.json").is_file()


def ensure_precalc(batch_dir: Path, case_id: str) -> dict:
    """Solve (or find) the EHL precalc of a case's contact; a non-converged one is cached
    too (the case build then fails with the precalc's message)."""
    from generator.gap_source import precalc_dir

    contact = plan_index(batch_dir)[case_id].spec.contact
    t0 = time.monotonic()
    try:
        with _precalc_lock(contact):
            precalc_dir(contact, require_converged=False)
    except Exception as err:  # noqa: BLE001 - the case build reports it
        return {"id": case_id, "kind": "precalc", "status": "failed", "reason": _oneline(err)}
    return {"id": case_id, "kind": "precalc", "status": "finished",
            "wall_s": time.monotonic() - t0}


def _oneline(err: BaseException) -> str:
    text = " ".join(str(err).split())
    return f"{type(err).__name__}: {text}"[:500]


def _clean_stale_builds(case: Path) -> None:
    """Temporary folders of an interrupted write_case (``.ID.xxxx`` next to the case)."""
    for tmp in case.parent.glob(f".{case.name}.*"):
        if tmp.is_dir():
            shutil.rmtree(tmp, ignore_errors=True)


def execute_case(batch_dir: Path, case_id: str, rerun_failed: bool = False) -> dict:
    """Build and run one case of the batch in this process (under its lock) and complete its
    metrics.json. A finished case is left alone; a failed one unless ``rerun_failed``."""
    from generator.case_writer import write_case
    from generator.gap_source import precalc_dir
    from runs.run_case import CaseBusy, run_case

    from .ramp import seed_from_previous

    pc = plan_index(batch_dir)[case_id]
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
            write_case(pc.spec, case, overwrite=True)
            if pc.ramp and pc.ramp.get("previous"):
                stage = "ramp start"
                previous = batch_dir / CASES / pc.ramp["previous"]
                if case_status(previous) != "finished":
                    raise RuntimeError(f"the previous ramp step {previous.name} is not "
                                       f"finished ({case_status(previous)})")
                seed = seed_from_previous(case, previous)
            build_s = time.monotonic() - t0
            stage = "run"
            metrics = run_case(case)
        except CaseBusy as err:
            return {"id": case_id, "kind": "case", "status": "busy", "reason": str(err)}
        except Exception as err:  # noqa: BLE001 - recorded, the batch goes on
            metrics = _record_failure(case, case_id, stage, err, t0)
            return {"id": case_id, "kind": "case", "status": "failed",
                    "reason": metrics["reason"]}
        metrics = _complete_metrics(case, metrics, case_id, build_s, seed, t0)
        return {"id": case_id, "kind": "case", "status": metrics.get("status"),
                "reason": metrics.get("reason", "")}


def _record_failure(case: Path, case_id: str, stage: str, err: Exception, t0: float) -> dict:
    """metrics.json ``failed`` with the reason, and the traceback in error.log."""
    case.mkdir(parents=True, exist_ok=True)
    atomic_write_text(case / "error.log", traceback.format_exc())
    old = read_metrics(case) or {}
    keep = old if old.get("status") == "running" else {}   # this attempt's run only
    metrics = {**{k: v for k, v in keep.items() if k != "status"}, "status": "failed",
               "end_reason": f"{stage.replace(' ', '_')}_error",
               "reason": f"{stage}: {_oneline(err)}", "case_id": case_id,
               "case_wall_s": time.monotonic() - t0}
    atomic_write_json(case / "metrics.json", metrics)
    return metrics


def _failure_reason(metrics: dict) -> str:
    if metrics.get("status") != "failed":
        return ""
    tail = [ln.strip() for ln in metrics.get("log_tail") or [] if ln.strip()]
    last = tail[-1] if tail else ""
    return (f"solver {metrics.get('end_reason')} (exit code {metrics.get('solver_exit_code')})"
            + (f": {last[:300]}" if last else ""))


def _complete_metrics(case: Path, metrics: dict, case_id: str, build_s: float | None,
                      seed: dict | None, t0: float) -> dict:
    """Add the batch's keys to the run's metrics.json (written once, by its own worker)."""
    extra = {"case_id": case_id, "build_wall_s": build_s,
             "case_wall_s": time.monotonic() - t0}
    if seed:
        extra["ramp_start_method"] = seed["method"]
        extra["ramp_start_time_s"] = seed["previous_time_s"]
    reason = _failure_reason(metrics)
    if reason:
        extra["reason"] = reason
    metrics = {**metrics, **extra}
    atomic_write_json(case / "metrics.json", metrics)
    return metrics


# =========================================================================== results.csv
def _scalar(value: Any) -> bool:
    return value is None or isinstance(value, (str, int, float, bool))


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else ""
    return str(value)


def solver_log(case: Path) -> str:
    """The name of the case's solver log (log.interFoam, log.compressibleInterFoam)."""
    try:
        from generator.case_writer import load_geometry

        return load_geometry(case).log_name
    except Exception:  # noqa: BLE001 - not built (yet), or an older geometry.json
        return LOG


def result_row(batch_dir: Path, pc: PlannedCase, live: bool = False,
               blocked: str = "") -> dict[str, Any]:
    """The results.csv row of a planned case (typed values)."""
    case = batch_dir / CASES / pc.id
    m = read_metrics(case) or {}
    status = case_status(case, live)
    ramp = pc.ramp or {}
    reason = m.get("reason", "") if status in ("failed", "interrupted") else ""
    if status == "interrupted" and not reason:
        reason = "stopped before the end of its run (rebuilt on the next run)"
    if status == "pending" and blocked:
        reason = blocked
    log = solver_log(case)
    row = {"case_id": pc.id, **pc.params, "ramp": ramp.get("name"),
           "ramp_step": ramp.get("step"), "ramp_direction": ramp.get("direction"),
           "status": status, "end_reason": m.get("end_reason") if status != "pending" else None,
           "reason": reason, "state": m.get("state") if status == "finished" else None,
           "wall_s": m.get("wall_s"), "cells": m.get("cells"),
           "case_dir": f"{CASES}/{pc.id}",
           "log": f"{CASES}/{pc.id}/{log}" if (case / log).is_file() else None}
    if status in ("finished", "failed"):
        row.update({k: v for k, v in m.items() if k not in row and _scalar(v)})
    return row


def results_rows(batch_dir: Path, plan: list[PlannedCase], live: set[str] = frozenset(),
                 blocked: dict[str, str] | None = None) -> list[dict[str, Any]]:
    """One row per planned case, in plan order."""
    blocked = blocked or {}
    return [result_row(batch_dir, pc, pc.id in live, blocked.get(pc.id, "")) for pc in plan]


def write_results(batch_dir: Path, plan: list[PlannedCase], live: set[str] = frozenset(),
                  blocked: dict[str, str] | None = None) -> list[dict[str, Any]]:
    """Rewrite results.csv atomically from the metrics.json files; returns the rows."""
    rows = results_rows(batch_dir, plan, live, blocked)
    columns = list(FIXED_COLUMNS)
    for row in rows:
        columns += [k for k in row if k not in columns]
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({c: _cell(row.get(c)) for c in columns})
    atomic_write_text(batch_dir / RESULTS, buf.getvalue())
    return rows


def read_results(batch_dir: Path) -> list[dict[str, str]]:
    """results.csv as a list of dicts (strings)."""
    with open(Path(batch_dir) / RESULTS, newline="") as fh:
        return list(csv.DictReader(fh))


# =========================================================================== executors
def cpu_budget() -> int:
    """CPU cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


class LocalExecutor:
    """Worker processes on this machine (spawned, die with the batch process)."""

    kind = "local"

    def __init__(self, cores: int, n_workers: int):
        self.cores, self.n_workers = cores, n_workers
        self.pool = self._new_pool()

    def _new_pool(self):
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        return ProcessPoolExecutor(max_workers=self.n_workers,
                                   mp_context=multiprocessing.get_context("spawn"),
                                   initializer=_worker_init, initargs=(os.getpid(),))

    def capacity(self) -> int:
        return self.cores

    def describe(self) -> str:
        return f"local, {self.cores} cores, up to {self.n_workers} worker processes"

    def submit(self, batch_dir: Path, kind: str, key: str, rerun_failed: bool, cpu: int):
        return self.pool.submit(run_task, str(batch_dir), kind, key, rerun_failed, cpu)

    def broken(self, err: BaseException) -> bool:
        """A dead worker breaks the whole pool: start a new one."""
        from concurrent.futures.process import BrokenProcessPool

        if isinstance(err, BrokenProcessPool) and getattr(self.pool, "_broken", True):
            self.pool.shutdown(wait=True, cancel_futures=True)
            self.pool = self._new_pool()
            return True
        return False

    def interrupt(self) -> None:
        """Ask every busy worker to stop its case (idle ones ignore it)."""
        for p in list((getattr(self.pool, "_processes", None) or {}).values()):
            try:
                os.kill(p.pid, signal.SIGUSR1)
            except (ProcessLookupError, AttributeError):
                pass

    def shutdown(self) -> None:
        self.pool.shutdown(wait=True, cancel_futures=True)


def _dask_task(batch_dir: str, kind: str, key: str, rerun_failed: bool, cpu: int) -> dict:
    """Runs on a Dask worker: the job in a child process (``python -m runs.batch task``)."""
    env = {**os.environ, "NUMBA_NUM_THREADS": str(max(1, cpu)), "OMP_NUM_THREADS": "1"}
    argv = [sys.executable, "-m", "runs.batch", "task", batch_dir, kind, key, "--cpu", str(cpu)]
    if rerun_failed:
        argv.append("--rerun-failed")
    proc = subprocess.run(argv, capture_output=True, text=True, env=env)
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("{")]
    if proc.returncode == 0 and lines:
        return json.loads(lines[-1])
    return {"id": key, "kind": kind, "status": "failed",
            "reason": f"worker process exit code {proc.returncode}: "
                      f"{' '.join(proc.stderr.split()[-40:])}"}


class DaskExecutor:
    """Tasks on a Dask distributed cluster, each asking for ``CPU = n_procs`` resources."""

    kind = "dask"

    def __init__(self, client, cluster=None, planned_cores: int = 0):
        self.client, self.cluster, self.planned_cores = client, cluster, planned_cores
        self.futures: list = []
        self._capacity = (-math.inf, 0)

    def capacity(self) -> int:
        """CPU resources of the workers now (asked every 5 s), or what Slurm will bring."""
        when, have = self._capacity
        if time.monotonic() - when > 5.0:
            try:
                workers = self.client.scheduler_info(n_workers=-1).get("workers", {})
            except Exception:  # noqa: BLE001
                workers = {}
            have = sum(int(w.get("resources", {}).get("CPU", 0)) for w in workers.values())
            self._capacity = (time.monotonic(), have)
        return max(have, self.planned_cores)

    def describe(self) -> str:
        return f"dask, scheduler {self.client.scheduler.address}, {self.capacity()} CPU now"

    def submit(self, batch_dir: Path, kind: str, key: str, rerun_failed: bool, cpu: int):
        import uuid

        fut = self.client.submit(_dask_task, str(batch_dir), kind, key, rerun_failed, cpu,
                                 resources={"CPU": cpu}, pure=False,
                                 key=f"ehlfoam-{kind}-{key}-{uuid.uuid4().hex[:8]}")
        self.futures.append(fut)
        return fut

    def broken(self, err: BaseException) -> bool:
        return False

    def interrupt(self) -> None:
        """Cancel what has not started; a cluster this process made is closed (its workers'
        children stop gracefully); tasks on an outside cluster finish on their own."""
        self.client.cancel([f for f in self.futures if not f.done()])
        if self.cluster is not None:
            self.cluster.close()

    def shutdown(self) -> None:
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


SLURM_KEYS = {"cores": int, "memory": str, "walltime": str, "queue": str, "jobs": int,
              "account": str, "python": str}


def parse_slurm(text: str) -> dict[str, Any]:
    """``cores=32,memory=64GB,walltime=02:00:00,queue=normal,jobs=4`` -> dict."""
    out: dict[str, Any] = {"cores": 1, "memory": "4GB", "walltime": "01:00:00", "jobs": 1}
    for item in filter(None, (t.strip() for t in text.split(","))):
        key, sep, value = item.partition("=")
        if not sep or key not in SLURM_KEYS:
            raise SpecError(f"--slurm {item!r}: give KEY=VALUE with KEY one of "
                            f"{', '.join(SLURM_KEYS)}")
        try:
            out[key] = SLURM_KEYS[key](value)
        except ValueError:
            raise SpecError(f"--slurm {key} = {value!r}: not an integer") from None
        if key in ("cores", "jobs") and out[key] < 1:
            raise SpecError(f"--slurm {key} = {out[key]}: valid range {key} >= 1")
    return out


def slurm_cluster(opts: dict[str, Any], scale: bool = True):
    """A dask-jobqueue SLURMCluster: one worker per job with ``cores`` threads and the
    resource ``CPU = cores``; ``jobs`` jobs."""
    from dask_jobqueue import SLURMCluster

    kw = {"cores": opts["cores"], "processes": 1, "memory": opts["memory"],
          "walltime": opts["walltime"],
          "worker_extra_args": ["--resources", f"CPU={opts['cores']}"]}
    for key in ("queue", "account", "python"):
        if opts.get(key):
            kw[key] = opts[key]
    cluster = SLURMCluster(**kw)
    if scale:
        cluster.scale(jobs=opts["jobs"])
    return cluster


# =========================================================================== scheduling
@dataclass
class Task:
    """One job of the batch: a precalc or a case."""

    kind: str                      # "precalc" | "case"
    key: str                       # case id (for a precalc: a case with that contact)
    cpu: int
    cost: float                    # estimated CPU seconds
    priority: float = 0.0          # longest chain first
    deps: set[str] = field(default_factory=set)
    name: str = ""

    def __post_init__(self):
        self.name = self.name or (self.key if self.kind == "case" else f"precalc:{self.key}")


@dataclass
class BatchOutcome:
    """What a batch run ended with."""

    batch_dir: Path
    counts: dict[str, int]
    interrupted: bool
    wall_s: float
    ran: list[str]
    skipped: list[str]

    @property
    def exit_code(self) -> int:
        if self.interrupted:
            return 130
        return 0 if self.counts.get("finished", 0) == sum(self.counts.values()) else 1


def _spec_diff(a: Any, b: Any, prefix: str = "") -> list[str]:
    if isinstance(a, dict) and isinstance(b, dict):
        out = []
        for k in sorted(set(a) | set(b)):
            out += _spec_diff(a.get(k), b.get(k), f"{prefix}.{k}" if prefix else k)
        return out
    return [] if a == b else [f"{prefix}: {a!r} (finished) vs {b!r} (spec)"]


def check_finished_specs(batch_dir: Path, plan: list[PlannedCase]) -> None:
    """A finished case must have been built from the spec the plan gives it now."""
    from generator.case_writer import load_spec_of

    for pc in plan:
        case = batch_dir / CASES / pc.id
        if case_status(case) != "finished":
            continue
        try:
            old = load_spec_of(case).model_dump()
        except Exception as err:  # noqa: BLE001
            raise BatchError(f"finished case {case} has an unreadable spec ({err})") from None
        diff = [d for d in _spec_diff(old, pc.spec.model_dump()) if not d.startswith("name:")]
        if diff:
            raise BatchError(
                f"case {pc.id} finished with another case spec than the batch spec gives it "
                f"now ({'; '.join(diff[:3])}); its results are never overwritten: use another "
                f"--out folder, or delete {case} to recompute it")


class Progress:
    """Counts, elapsed and estimated time on a rich progress bar (a terminal) or as log
    lines."""

    def __init__(self, title: str, quiet: bool):
        from rich.console import Console
        from rich.progress import BarColumn, Progress as RichProgress, TextColumn

        self.console = Console(stderr=False)
        self.bar = not quiet and self.console.is_terminal
        self.quiet = quiet
        self.t0 = time.monotonic()
        self.rich = RichProgress(TextColumn("{task.description}"), BarColumn(),
                                 TextColumn("{task.percentage:>3.0f}%"),
                                 TextColumn("{task.fields[counts]}"),
                                 console=self.console, disable=not self.bar, transient=False)
        self.task = self.rich.add_task(title, total=1.0, counts="")
        self.last_line, self.last_print = "", time.monotonic()

    def __enter__(self):
        self.rich.__enter__()
        return self

    def __exit__(self, *exc):
        self.rich.__exit__(*exc)

    def elapsed(self) -> float:
        return time.monotonic() - self.t0

    def update(self, fraction: float, counts: dict[str, int], eta: float | None) -> None:
        text = (f"done {counts['finished']}/{counts['total']}  running {counts['running']}  "
                f"failed {counts['failed']}  elapsed {_hms(self.elapsed())}  "
                f"eta {_hms(eta) if eta is not None else '?'}")
        self.rich.update(self.task, completed=min(max(fraction, 0.0), 1.0), counts=text)
        self.last_line = text
        if not self.bar and time.monotonic() - self.last_print > STATUS_EVERY_S:
            self.log(f"status   {text}")

    def log(self, text: str) -> None:
        self.last_print = time.monotonic()
        line = f"[{_hms(self.elapsed())}] {text}"
        if self.bar:
            self.rich.console.print(line, highlight=False, soft_wrap=True)
        else:
            print(line, flush=True)


def _hms(seconds: float) -> str:
    s = int(round(max(seconds, 0.0)))
    return f"{s // 3600}:{s % 3600 // 60:02d}:{s % 60:02d}"


def _sim_fraction(case: Path, end_time: float) -> float:
    """Simulated time reached over the end time, from the last row of history.csv."""
    try:
        with open(case / "history.csv", "rb") as fh:
            fh.seek(0, os.SEEK_END)
            fh.seek(max(0, fh.tell() - 400))
            last = fh.read().decode(errors="replace").strip().splitlines()[-1]
        return min(float(last.split(",")[0]) / end_time, 1.0)
    except (OSError, ValueError, IndexError):
        return 0.0


class BatchRunner:
    """Schedules the tasks of one batch run on an executor (dependencies, longest first,
    CPU accounting), follows progress and keeps results.csv."""

    def __init__(self, batch_dir: Path, plan: list[PlannedCase], executor, *,
                 rerun_failed: bool, progress: Progress):
        self.batch_dir, self.plan, self.executor = batch_dir, plan, executor
        self.rerun_failed, self.progress = rerun_failed, progress
        self.by_id = {pc.id: pc for pc in plan}
        self.tasks: dict[str, Task] = {}
        self.skipped: list[str] = []
        self.blocked: dict[str, str] = {}
        self.inflight: dict[str, tuple[Any, Task, float]] = {}
        self.done_cost = 0.0
        self.outcome: dict[str, str] = {}
        self.retried: set[str] = set()
        self._build_tasks()

    # ------------------------------------------------------------- the task graph
    def _build_tasks(self) -> None:
        todo = []
        for pc in self.plan:
            status = case_status(self.batch_dir / CASES / pc.id)
            if status == "finished" or (status == "failed" and not self.rerun_failed):
                self.skipped.append(pc.id)
            else:
                todo.append(pc)
        todo_ids = {pc.id for pc in todo}
        precalcs: dict[str, Task] = {}
        local = self.executor.kind == "local"
        from generator.gap_source import spec_key

        for pc in todo:
            deps = set()
            key = spec_key(pc.spec.contact)
            if not (local and precalc_cached(pc.spec.contact)):
                if key not in precalcs:
                    precalcs[key] = Task("precalc", pc.id, 1, PRECALC_CPU_S)
                deps.add(precalcs[key].name)
            prev = (pc.ramp or {}).get("previous")
            if prev and prev in todo_ids:
                deps.add(prev)
            task = Task("case", pc.id, pc.n_procs, est_cpu_s(pc.spec), deps=deps)
            self.tasks[task.name] = task
            if prev and prev not in todo_ids and case_status(
                    self.batch_dir / CASES / prev) != "finished":
                self.blocked[pc.id] = f"waits for ramp step {prev} (failed; --rerun-failed)"
        for t in precalcs.values():
            self.tasks[t.name] = t
        for name in list(self.blocked):
            self.tasks.pop(name, None)
            self._block_successors(name, "not run")
        self._priorities()

    def _successors(self, name: str) -> list[Task]:
        return [t for t in self.tasks.values() if name in t.deps and t.kind == "case"]

    def _priorities(self) -> None:
        """Case: its cost plus its longest chain of successors; precalc: above all cases."""
        memo: dict[str, float] = {}

        def chain(t: Task) -> float:
            if t.name not in memo:
                memo[t.name] = t.cost + max((chain(s) for s in self._successors(t.name)),
                                            default=0.0)
            return memo[t.name]

        for t in self.tasks.values():
            t.priority = chain(t) if t.kind == "case" else 1e12 + chain(t)

    def _block_successors(self, name: str, reason: str) -> None:
        """The later steps of a ramp whose step ``name`` did not finish stay pending."""
        for s in self._successors(name):
            self.blocked[s.key] = f"waits for ramp step {name} ({reason})"
            self.tasks.pop(s.name, None)
            self._block_successors(s.name, "not run")

    # ------------------------------------------------------------- the loop
    def counts(self) -> dict[str, int]:
        live = {t.key for _, t, _ in self.inflight.values() if t.kind == "case"}
        c = dict.fromkeys(STATUSES, 0)
        for pc in self.plan:
            c[case_status(self.batch_dir / CASES / pc.id, pc.id in live)] += 1
        c["total"] = len(self.plan)
        return c

    def _ready(self) -> list[Task]:
        started = {t.name for _, t, _ in self.inflight.values()}
        ready = [t for t in self.tasks.values() if not t.deps and t.name not in started]
        return sorted(ready, key=lambda t: -t.priority)

    def _submit_ready(self) -> None:
        used = sum(t.cpu for _, t, _ in self.inflight.values())
        cap = self.executor.capacity()
        for t in self._ready():
            if used + t.cpu > cap:
                continue
            fut = self.executor.submit(self.batch_dir, t.kind, t.key, self.rerun_failed, t.cpu)
            self.inflight[t.name] = (fut, t, time.monotonic())
            used += t.cpu
            self.progress.log(f"start    {t.key}" if t.kind == "case" else
                              f"start    EHL precalc of the contact of {t.key}")

    def _finish(self, name: str, result: dict) -> None:
        _, task, _ = self.inflight.pop(name)
        self.tasks.pop(name, None)
        self.done_cost += task.cost
        if task.kind == "precalc":
            if result.get("status") != "finished":
                self.progress.log(f"precalc of {task.key}'s contact: {result.get('reason')}")
            self._release(name)
            return
        case = self.batch_dir / CASES / task.key
        status = case_status(case)
        m = read_metrics(case) or {}
        self.outcome[task.key] = status
        if status == "finished":
            wall = m.get("case_wall_s") or m.get("wall_s") or 0.0
            word = "kept" if result.get("skipped") else "finished"
            self.progress.log(f"{word:8s} {task.key}: state {m.get('state')}, "
                              f"{m.get('end_reason')}, {wall:.0f} s")
        else:
            reason = result.get("reason") or m.get("reason") or status
            self.progress.log(f"{status:8s} {task.key}: {reason}")
            self._block_successors(name, status)
        self._release(name)
        self.write_results()

    def _release(self, name: str) -> None:
        """Tasks waiting for ``name`` may start."""
        for t in self.tasks.values():
            t.deps.discard(name)

    def _poll(self) -> None:
        for name, (fut, task, _) in list(self.inflight.items()):
            if not fut.done():
                continue
            try:
                result = fut.result()
            except Exception as err:  # noqa: BLE001 - a dead worker, a cancelled task
                result = self._lost(name, task, err)
                if result is None:
                    continue
            self._finish(name, result)

    def _lost(self, name: str, task: Task, err: BaseException) -> dict | None:
        """A task whose worker died: retried once (its case rebuilt), then failed."""
        self.executor.broken(err)
        if task.name not in self.retried and task.kind == "case":
            self.retried.add(task.name)
            self.inflight.pop(name)
            self.progress.log(f"retry    {task.key}: worker lost ({_oneline(err)})")
            return None
        case = self.batch_dir / CASES / task.key
        if task.kind == "case" and case_status(case) not in ("finished", "failed"):
            with file_lock(self.batch_dir / LOCKS / f"{task.key}.lock", timeout=5.0) as got:
                if got:
                    _record_failure_plain(case, task.key, f"worker lost: {_oneline(err)}")
        return {"id": task.key, "status": "failed", "reason": _oneline(err)}

    def _eta(self, partial: float) -> float | None:
        remaining = sum(t.cost for t in self.tasks.values()) - partial
        done = self.done_cost + partial
        elapsed = self.progress.elapsed()
        if done > 0 and elapsed > 5:
            return max(remaining, 0.0) * elapsed / done
        cap = max(self.executor.capacity(), 1)
        return remaining / cap if remaining > 0 else 0.0

    def _refresh(self) -> None:
        partial = 0.0
        for _, task, _ in self.inflight.values():
            if task.kind == "case":
                pc = self.by_id[task.key]
                frac = _sim_fraction(self.batch_dir / CASES / task.key, pc.spec.end_time)
                partial += task.cost * frac
        total = self.done_cost + sum(t.cost for t in self.tasks.values())
        frac = (self.done_cost + partial) / total if total > 0 else 1.0
        self.progress.update(frac, self.counts(), self._eta(partial))

    def write_results(self) -> list[dict]:
        live = {t.key for _, t, _ in self.inflight.values() if t.kind == "case"}
        return write_results(self.batch_dir, self.plan, live, self.blocked)

    def run(self) -> None:
        """Until every task is done (KeyboardInterrupt propagates: see :meth:`stop`)."""
        self.write_results()
        last_refresh = last_warning = 0.0
        while self.tasks:
            self._submit_ready()
            if not self.inflight and time.monotonic() - last_warning > 60.0:
                # only a Dask cluster can be short of CPU (the local budget is checked first)
                need = max(t.cpu for t in self.tasks.values())
                self.progress.log(f"waiting for workers: a task needs CPU = {need}, the "
                                  f"cluster offers {self.executor.capacity()} (start Dask "
                                  f"workers with --resources CPU=<cores>)")
                last_warning = time.monotonic()
            time.sleep(POLL_S)
            self._poll()
            if time.monotonic() - last_refresh > 2.0:
                self._refresh()
                last_refresh = time.monotonic()
        self._refresh()

    def stop(self) -> None:
        """Ctrl-C / SIGTERM: stop the cases in flight (they write ``interrupted``), wait for
        their workers, keep results.csv right. A second Ctrl-C stops waiting."""
        self.progress.log(f"interrupted: stopping {len(self.inflight)} task(s) in flight")
        self.executor.interrupt()
        deadline = time.monotonic() + 150.0
        try:
            while self.inflight and time.monotonic() < deadline:
                for name, (fut, _, _) in list(self.inflight.items()):
                    if fut.done():
                        self.inflight.pop(name)
                time.sleep(POLL_S)
        except KeyboardInterrupt:
            pass
        self.inflight.clear()


def _record_failure_plain(case: Path, case_id: str, reason: str) -> None:
    case.mkdir(parents=True, exist_ok=True)
    old = read_metrics(case) or {}
    atomic_write_json(case / "metrics.json", {**{k: v for k, v in old.items() if k != "status"},
                                              "status": "failed", "end_reason": "worker_lost",
                                              "reason": reason, "case_id": case_id})


# =========================================================================== entry point
@dataclass
class BatchOptions:
    """How to run a batch (see ``ehlfoam batch --help``)."""

    out: Path | None = None
    jobs: int | None = None            # cases at once (local)
    cores: int | None = None           # CPU budget (local); default: this process's CPUs
    rerun_failed: bool = False
    scheduler: str | None = None       # Dask scheduler address
    slurm: dict[str, Any] | None = None
    client: Any = None                 # an existing distributed.Client (tests, benchmarks)
    quiet: bool = False
    regime: bool = True
    report: bool = True


def batch_folder(spec_path: Path, out: Path | None) -> Path:
    """``--out`` or ``runs/NAME/`` for ``runs/NAME.toml``."""
    return Path(out) if out else spec_path.with_suffix("")


def _make_executor(opts: BatchOptions, plan: list[PlannedCase]):
    need = max(pc.n_procs for pc in plan)
    if opts.client is not None:
        return DaskExecutor(opts.client)
    if opts.scheduler:
        from distributed import Client

        try:
            return DaskExecutor(Client(opts.scheduler, timeout="20s"))
        except (OSError, TimeoutError) as err:
            raise BatchError(f"--scheduler {opts.scheduler}: cannot reach a Dask scheduler "
                             f"({_oneline(err)})") from None
    if opts.slurm is not None:
        from distributed import Client

        cluster = slurm_cluster(opts.slurm)
        return DaskExecutor(Client(cluster), cluster,
                            planned_cores=opts.slurm["cores"] * opts.slurm["jobs"])
    cores = opts.jobs * need if opts.jobs else (opts.cores or cpu_budget())
    if need > cores:
        raise BatchError(f"run.n_procs = {need} is more than the CPU budget of {cores} "
                         f"cores (--cores)")
    return LocalExecutor(cores, max(1, cores))


def _write_inputs(batch_dir: Path, spec_path: Path, plan: list[PlannedCase]) -> None:
    atomic_write_text(batch_dir / SPEC_COPY, spec_path.read_text())
    atomic_write_json(batch_dir / PLAN, [pc.to_json() for pc in plan])


def _after(batch_dir: Path, rows: list[dict], opts: BatchOptions, log: Callable) -> None:
    """Regime map, then the batch report (if the report package is there)."""
    if opts.regime:
        try:
            from .regime import write_regime

            summary = write_regime(batch_dir, rows)
            for line in summary.get("summary", []):
                log(f"regime: {line}")
        except Exception as err:  # noqa: BLE001 - the results stay
            log(f"regime map failed: {_oneline(err)}")
    if opts.report:
        try:
            from runs.report import report_batch
        except ImportError:
            log("batch report: runs.report is not available yet (no report written)")
            return
        try:
            out = report_batch(batch_dir)
            log(f"batch report: {out if out else batch_dir}")
        except Exception as err:  # noqa: BLE001
            log(f"batch report failed: {_oneline(err)}")


def run_batch(spec_path: str | Path, opts: BatchOptions | None = None) -> BatchOutcome:
    """Validate and expand the batch spec, then build, run and report every case that is
    not finished yet under the batch folder. Raises :class:`SpecError` (bad spec, nothing
    written) or :class:`BatchError` (cannot start)."""
    opts = opts or BatchOptions()
    spec_path = Path(spec_path)
    batch, plan = load_plan(spec_path)
    batch_dir = batch_folder(spec_path, opts.out).absolute()
    check_finished_specs(batch_dir, plan)
    batch_dir.mkdir(parents=True, exist_ok=True)
    with file_lock(batch_dir / BATCH_LOCK) as got:
        if not got:
            raise BatchError(f"batch folder {batch_dir} is in use by another ehlfoam batch")
        (batch_dir / LOCKS).mkdir(exist_ok=True)
        _write_inputs(batch_dir, spec_path, plan)
        return _run_locked(batch, plan, batch_dir, opts)


def _run_locked(batch: BatchSpec, plan: list[PlannedCase], batch_dir: Path,
                opts: BatchOptions) -> BatchOutcome:
    t0 = time.monotonic()
    executor = _make_executor(opts, plan)
    interrupted = False
    previous = signal.getsignal(signal.SIGTERM)
    in_main = threading.current_thread() is threading.main_thread()
    if in_main:
        signal.signal(signal.SIGTERM, _raise_interrupt)
    with Progress(f"batch {batch.name}", opts.quiet) as progress:
        runner = BatchRunner(batch_dir, plan, executor, rerun_failed=opts.rerun_failed,
                             progress=progress)
        progress.log(f"batch {batch.name}: {len(plan)} cases, {len(runner.skipped)} kept, "
                     f"{sum(t.kind == 'case' for t in runner.tasks.values())} to run "
                     f"({executor.describe()}) -> {batch_dir}")
        try:
            runner.run()
        except KeyboardInterrupt:
            interrupted = True
            runner.stop()
        finally:
            try:
                executor.shutdown()
            except Exception:  # noqa: BLE001
                pass
            if in_main:
                signal.signal(signal.SIGTERM,
                              previous if previous is not None else signal.SIG_DFL)
            runner.inflight.clear()
            rows = runner.write_results()
        counts = {s: sum(r["status"] == s for r in rows) for s in STATUSES}
        progress.log("results: " + ", ".join(f"{v} {k}" for k, v in counts.items() if v)
                     + f" -> {batch_dir / RESULTS}")
        if not interrupted:
            _after(batch_dir, rows, opts, progress.log)
    return BatchOutcome(batch_dir, counts, interrupted, time.monotonic() - t0,
                        ran=sorted(runner.outcome), skipped=runner.skipped)


def _raise_interrupt(signum, frame):
    raise KeyboardInterrupt


def dry_run(spec_path: str | Path, out: Path | None = None) -> str:
    """The plan as a table (id, ramp, estimated CPU) without building anything."""
    from generator.gap_source import spec_key

    spec_path = Path(spec_path)
    batch, plan = load_plan(spec_path)
    batch_dir = batch_folder(spec_path, out)
    lines = [f"batch {batch.name}: {len(plan)} cases -> {batch_dir}"]
    contacts = {spec_key(pc.spec.contact) for pc in plan}
    new = {spec_key(pc.spec.contact) for pc in plan if not precalc_cached(pc.spec.contact)}
    total = 0.0
    for pc in plan:
        est = est_cpu_s(pc.spec)
        total += est
        ramp = (f"ramp {pc.ramp['name']} step {pc.ramp['step']} {pc.ramp['direction']}"
                if pc.ramp else "")
        status = case_status(batch_dir / CASES / pc.id)
        lines.append(f"  {pc.id:44s} end {pc.spec.end_time:7.3f} s  ~{est:6.0f} s CPU  "
                     f"{status:9s} {ramp}")
    lines.append(f"estimated CPU: {total / 60:.0f} min for the cases + {len(new)} of "
                 f"{len(contacts)} EHL precalcs not cached (~{len(new) * PRECALC_CPU_S / 60:.0f}"
                 f" min); rough (docs/batches.md)")
    return "\n".join(lines)


# =========================================================================== child entry
def _task_main(argv: list[str]) -> int:
    """``python -m runs.batch task BATCH_DIR KIND KEY [--cpu N] [--rerun-failed]``: one job
    in this process (a Dask worker's child); prints the result as one JSON line."""
    import argparse

    ap = argparse.ArgumentParser(prog="python -m runs.batch task")
    ap.add_argument("batch_dir")
    ap.add_argument("kind", choices=("case", "precalc"))
    ap.add_argument("key")
    ap.add_argument("--cpu", type=int, default=1)
    ap.add_argument("--rerun-failed", action="store_true")
    args = ap.parse_args(argv)
    _worker_init(os.getppid())
    result = run_task(args.batch_dir, args.kind, args.key, args.rerun_failed, args.cpu)
    print(json.dumps(result), flush=True)
    return 0


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "task":
        sys.exit(_task_main(sys.argv[2:]))
    print("usage: python -m runs.batch task BATCH_DIR KIND KEY [--cpu N] [--rerun-failed]",
          file=sys.stderr)
    sys.exit(2)
