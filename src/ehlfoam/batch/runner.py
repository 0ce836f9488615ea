"""Scheduling one batch run: its tasks (the EHL precalcs of new contacts, then the cases; a ramp
step after the step before it) on an executor, longest chain first within the CPU budget;
progress, a lost worker's retry, Ctrl-C, and results.csv after every case."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ehlfoam.batch.case import oneline, precalc_cached, record_worker_lost
from ehlfoam.batch.folder import CASES, LOCKS, STATUSES, case_status, file_lock, metrics_or_none
from ehlfoam.batch.progress import Progress, sim_fraction
from ehlfoam.batch.results import write_results
from ehlfoam.batch.plan import PRECALC_CPU_S, PlannedCase, est_cpu_s
from ehlfoam.metrics.record import MetricsRecord
from ehlfoam.notices import NoticeTally

POLL_S = 0.5


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
        self.inflight: dict[str, tuple[Any, Task]] = {}
        self.done_cost = 0.0
        self.outcome: dict[str, str] = {}
        self.retried: set[str] = set()
        self.notices = NoticeTally(progress.log)   # each warning once per batch
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
        from ehlfoam.gap.source import spec_key

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
    def _live_cases(self) -> set[str]:
        """The ids of the cases in flight."""
        return {t.key for _, t in self.inflight.values() if t.kind == "case"}

    def counts(self) -> dict[str, int]:
        live = self._live_cases()
        c = dict.fromkeys(STATUSES, 0)
        for pc in self.plan:
            c[case_status(self.batch_dir / CASES / pc.id, pc.id in live)] += 1
        c["total"] = len(self.plan)
        return c

    def _ready(self) -> list[Task]:
        started = {t.name for _, t in self.inflight.values()}
        ready = [t for t in self.tasks.values() if not t.deps and t.name not in started]
        return sorted(ready, key=lambda t: -t.priority)

    def _submit_ready(self) -> None:
        used = sum(t.cpu for _, t in self.inflight.values())
        cap = self.executor.capacity()
        for t in self._ready():
            if used + t.cpu > cap:
                continue
            fut = self.executor.submit(self.batch_dir, t.kind, t.key, self.rerun_failed, t.cpu)
            self.inflight[t.name] = (fut, t)
            used += t.cpu
            self.progress.log(f"start    {t.key}" if t.kind == "case" else
                              f"start    EHL precalc of the contact of {t.key}")

    def _finish(self, name: str, result: dict) -> None:
        _, task = self.inflight.pop(name)
        self.tasks.pop(name, None)
        self.done_cost += task.cost
        if task.kind == "precalc":
            if result.get("status") != "finished":
                self.progress.log(f"precalc of {task.key}'s contact: {result.get('reason')}")
            self._release(name)
            return
        case = self.batch_dir / CASES / task.key
        status = case_status(case)
        m = metrics_or_none(case) or MetricsRecord()
        self.outcome[task.key] = status
        if status == "finished":
            wall = m.get("case_wall_s") or m.get("wall_s") or 0.0
            word = "kept" if result.get("skipped") else "finished"
            self.progress.log(f"{word:8s} {task.key}: state {m.get('state')}, "
                              f"{m.get('end_reason')}, {wall:.0f} s")
            self.notices.add(task.key, m.get("warnings"))
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
        for name, (fut, task) in list(self.inflight.items()):
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
            self.progress.log(f"retry    {task.key}: worker lost ({oneline(err)})")
            return None
        case = self.batch_dir / CASES / task.key
        if task.kind == "case" and case_status(case) not in ("finished", "failed"):
            with file_lock(self.batch_dir / LOCKS / f"{task.key}.lock", timeout=5.0) as got:
                if got:
                    record_worker_lost(case, task.key, f"worker lost: {oneline(err)}")
        return {"id": task.key, "status": "failed", "reason": oneline(err)}

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
        for _, task in self.inflight.values():
            if task.kind == "case":
                pc = self.by_id[task.key]
                frac = sim_fraction(self.batch_dir / CASES / task.key, pc.spec.end_time)
                partial += task.cost * frac
        total = self.done_cost + sum(t.cost for t in self.tasks.values())
        frac = (self.done_cost + partial) / total if total > 0 else 1.0
        self.progress.update(frac, self.counts(), self._eta(partial))

    def write_results(self) -> list[dict]:
        return write_results(self.batch_dir, self.plan, self._live_cases(), self.blocked)

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
        if summary := self.notices.summary():
            self.progress.log(summary)

    def stop(self) -> None:
        """Ctrl-C / SIGTERM: stop the cases in flight (they write ``interrupted``), wait for
        their workers, keep results.csv right. A second Ctrl-C stops waiting."""
        self.progress.log(f"interrupted: stopping {len(self.inflight)} task(s) in flight")
        self.executor.interrupt()
        deadline = time.monotonic() + 150.0
        try:
            while self.inflight and time.monotonic() < deadline:
                for name, (fut, _) in list(self.inflight.items()):
                    if fut.done():
                        self.inflight.pop(name)
                time.sleep(POLL_S)
        except KeyboardInterrupt:
            pass
        self.inflight.clear()

