"""Run a batch of cases: plan -> cases, on local processes or on Dask; resume; results.csv.

The entry points (:func:`run_batch`, :func:`dry_run`) and their options. The parts:
``spec`` (the batch spec), ``plan`` (its cases), ``folder`` (the folder's layout, locks, a
case's status), ``case`` (build and run one case), ``executors`` (local processes, Dask,
Slurm; the worker side), ``runner`` (scheduling the tasks), ``progress`` (the progress bar),
``results`` (results.csv), ``regime`` (the regime analysis). The report is made by the
caller's ``report`` function (the batch sits below the reports).

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
  fields (ehlfoam.seed.start); ramps and sweep cases run in parallel.
- **Local executor** (default): a ``ProcessPoolExecutor`` (spawn) running at most
  ``cores // run.n_procs`` cases at once, longest first; the EHL precalcs of new contacts are
  solved first, each once (a file lock per contact guards the cache across processes).
- **Dask executor**: each case is a task with ``resources={"CPU": run.n_procs}``, run in a
  child process of the worker (the solver's signal handling and gmsh need a process of their
  own). Workers must offer the resource: ``dask worker ADDRESS --resources CPU=<cores>``.
"""

from __future__ import annotations

import signal
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from ehlfoam._io import atomic_write_json, atomic_write_text

from ehlfoam.batch.case import oneline, precalc_cached
from ehlfoam.batch.confirm import PREFIX, check_confirm, confirm_plan
from ehlfoam.batch.executors import (DaskExecutor, LocalExecutor, check_slurm, cpu_budget,
                                     slurm_cluster)
from ehlfoam.batch.folder import (BATCH_LOCK, CASES, LOCKS, PLAN, RESULTS, SPEC_COPY, STATUSES, batch_folder, case_status, file_lock)
from ehlfoam.batch.progress import Progress
from ehlfoam.batch.runner import BatchRunner
from ehlfoam.batch.plan import PRECALC_CPU_S, PlannedCase, est_cpu_s, load_plan
from ehlfoam.batch.spec import DEFAULT_MAX_CASES, BatchSpec
from ehlfoam.case.bounds import LIMIT_KEYS, check_n_procs
from ehlfoam.errors import SpecError


class BatchError(RuntimeError):
    """The batch cannot start (busy folder, a finished case with another spec, no CPU)."""


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
    from ehlfoam.case.geometry import load_spec_of

    for pc in plan:
        case = batch_dir / CASES / pc.id
        if case_status(case) != "finished":
            continue
        try:
            old = load_spec_of(case).model_dump()
        except Exception as err:  # noqa: BLE001
            raise BatchError(f"finished case {case} has an unreadable spec ({err})") from None
        diff = [d for d in _spec_diff(old, pc.spec.model_dump())
                if not d.startswith(("name:", *(f"{k}:" for k in LIMIT_KEYS)))]
        if diff:
            raise BatchError(
                f"case {pc.id} finished with another case spec than the batch spec gives it "
                f"now ({'; '.join(diff[:3])}); its results are never overwritten: use another "
                f"--out folder, or delete {case} to recompute it")


@dataclass
class BatchOptions:
    """How to run a batch (see ``ehlfoam batch --help``)."""

    out: Path | None = None
    jobs: int | None = None            # cases at once (local)
    cores: int | None = None           # CPU budget (local); default: this process's CPUs
    rerun_failed: bool = False
    scheduler: str | None = None       # Dask scheduler address
    slurm: dict[str, Any] | None = None
    client: Any = None                 # an existing distributed.Client (tests, timings)
    quiet: bool = False
    regime: bool = True                # the regime analysis (regime/regime.json)
    #: the most cases the batch may ask for, counted before they are expanded
    max_cases: int = DEFAULT_MAX_CASES
    #: run cases (run.n_procs, --cores, --jobs) beyond the cores this process may use
    oversubscribe: bool = False
    #: what reports the batch after its cases, called with the batch folder and the log
    #: (``ehlfoam batch`` passes :func:`ehlfoam.report.after_batch`); None: no report
    report: Callable[[Path, Callable[[str], None]], Any] | None = None

    def __post_init__(self) -> None:
        if self.report is not None and self.report is not False and not callable(self.report):
            raise TypeError(f"BatchOptions.report = {self.report!r}: give the function that "
                            f"reports a batch (ehlfoam.report.after_batch) or None")


