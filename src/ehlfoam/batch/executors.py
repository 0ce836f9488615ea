"""Where a batch's tasks run: worker processes on this machine, or a Dask cluster (an existing
scheduler, or Slurm through dask-jobqueue); and what runs in a worker: :func:`run_task`.

- **Local** (:class:`LocalExecutor`): a ``ProcessPoolExecutor`` (spawn). Its workers ignore
  the terminal's Ctrl-C (the batch process decides); SIGUSR1 or SIGTERM stop a busy worker's
  case gracefully (the solver writes its last time, metrics.json says ``interrupted``). A
  worker also stops when the batch process is killed (SIGKILL): a Linux parent-death signal
  and a watchdog thread.
- **Dask** (:class:`DaskExecutor`): each task asks for ``resources={"CPU": cpu}`` and runs in
  a child process of the worker (``python -m ehlfoam.batch.executors task ...``: the solver's
  signal handling and gmsh need a process of their own). Workers must offer the resource:
  ``dask worker ADDRESS --resources CPU=<cores>``.

:func:`run_task` and :func:`_dask_task` are pickled by reference: they stay module-level.
"""

from __future__ import annotations

import json
import math
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

from ehlfoam.batch.case import ensure_precalc, execute_case
from ehlfoam.errors import SpecError
from ehlfoam.foam.lifetime import set_parent_death_signal


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
    set_parent_death_signal(signal.SIGUSR1)

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


# =========================================================================== executors
def cpu_budget() -> int:
    """CPU cores this process may use (:func:`ehlfoam.case.bounds.usable_cores`)."""
    from ehlfoam.case.bounds import usable_cores

    return usable_cores()


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
    """Runs on a Dask worker: the job in a child process (``python -m ehlfoam.batch.executors
    task``)."""
    env = {**os.environ, "NUMBA_NUM_THREADS": str(max(1, cpu)), "OMP_NUM_THREADS": "1"}
    argv = [sys.executable, "-m", "ehlfoam.batch.executors", "task", batch_dir, kind, key,
            "--cpu", str(cpu)]
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
#: What each ``--slurm`` value may be: dask-jobqueue writes them into the sbatch script
#: (``#SBATCH`` lines, the worker's command line) as they are, so a newline, ``;``, ``$``, a
#: quote or a space would add directives or commands. Checked before the script is made.
SLURM_PATTERNS = {
    "memory": (r"[1-9][0-9]{0,5}(\.[0-9]{1,3})?(B|KB|MB|GB|TB|KiB|MiB|GiB|TiB)",
               "a size like 4GB, 512MB or 1.5TB"),
    "walltime": (r"([0-9]{1,3}-)?[0-9]{1,3}:[0-5][0-9]:[0-5][0-9]",
                 "HH:MM:SS (or D-HH:MM:SS), e.g. 01:00:00"),
    "queue": (r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}", "a partition name: letters, digits, _ . -"),
    "account": (r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}", "an account name: letters, digits, _ . -"),
    "python": (r"/?[A-Za-z0-9_.+-]+(/[A-Za-z0-9_.+-]+)*",
               "a path to a Python interpreter: letters, digits, _ . + - and /"),
}
#: The most cores of one job and jobs of one batch (a typo guard)
SLURM_MAX = {"cores": 4096, "jobs": 10000}
SLURM_DEFAULTS: dict[str, Any] = {"cores": 1, "memory": "4GB", "walltime": "01:00:00",
                                  "jobs": 1}


def _slurm_value(key: str, value: Any) -> Any:
    """One ``--slurm`` value, checked against its pattern; SpecError naming it."""
    if key not in SLURM_KEYS:
        raise SpecError(f"--slurm {key}: unknown key (valid: {', '.join(SLURM_KEYS)})")
    if SLURM_KEYS[key] is int:
        text = str(value).strip() if not isinstance(value, bool) else "?"
        if not re.fullmatch(r"[0-9]{1,6}", text) or not 1 <= int(text) <= SLURM_MAX[key]:
            raise SpecError(f"--slurm {key} = {value!r}: valid range 1 <= {key} <= "
                            f"{SLURM_MAX[key]} (an integer)")
        return int(text)
    pattern, what = SLURM_PATTERNS[key]
    if not isinstance(value, str) or not re.fullmatch(pattern, value):
        raise SpecError(f"--slurm {key} = {value!r}: valid is {what} (no spaces, quotes, "
                        f"newlines, ; or $: it goes into the sbatch script)")
    return value


def check_slurm(opts: Any) -> dict[str, Any]:
    """Slurm options (``BatchOptions.slurm``, :func:`parse_slurm`) with every value checked
    against its pattern (:data:`SLURM_PATTERNS`) and the defaults filled in; SpecError
    naming the first bad one. No value reaches the sbatch script unchecked."""
    if not isinstance(opts, dict):
        raise SpecError(f"--slurm {opts!r}: give KEY=VALUE,... with KEY one of "
                        f"{', '.join(SLURM_KEYS)}")
    out = dict(SLURM_DEFAULTS)
    for key, value in opts.items():
        if value is None and key not in SLURM_DEFAULTS:
            continue
        out[key] = _slurm_value(str(key), value)
    return out


def parse_slurm(text: str) -> dict[str, Any]:
    """``cores=32,memory=64GB,walltime=02:00:00,queue=normal,jobs=4`` -> dict, every value
    checked (:func:`check_slurm`)."""
    given: dict[str, Any] = {}
    for item in filter(None, (t.strip() for t in text.split(","))):
        key, sep, value = item.partition("=")
        if not sep or key not in SLURM_KEYS:
            raise SpecError(f"--slurm {item!r}: give KEY=VALUE with KEY one of "
                            f"{', '.join(SLURM_KEYS)}")
        if key in given:
            raise SpecError(f"--slurm {key} is given twice ({given[key]!r}, {value!r})")
        given[key] = value
    return check_slurm(given)


def slurm_cluster(opts: dict[str, Any], scale: bool = True):
    """A dask-jobqueue SLURMCluster: one worker per job with ``cores`` threads and the
    resource ``CPU = cores``; ``jobs`` jobs. The options are checked first
    (:func:`check_slurm`): SpecError before any script is written."""
    from dask_jobqueue import SLURMCluster

    opts = check_slurm(opts)
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


# =========================================================================== child entry
def _task_main(argv: list[str]) -> int:
    """``python -m ehlfoam.batch.executors task BATCH_DIR KIND KEY [--cpu N] [--rerun-failed]``:
    one job in this process (a Dask worker's child); prints the result as one JSON line."""
    import argparse

    ap = argparse.ArgumentParser(prog="python -m ehlfoam.batch.executors task")
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
    print("usage: python -m ehlfoam.batch.executors task BATCH_DIR KIND KEY [--cpu N] "
          "[--rerun-failed]", file=sys.stderr)
    sys.exit(2)
