"""Hostile scenarios for processes, runs and overwrites (issue 73, points 3, 4 and 7).

One table, :data:`SCENARIOS`, one row per scenario: its name, what is done, the exit code of
the command judged, the words its message must hold, and what may be left on disk; one
parametrized test runs them. Every row asserts the exit code, the message (no Traceback),
what is left (checked by the scenario), and that no process of the scenario survives it (its
process tree as seen just before a kill, and anything working in its folders: helper
:mod:`tests.hostile.procs`). The kill rows print a line of the kill matrix (moment ->
processes left, rows lost/duplicated, resume exit code); ``pytest -rP`` shows them.

- refusals (no OpenFOAM): ``--overwrite`` of what the tool did not make or of a case being
  run, bad ``--start-from`` sources found before anything is written, bad ``run`` folders;
- runs (``openfoam``): SIGKILL of ``ehlfoam run`` (serial, 2 ranks), concurrent runs, the
  case folder removed mid-run, failures before the first time step, a stale decomposition;
- batches (``openfoam``, ``slow``): SIGKILL of ``ehlfoam batch`` during the EHL precalc of
  a new contact, the case build, the solver (serial, 2 ranks), the metrics, the report.
"""

from __future__ import annotations

import fcntl
import json
import os
import shutil
import struct
import subprocess
import sys
import time
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest

import ehlfoam

from ehlfoam.batch.folder import case_status, lock_is_held
from ehlfoam.batch.results import read_results
from ehlfoam.case.geometry import META
from ehlfoam.case.ownership import MARKER, run_lock_held
from ehlfoam.case.writer import write_case
from ehlfoam.report.case_data import load_case
from ehlfoam.run import fields as case_fields
from ehlfoam.seed.snapshot import save_snapshot
from ehlfoam.spec.case import make_case_spec
from tests.hostile import procs
from tests.tiny import SMALL

EHLFOAM = str(Path(sys.executable).parent / "ehlfoam")
ROOT = Path(__file__).resolve().parents[2]
IS_ROOT = os.geteuid() == 0 and shutil.which("unshare") is not None

#: the tiny case, run long enough (50 ms) to be killed while it runs
LONG = {**SMALL, "run": {**SMALL["run"], "end_time": 0.05}}
def _toml(value) -> str:
    """A TOML value: a number, a string, or a table inline."""
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_toml(v)}" for k, v in value.items()) + " }"
    return json.dumps(value) if isinstance(value, str) else repr(value)


#: the tiny case as a case spec file
SPEC_TOML = "\n".join(f"{k} = {_toml(v)}" for k, v in SMALL.items()) + "\n"
#: the tiny case as a batch's [base] (3 ms, 11 writes; NPROCS: run.n_procs)
BATCH_BASE = "[base]\n" + "\n".join(
    f"{k} = {_toml(v)}" for k, v in {**SMALL, "name": "b", "run": {
        "end_time": 3e-3, "writes_per_transit": 250, "n_procs": 0}}.items()
    if k != "name").replace("n_procs = 0", "n_procs = NPROCS") + "\n"


@dataclass
class Result:
    """What a scenario did: the exit code and message of the command judged, the processes
    to account for, the folders nothing may keep working in, a kill-matrix line."""

    rc: int
    message: str
    procs: dict[int, int] = field(default_factory=dict)
    folders: list[Path] = field(default_factory=list)
    matrix: str = ""


@dataclass(frozen=True)
class Hostile:
    """A row of the table."""

    name: str
    scenario: str
    rc: int
    words: tuple[str, ...]
    left: str
    run: Callable[[Path, "Lab"], Result]


# ------------------------------------------------------------------ shared pieces
class Lab:
    """Cases built once per module (copied by each scenario) and the commands."""

    def __init__(self, base: Path):
        self.base = base
        self._built: dict[str, Path] = {}

    def built(self, name: str = "long", n_procs: int = 1) -> Path:
        if name not in self._built:
            spec = {**LONG, "run": {**LONG["run"], "n_procs": n_procs}}
            write_case(make_case_spec(spec), self.base / name)
            self._built[name] = self.base / name
        return self._built[name]

    def case(self, tmp: Path, name: str = "long", n_procs: int = 1, dst: str = "case") -> Path:
        out = tmp / dst
        shutil.copytree(self.built(name, n_procs), out)
        return out

    def spec_file(self, tmp: Path) -> Path:
        path = tmp / "spec.toml"
        path.write_text(SPEC_TOML)
        return path

    def snapshot(self, tmp: Path) -> Path:
        """A real case snapshot, of a built case given a write (its initial fields)."""
        case = self.case(tmp, dst="snapped")
        shutil.copytree(case / "0.orig", case / "0.0001")
        path = tmp / "state.npz"
        save_snapshot(case, path)
        shutil.rmtree(case)
        return path