def check_cores(opts: BatchOptions, plan: list[PlannedCase]) -> None:
    """The cores the batch asks for within what runs it, before anything is written: on this
    machine ``run.n_procs``, ``--cores`` and ``--jobs`` x ``run.n_procs`` within the usable
    cores unless ``oversubscribe``; on Slurm ``run.n_procs`` within a job's cores (a case
    asking for more would wait for ever)."""
    widest = max(plan, key=lambda pc: pc.n_procs)
    need = widest.n_procs
    if opts.client is not None or opts.scheduler:
        return
    if opts.slurm is not None:
        if need > opts.slurm["cores"]:
            raise SpecError(f"run.n_procs = {need} (case {widest.id}) is more than --slurm "
                            f"cores = {opts.slurm['cores']}, the CPUs of each Slurm job's "
                            f"worker (valid range 1 <= run.n_procs <= {opts.slurm['cores']})")
        return
    over = opts.oversubscribe
    check_n_procs(need, oversubscribe=over, context=f" (case {widest.id})")
    if opts.cores:
        check_n_procs(opts.cores, oversubscribe=over, where="--cores")
    if opts.jobs:
        check_n_procs(opts.jobs, oversubscribe=over, where="--jobs", per=need,
                      context=" cases at once")


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
                             f"({oneline(err)})") from None
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
    """The regime analysis, then the report (``opts.report``)."""
    if opts.regime:
        try:
            from ehlfoam.batch.regime import write_regime

            write_regime(batch_dir, rows)
        except Exception as err:  # noqa: BLE001 - the results stay
            log(f"regime map failed: {oneline(err)}")
    if opts.report:
        try:
            opts.report(batch_dir, log)
        except Exception as err:  # noqa: BLE001
            log(f"batch report failed: {oneline(err)}")


def run_batch(spec_path: str | Path, opts: BatchOptions | None = None) -> BatchOutcome:
    """Validate and expand the batch spec, then build, run and report every case that is
    not finished yet under the batch folder. Raises :class:`SpecError` (bad spec, nothing
    written) or :class:`BatchError` (cannot start)."""
    opts = opts or BatchOptions()
    spec_path = Path(spec_path)
    if opts.slurm is not None:
        opts = replace(opts, slurm=check_slurm(opts.slurm))
    batch, plan = load_plan(spec_path, max_cases=opts.max_cases)
    check_confirm(batch, plan)
    check_cores(opts, plan)
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
            extra = confirm_plan(batch, plan, runner.write_results(), batch_dir)
            if extra:   # the 3D confirmations of the thin-film map's transitions
                outcome, kept = runner.outcome, runner.skipped
                plan = plan + extra
                atomic_write_json(batch_dir / PLAN, [pc.to_json() for pc in plan])
                runner = BatchRunner(batch_dir, plan, executor, rerun_failed=opts.rerun_failed,
                                     progress=progress)
                runner.outcome.update(outcome)
                runner.skipped = kept + [i for i in runner.skipped if i.startswith(PREFIX)]
                progress.log(f"confirm: {len(extra)} cases either side of the thin-film "
                             f"transitions on the {batch.confirm.rung} rung "
                             f"({batch.confirm.scene}), from the thin-film states")
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


def dry_run(spec_path: str | Path, out: Path | None = None,
            max_cases: int = DEFAULT_MAX_CASES) -> str:
    """The plan as a table (id, ramp, estimated CPU) without building anything; a batch of
    more than ``max_cases`` cases is refused as by :func:`run_batch`."""
    from ehlfoam.gap.source import spec_key

    spec_path = Path(spec_path)
    batch, plan = load_plan(spec_path, max_cases=max_cases)
    check_confirm(batch, plan)
    batch_dir = batch_folder(spec_path, out)
    lines = [f"batch {batch.name}: {len(plan)} cases -> {batch_dir}"]
    if batch.confirm is not None:
        lines.append(f"  then two {batch.confirm.rung} {batch.confirm.scene} cases at each "
                     f"thin-film transition (confirm_...), from the thin-film states")
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