def cli(*args: str, cwd: Path, env: dict | None = None,
        timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([EHLFOAM, *args], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout, env=env, start_new_session=True)


def start(*args: str, cwd: Path, env: dict | None = None) -> subprocess.Popen:
    return subprocess.Popen([EHLFOAM, *args], cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, env=env,
                            start_new_session=True)


def flip_a_byte(npz: Path, member: str = "alpha.oil.npy") -> None:
    """Flip one bit in the middle of ``member``'s compressed data (not in a header field
    that readers ignore, such as the zip64 sizes of a local header)."""
    with zipfile.ZipFile(npz) as z:
        info = z.getinfo(member)
    data = bytearray(npz.read_bytes())
    start = info.header_offset
    name_len, extra_len = struct.unpack("<HH", data[start + 26:start + 30])
    data[start + 30 + name_len + extra_len + info.compress_size // 2] ^= 0x01
    npz.write_bytes(bytes(data))


def snapshot_of_folder(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def nothing_beside(tmp: Path, keep: set[str]) -> None:
    extra = sorted(p.name for p in tmp.iterdir() if p.name not in keep)
    assert not extra, f"left behind: {extra}"


def times(case: Path) -> int:
    """Time folders in ``case``; 0 when it is absent or vanishes while read (a
    staging folder the builder renames into place)."""
    try:
        return len(case_fields.time_folders(case))
    except (FileNotFoundError, NotADirectoryError):
        return 0


def kill_when(proc: subprocess.Popen, ready: Callable[[], bool], what: str,
              timeout: float = 120.0, after: float = 0.0,
              still: Callable[[], bool] | None = None) -> dict[int, int]:
    """Wait for ``ready``, take the process tree, SIGKILL ``proc``; returns the tree.
    ``still``: true when the moment has not passed yet, checked right before the kill."""
    procs.wait_for(ready, proc, timeout, what)
    if after:
        time.sleep(after)
    tree = procs.tree(proc.pid)
    TREES.append(tree)
    COMMANDS.update({pid: procs.command_line(pid) for pid in tree})
    in_time = still() if still is not None else True
    proc.kill()
    try:
        proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:   # its output pipe is held open by a survivor
        raise AssertionError(f"processes of the killed command survive (its output stays "
                             f"open): {procs.survivors(tree, [], timeout=0)}") from None
    assert in_time, f"the kill came after {what} was over"
    return tree


#: the command lines of the processes of the trees taken (read before they are killed)
COMMANDS: dict[int, str] = {}
#: the trees taken, for the clean-up after a failed scenario
TREES: list[dict[int, int]] = []


def solver_pids(tree: dict[int, int]) -> list[int]:
    return [p for p in tree
            if "interFoam" in COMMANDS.get(p, "") or "interFoam" in procs.command_line(p)]


# ------------------------------------------------------------------ refusals
def overwrite_non_case(tmp: Path, lab: Lab) -> Result:
    thesis = tmp / "thesis"
    thesis.mkdir()
    (thesis / "thesis.tex").write_text("four years of work\n")
    before = snapshot_of_folder(thesis)
    p = cli("case", str(lab.spec_file(tmp)), "--out", "thesis", "--overwrite", cwd=tmp)
    assert snapshot_of_folder(thesis) == before
    nothing_beside(tmp, {"thesis", "spec.toml"})
    return Result(p.returncode, p.stderr)


def overwrite_working_folder(tmp: Path, lab: Lab) -> Result:
    work = tmp / "work"
    work.mkdir()
    (work / "notes.txt").write_text("data\n")
    spec = lab.spec_file(work)
    before = snapshot_of_folder(work)
    p = cli("case", str(spec), "--out", ".", "--overwrite", cwd=work)
    assert snapshot_of_folder(work) == before
    nothing_beside(tmp, {"work"})
    return Result(p.returncode, p.stderr)


def case_into_empty_working_folder(tmp: Path, lab: Lab) -> Result:
    work = tmp / "empty"
    work.mkdir()
    p = cli("case", str(lab.spec_file(tmp)), "--out", ".", cwd=work)
    assert not any(work.iterdir())
    nothing_beside(tmp, {"empty", "spec.toml"})
    return Result(p.returncode, p.stderr)


def overwrite_folder_holding_cwd(tmp: Path, lab: Lab) -> Result:
    case = lab.case(tmp)               # an ehlfoam case, but the working folder is inside
    sub = case / "system"
    before = snapshot_of_folder(case)
    p = cli("case", str(lab.spec_file(tmp)), "--out", "..", "--overwrite", cwd=sub)
    assert snapshot_of_folder(case) == before
    return Result(p.returncode, p.stderr)


def out_is_a_file(tmp: Path, lab: Lab) -> Result:
    (tmp / "afile").write_text("x")
    p = cli("case", str(lab.spec_file(tmp)), "--out", "afile", "--overwrite", cwd=tmp)
    assert (tmp / "afile").read_text() == "x"
    nothing_beside(tmp, {"afile", "spec.toml"})
    return Result(p.returncode, p.stderr)


def case_without_overwrite(tmp: Path, lab: Lab) -> Result:
    case = lab.case(tmp)
    before = snapshot_of_folder(case)
    p = cli("case", str(lab.spec_file(tmp)), "--out", "case", cwd=tmp)
    assert snapshot_of_folder(case) == before
    return Result(p.returncode, p.stderr)


def overwrite_locked_case(tmp: Path, lab: Lab) -> Result:
    case = lab.case(tmp)
    with open(case / META / "run.lock", "a") as fh:     # a run holds it
        fcntl.flock(fh, fcntl.LOCK_EX)
        before = snapshot_of_folder(case)
        p = cli("case", str(lab.spec_file(tmp)), "--out", "case", "--overwrite", cwd=tmp)
    after = snapshot_of_folder(case)
    assert after == before, "the case being run was touched"
    nothing_beside(tmp, {"case", "spec.toml"})
    return Result(p.returncode, p.stderr)


def overwrite_with_bad_start(tmp: Path, lab: Lab) -> Result:
    case = lab.case(tmp)
    before = snapshot_of_folder(case)
    bad = lab.snapshot(tmp)
    flip_a_byte(bad)
    p = cli("case", str(lab.spec_file(tmp)), "--out", "case", "--overwrite",
            "--start-from", str(bad), cwd=tmp)
    assert snapshot_of_folder(case) == before, "the earlier case was lost"
    nothing_beside(tmp, {"case", "spec.toml", "state.npz"})
    return Result(p.returncode, p.stderr)


def _start_refused(tmp: Path, lab: Lab, source: Path, keep: set[str]) -> Result:
    p = cli("case", str(lab.spec_file(tmp)), "--out", "new", "--start-from", str(source),
            cwd=tmp)
    assert not (tmp / "new").exists()
    nothing_beside(tmp, keep | {"spec.toml"})
    return Result(p.returncode, p.stderr)


def start_fake_time_folder(tmp: Path, lab: Lab) -> Result:
    src = lab.case(tmp, dst="source")
    (src / "0.5").mkdir()
    (src / "0.5" / "alpha.oil").write_text("FoamFile { class volScalarField; }\n"
                                            "internalField nonuniform List<scalar> ( 1 2 \n")
    return _start_refused(tmp, lab, src, {"source"})


def start_flipped_snapshot(tmp: Path, lab: Lab) -> Result:
    snap = lab.snapshot(tmp)
    flip_a_byte(snap)
    return _start_refused(tmp, lab, snap, {"state.npz"})


def start_truncated_snapshot(tmp: Path, lab: Lab) -> Result:
    snap = lab.snapshot(tmp)
    snap.write_bytes(snap.read_bytes()[: snap.stat().st_size // 2])
    return _start_refused(tmp, lab, snap, {"state.npz"})


def start_npz_not_a_state(tmp: Path, lab: Lab) -> Result:
    other = tmp / "other.npz"
    np.savez(other, x=np.arange(3.0), y=np.ones(2))
    return _start_refused(tmp, lab, other, {"other.npz"})


def start_missing(tmp: Path, lab: Lab) -> Result:
    return _start_refused(tmp, lab, tmp / "nowhere", set())


def run_missing_folder(tmp: Path, lab: Lab) -> Result:
    p = cli("run", "nowhere", cwd=tmp)
    nothing_beside(tmp, set())
    return Result(p.returncode, p.stderr)


def run_not_a_case(tmp: Path, lab: Lab) -> Result:
    (tmp / "thesis").mkdir()
    (tmp / "thesis" / "thesis.tex").write_text("x")
    p = cli("run", "thesis", cwd=tmp)
    assert sorted(os.listdir(tmp / "thesis")) == ["thesis.tex"]
    return Result(p.returncode, p.stderr)


# ------------------------------------------------------------------ runs
def _after_run_kill(tmp: Path, case: Path, tree: dict[int, int], moment: str) -> Result:
    left = procs.survivors(tree, [tmp])
    assert not left, f"survived the SIGKILL of ehlfoam run: {left}"
    assert not run_lock_held(case), "the run lock is still held"
    raw = json.loads((case / "metrics.json").read_text())["status"]
    assert load_case(case).status == "interrupted"          # what the report says
    assert case_status(case) == "interrupted"               # what the batch says
    ehlfoam.read_metrics(case)                      # the public reader settles the file:
    settled = json.loads((case / "metrics.json").read_text())
    assert settled["status"] == "interrupted", settled
    resume = cli("run", "case", "--quiet", "--wall-limit", "2", cwd=tmp)
    m = json.loads((case / "metrics.json").read_text())
    assert m["status"] == "finished" and m["end_reason"] == "wall_limit", m
    matrix = (f"{moment}: processes left 0, run lock free, metrics.json {raw!r} read as "
              f"interrupted (monitor_killed), resume exit {resume.returncode}")
    return Result(resume.returncode, f"{settled['end_reason']}: {settled['reason']}\n"
                  f"{resume.stderr}", tree, [tmp], matrix)


def run_sigkill_serial(tmp: Path, lab: Lab) -> Result:
    case = lab.case(tmp)
    proc = start("run", "case", "--quiet", cwd=tmp)
    tree = kill_when(proc, lambda: times(case) >= 2, "two writes")
    assert solver_pids(tree), [COMMANDS.get(p) for p in tree]
    return _after_run_kill(tmp, case, tree, "run, solver serial")


def run_sigkill_mpi(tmp: Path, lab: Lab) -> Result:
    case = lab.case(tmp, "long2", n_procs=2)
    proc = start("run", "case", "--quiet", cwd=tmp)
    tree = kill_when(proc, lambda: times(case / "processor0") >= 2, "two writes of the ranks")
    assert len(solver_pids(tree)) >= 2, [COMMANDS.get(p) for p in tree]
    return _after_run_kill(tmp, case, tree, "run, solver on 2 ranks")


def _holds(pid: int, path: str) -> bool:
    """The process has ``path`` open (it holds the flock taken on it)."""
    try:
        return any(os.readlink(f"/proc/{pid}/fd/{fd}") == path
                   for fd in os.listdir(f"/proc/{pid}/fd"))
    except OSError:
        return False


def run_concurrent(tmp: Path, lab: Lab) -> Result:
    """A second run is refused while the first runs; the solver holds the run lock too, and
    after a SIGKILL of the monitor the lock stays held as long as a solver lives."""
    case = lab.case(tmp)
    first = start("run", "case", "--quiet", cwd=tmp)
    procs.wait_for(lambda: times(case) >= 1, first, 120, "a write")
    second = cli("run", "case", "--quiet", cwd=tmp)
    overwrite = cli("case", str(lab.spec_file(tmp)), "--out", "case", "--overwrite", cwd=tmp)
    assert overwrite.returncode == 2 and "being run" in overwrite.stderr, overwrite.stderr
    tree = procs.tree(first.pid)
    solvers = solver_pids(tree)
    lock = str(case / META / "run.lock")
    assert solvers and all(_holds(s, lock) for s in solvers), "the solver has no run lock"
    first.kill()
    first.communicate(timeout=30)
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        held = run_lock_held(case)
        holders = [s for s in solvers if _holds(s, lock)]   # after the probe: they held it
        if not holders:
            break
        assert held, f"solvers {holders} live with the run lock open and it is free"
        time.sleep(0.01)
    assert not run_lock_held(case)
    return Result(second.returncode, second.stderr, tree, [tmp])


def run_case_removed(tmp: Path, lab: Lab) -> Result:
    case = lab.case(tmp)
    proc = start("run", "case", "--quiet", cwd=tmp)
    procs.wait_for(lambda: times(case) >= 2, proc, 120, "two writes")
    tree = procs.tree(proc.pid)
    while case.exists():     # the solver may recreate a folder while it is deleted
        shutil.rmtree(case, ignore_errors=True)
        time.sleep(0.2)
        if proc.poll() is not None:
            shutil.rmtree(case, ignore_errors=True)
    out, _ = proc.communicate(timeout=60)
    line = json.loads([ln for ln in out.splitlines() if ln.startswith("{")][-1])
    assert line["end_reason"] == "case_removed" and line["status"] == "failed", line
    assert not case.exists()
    return Result(proc.returncode, line["reason"], tree, [tmp])


def run_path_with_space(tmp: Path, lab: Lab) -> Result:
    case = lab.case(tmp, dst="with space")
    before = snapshot_of_folder(case)
    p = cli("run", "with space", "--quiet", cwd=tmp)
    assert snapshot_of_folder(case) == before and not (case / "metrics.json").exists()
    return Result(p.returncode, p.stderr)


def run_solver_cannot_start(tmp: Path, lab: Lab) -> Result:
    case = lab.case(tmp)
    env = {**os.environ, "EHLFOAM_FOAM": "prefix",
           "EHLFOAM_FOAM_PREFIX": str(tmp / "no-such-wrapper")}
    p = cli("run", "case", "--quiet", cwd=tmp, env=env)
    m = json.loads((case / "metrics.json").read_text())
    assert m["status"] == "failed" and m["end_reason"] == "start_failed", m
    assert not run_lock_held(case)
    return Result(p.returncode, m["reason"])


def run_stale_decomposition(tmp: Path, lab: Lab) -> Result:
    """run.n_procs = 2, but decomposeParDict and the processor folders say 3 (a hand edit,
    an earlier spec): the run writes the dictionary from the spec and decomposes afresh."""
    case = lab.case(tmp, "long2", n_procs=2)
    text = (case / "system" / "decomposeParDict").read_text()
    (case / "system" / "decomposeParDict").write_text(
        text.replace("numberOfSubdomains 2", "numberOfSubdomains 3").replace("(2 1 1)",
                                                                            "(3 1 1)"))
    shutil.copytree(case / "0.orig", case / "0")
    assert cli("foam", "decomposePar", "-force", cwd=case).returncode == 0
    assert len(list(case.glob("processor*"))) == 3
    p = cli("run", "case", "--quiet", "--wall-limit", "3", cwd=tmp)
    assert sorted(x.name for x in case.glob("processor*")) == ["processor0", "processor1"]
    assert "numberOfSubdomains 2" in (case / "system" / "decomposeParDict").read_text()
    m = json.loads((case / "metrics.json").read_text())
    assert m["status"] == "finished", m
    return Result(p.returncode, p.stderr + m["end_reason"])


def run_kill_at_start(tmp: Path, lab: Lab) -> Result:
    """SIGKILL while the run decomposes the case (before the solver starts)."""
    case = lab.case(tmp, "long2", n_procs=2)
    proc = start("run", "case", "--quiet", cwd=tmp)
    tree = kill_when(proc, lambda: (case / "log.decomposePar").exists(), "decomposePar",
                     still=lambda: not (case / "log.interFoam").exists())
    return _after_run_kill(tmp, case, tree, "run, decomposing before the solver")


def case_kill_during_overwrite(tmp: Path, lab: Lab) -> Result:
    """SIGKILL of `ehlfoam case --overwrite` while it writes the new case: the earlier case
    stays whole; the same command again replaces it and clears the dead build."""
    case = lab.case(tmp)
    before = snapshot_of_folder(case)
    spec = lab.spec_file(tmp)
    proc = start("case", str(spec), "--out", "case", "--overwrite", cwd=tmp)
    tree = kill_when(proc, lambda: any(tmp.glob(".case.*")), "the new case being written")
    assert snapshot_of_folder(case) == before, "the earlier case was touched"
    resume = cli("case", str(spec), "--out", "case", "--overwrite", cwd=tmp)
    assert (case / META / MARKER).is_file() and snapshot_of_folder(case) != before
    nothing_beside(tmp, {"case", "spec.toml"})
    matrix = (f"case --overwrite, writing the new case: processes left 0, the earlier case "
              f"whole, resume exit {resume.returncode}")
    return Result(resume.returncode, resume.stdout + resume.stderr, tree, [tmp], matrix)


# ------------------------------------------------------------------ batches
def _batch_spec(tmp: Path, n_cases: int, n_procs: int = 1) -> Path:
    speeds = ", ".join(str(0.02 + 0.001 * k) for k in range(n_cases))
    text = BATCH_BASE.replace("NPROCS", str(n_procs)) + f"\n[[sweep]]\ncontact.speed = [{speeds}]\n"
    path = tmp / "b.toml"
    path.write_text(text)
    return path


def _batch(tmp: Path, moment: str, ready: Callable[[Path], bool], *, n_cases: int = 1,
           n_procs: int = 1, report: bool = False, env: dict | None = None,
           after: float = 0.0, still: Callable[[Path], bool] | None = None) -> Result:
    spec = _batch_spec(tmp, n_cases, n_procs)
    batch = tmp / "runs" / "b"
    flags = ["--jobs", "1", "--quiet"] + ([] if report else ["--no-report"])
    proc = start("batch", str(spec), *flags, cwd=tmp, env=env)
    tree = kill_when(proc, lambda: ready(batch), moment, after=after,
                     still=None if still is None else (lambda: still(batch)))
    left = procs.survivors(tree, [tmp])
    plan = [c["id"] for c in json.loads((batch / "plan.json").read_text())]
    cases = [batch / "cases" / cid for cid in plan]
    assert not lock_is_held(batch / "batch.lock")
    held = [c.name for c in cases if run_lock_held(c)]
    running = [c.name for c in cases if case_status(c) == "running"]
    rows = [r["case_id"] for r in read_results(batch)] if (batch / "results.csv").exists() \
        else []
    lost, dup = len(set(plan) - set(rows)), len(rows) - len(set(rows))
    resume = cli("batch", str(spec), *flags, cwd=tmp, env=env)
    final = read_results(batch)
    assert sorted(r["case_id"] for r in final) == sorted(plan), final
    assert [r["status"] for r in final] == ["finished"] * len(plan), final
    assert not list((batch / "cases").glob(".*")), "a half-built case was left behind"
    matrix = (f"{moment}: processes left {len(left)}, run locks held {len(held)}, cases read "
              f"running {len(running)}, rows lost {lost}, duplicated {dup}, resume exit "
              f"{resume.returncode}")
    assert not left, f"survived the SIGKILL of ehlfoam batch: {left}"
    assert not held and not running and not dup, matrix
    return Result(resume.returncode, resume.stdout + resume.stderr, tree, [tmp], matrix)


def batch_during_precalc(tmp: Path, lab: Lab) -> Result:
    cache = tmp / "cache"            # a cache without this contact: the precalc runs
    (cache / "precalc").mkdir(parents=True)
    real = Path(os.environ.get("EHLFOAM_CACHE") or Path.home() / ".cache" / "ehlfoam")
    (cache / "openfoam-trixie").symlink_to(real / "openfoam-trixie")
    env = {**os.environ, "EHLFOAM_CACHE": str(cache)}
    return _batch(tmp, "batch, EHL precalc of a new contact",
                  lambda b: any(p.name.endswith(".lock") for p in (cache / "precalc").iterdir()),
                  env=env, after=1.0,
                  still=lambda b: not any((cache / "precalc").glob("*/summary.json")))


def batch_during_build(tmp: Path, lab: Lab) -> Result:
    return _batch(tmp, "batch, meshing and case build",
                  lambda b: any(b.glob("locks/*.lock")),
                  still=lambda b: not list(b.glob(f"cases/*/{META}/{MARKER}")))


def _solving(batch: Path, sub: str = "") -> bool:
    return any(times(c / sub) >= 2 for c in batch.glob("cases/*")
               if not c.name.startswith("."))


def batch_during_solver(tmp: Path, lab: Lab) -> Result:
    return _batch(tmp, "batch, solver serial", _solving,
                  still=lambda b: not list(b.glob("cases/*/metrics.json"))
                  or _running(b))


def batch_during_mpi_solver(tmp: Path, lab: Lab) -> Result:
    return _batch(tmp, "batch, solver on 2 ranks", lambda b: _solving(b, "processor0"),
                  n_procs=2, still=_running)


def _running(batch: Path) -> bool:
    """A case's metrics.json says running (its solver has not ended)."""
    for p in batch.glob("cases/*/metrics.json"):
        try:
            if json.loads(p.read_text()).get("status") == "running":
                return True
        except (OSError, ValueError):
            pass
    return False


def _metrics_written(batch: Path) -> bool:
    for p in batch.glob("cases/*/metrics.json"):
        try:
            if json.loads(p.read_text()).get("status") == "finished":
                return True
        except (OSError, ValueError):
            pass
    return False


def batch_during_metrics(tmp: Path, lab: Lab) -> Result:
    return _batch(tmp, "batch, metrics of a case just written", _metrics_written, n_cases=2,
                  still=lambda b: not (b / "report").exists())


def batch_during_report(tmp: Path, lab: Lab) -> Result:
    return _batch(tmp, "batch, report drawing (its pool)",
                  lambda b: any(b.glob("cases/*/report")), n_cases=2, report=True,
                  still=lambda b: not (b / "report" / "index.html").exists())


# ------------------------------------------------------------------ the table
OF, SLOW = pytest.mark.openfoam, pytest.mark.slow
NEEDS_ROOT = pytest.mark.skipif(not IS_ROOT, reason="parallel runs of the embedded runtime "
                                                    "need root and unshare")


def _row(name, scenario, rc, words, left, fn, *marks):
    return pytest.param(Hostile(name, scenario, rc, tuple(words), left, fn), id=name,
                        marks=marks)


SCENARIOS = [
    # ---- overwrite: never destroy what the tool did not make (no OpenFOAM run)
    _row("overwrite-non-case", "case SPEC --out thesis --overwrite (a folder with a thesis)",
         2, ["not a case written by ehlfoam", "thesis"], "thesis/thesis.tex untouched",
         overwrite_non_case),
    _row("overwrite-working-folder", "case SPEC --out . --overwrite in a working folder", 2,
         ["working folder"], "the working folder untouched", overwrite_working_folder),
    _row("case-into-empty-working-folder", "case SPEC --out . in an empty working folder", 2,
         ["working folder"], "the folder, empty", case_into_empty_working_folder),
    _row("overwrite-folder-holding-cwd", "case SPEC --out .. --overwrite from inside a case",
         2, ["working folder"], "the case untouched", overwrite_folder_holding_cwd),
    _row("out-is-a-file", "case SPEC --out afile --overwrite", 2, ["not a folder", "afile"],
         "the file untouched", out_is_a_file),
    _row("case-without-overwrite", "case SPEC --out CASE (an earlier case, no --overwrite)",
         2, ["not empty", "--overwrite"], "the case untouched", case_without_overwrite),
    _row("overwrite-locked-case", "case SPEC --out CASE --overwrite, its run lock held", 2,
         ["being run", "run.lock"], "the case untouched, no temporary folder",
         overwrite_locked_case),
    _row("overwrite-with-bad-start", "case --out CASE --overwrite --start-from FLIPPED.npz",
         2, ["--start-from", "cannot be read whole"], "the earlier case whole",
         overwrite_with_bad_start),
    # ---- a bad --start-from is found before anything is written
    _row("start-fake-time-folder", "case --start-from CASE (its last time folder fake)", 2,
         ["--start-from", "0.5/alpha.oil", "cannot be read"], "no case",
         start_fake_time_folder),
    _row("start-flipped-snapshot", "case --start-from SNAPSHOT.npz (a flipped byte)", 2,
         ["--start-from", "snapshot", "cannot be read whole"], "no case",
         start_flipped_snapshot),
    _row("start-truncated-snapshot", "case --start-from SNAPSHOT.npz (cut in half)", 2,
         ["--start-from", "not a readable .npz"], "no case", start_truncated_snapshot),
    _row("start-npz-not-a-state", "case --start-from OTHER.npz (other arrays)", 2,
         ["--start-from", "not a thin-film state"], "no case", start_npz_not_a_state),
    _row("start-missing", "case --start-from NOWHERE", 2, ["--start-from", "nowhere"],
         "no case", start_missing),
    _row("run-missing-folder", "run NOWHERE", 2, ["nowhere", "no such folder"], "nothing",
         run_missing_folder),
    _row("run-not-a-case", "run THESIS (a folder that is no case)", 2, ["thesis"],
         "the folder untouched", run_not_a_case),
    # ---- runs: one run per case, no orphans, end reasons that say what happened
    _row("run-sigkill-serial", "run CASE; SIGKILL after two writes; report; run CASE again",
         0, ["monitor_killed"], "the case, its writes; metrics.json finished after the resume",
         run_sigkill_serial, OF),
    _row("run-sigkill-2-ranks", "run CASE (run.n_procs = 2); SIGKILL; run CASE again", 0,
         ["monitor_killed"], "the case; metrics.json finished after the resume",
         run_sigkill_mpi, OF, NEEDS_ROOT),
    _row("run-kill-at-start", "run CASE (n_procs 2); SIGKILL during decomposePar; run CASE "
         "again", 0, ["monitor_killed"], "the case; metrics.json finished after the resume",
         run_kill_at_start, OF, SLOW, NEEDS_ROOT),
    _row("case-kill-during-overwrite", "case SPEC --out CASE --overwrite; SIGKILL while the "
         "new case is written; the same again", 0, ["case", "cells"],
         "the earlier case whole, then the new one; no temporary folder",
         case_kill_during_overwrite),
    _row("run-concurrent", "run CASE twice at once; case --overwrite meanwhile; SIGKILL of "
         "the first while its solver holds the lock", 2, ["being run", "run.lock"],
         "the first run's case", run_concurrent, OF),
    _row("run-case-removed", "run CASE; rm -rf CASE mid-run", 1, ["removed", "nothing written"],
         "nothing (the folder is gone)", run_case_removed, OF),
    _row("run-path-with-space", "run 'with space' (a path OpenFOAM cannot take)", 2,
         ["OpenFOAM cannot take this path", "a space"],
         "the case untouched, no metrics.json", run_path_with_space, OF),
    _row("run-solver-cannot-start", "EHLFOAM_FOAM=prefix (a wrapper that does not exist) run "
         "CASE", 1, ["cannot start", "no-such-wrapper"], "metrics.json start_failed",
         run_solver_cannot_start, OF),
    _row("run-stale-decomposition", "run CASE (n_procs 2) with decomposeParDict and "
         "processor folders for 3", 0, ["wall_limit"], "processor0, processor1",
         run_stale_decomposition, OF, SLOW, NEEDS_ROOT),
    # ---- batches: SIGKILL at six moments, then the resume
    _row("batch-kill-precalc", "batch B; SIGKILL during the EHL precalc of a new contact; "
         "batch B again", 0, ["1 cases"], "results.csv, one finished row",
         batch_during_precalc, OF, SLOW),
    _row("batch-kill-build", "batch B; SIGKILL while the case is meshed and built; batch B "
         "again", 0, ["1 cases"], "results.csv, one finished row", batch_during_build, OF,
         SLOW),
    _row("batch-kill-solver", "batch B; SIGKILL while the serial solver runs; batch B again",
         0, ["1 cases"], "results.csv, one finished row", batch_during_solver, OF, SLOW),
    _row("batch-kill-solver-2-ranks", "batch B (n_procs 2); SIGKILL while the ranks run; "
         "batch B again", 0, ["1 cases"], "results.csv, one finished row",
         batch_during_mpi_solver, OF, SLOW, NEEDS_ROOT),
    _row("batch-kill-metrics", "batch B (2 cases); SIGKILL as the first case's metrics.json "
         "is written; batch B again", 0, ["2 cases"], "results.csv, two finished rows",
         batch_during_metrics, OF, SLOW),
    _row("batch-kill-report", "batch B (2 cases); SIGKILL while the case reports are drawn "
         "(a pool of 2); batch B again", 0, ["2 cases", "batch report"],
         "results.csv, two finished rows, the report", batch_during_report, OF, SLOW),
]


@pytest.fixture(scope="module")
def lab(tmp_path_factory) -> Lab:
    return Lab(tmp_path_factory.mktemp("lab"))


@pytest.mark.parametrize("row", SCENARIOS)
def test_hostile_process_scenario(row: Hostile, lab: Lab, tmp_path: Path) -> None:
    work = tmp_path / "w"
    work.mkdir()
    result = None
    try:
        result = row.run(work, lab)
        assert result.rc == row.rc, (row.scenario, result.rc, result.message)
        assert "Traceback" not in result.message, result.message
        missing = [w for w in row.words if w not in result.message]
        assert not missing, f"{row.scenario}: {missing} not in {result.message!r}"
        left = procs.survivors(result.procs, [work, *result.folders])
        assert not left, f"{row.scenario}: processes left {left}"
        if result.matrix:
            print(f"KILL MATRIX | {result.matrix}")
    finally:
        for tree in TREES:
            procs.kill_all(tree)
        TREES.clear()
