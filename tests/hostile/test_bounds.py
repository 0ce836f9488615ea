"""Hostile inputs on the bounds of work and on what generated scripts carry (issue 73, points
5 and 6): huge sweeps and ranges, n_procs beyond the cores, limits that are not positive
finite numbers, cases too big to build, hostile runtime paths in the hand-run Allrun and
hostile ``--slurm`` values.

Each row of :data:`CASES` is one input: a name, the command line (run in-process through
``ehlfoam.cli.main.main`` in a fresh folder), the exit code it must end with, the words its
message must hold, and what it may leave on disk. The one parametrized test asserts all of
them, and that no exception escaped (an escaped exception is what prints a traceback).
The inputs that start OpenFOAM (the Allrun rows) are at the end, marked ``openfoam``.

The counts the issue asks for come off the table: ``len(CASES)`` inputs; every row with
exit 2 is a refusal that must be clean (message words, no traceback, nothing written).
"""

from __future__ import annotations

import io
import os
import resource
import shlex
import signal
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager, redirect_stderr, redirect_stdout
from dataclasses import dataclass, field
from pathlib import Path

import psutil
import pytest

from tests.tiny import SMALL

# ------------------------------------------------------------------ the inputs
TOML_SMALL = """
name = "test"
contact = {speed = 0.02, grid = 129, tol_residual = 1e-4}
mesh = {resolution = "coarse", size_rim = 0.25, size_far = 1.2, n_layers = 3, wall_grading = 3.0}
domain = {upstream = 5.0, downstream = 7.0, side = 5.0}
[supply]
mode = "layers"
disc_layer = 3e-6
ball_layer = 3e-6
track_half_width = 2.5e-4
initial_puddle = 3.0
[run]
end_time = 1e-3
writes_per_transit = 1000
"""

#: batch specs by name (written as NAME.toml in the test's folder)
SPECS = {
    "product": "[sweep]\ncontact.speed = {start = 0.005, stop = 0.025, num = 1000}\n"
               "contact.load = {start = 10, stop = 30, num = 1000}\n",
    "num1e9": "[sweep]\ncontact.speed = {start = 0.005, stop = 0.025, num = 1000000000}\n",
    "step1e-12": "[sweep]\ncontact.speed = {start = 0.005, stop = 0.025, step = 1e-12}\n",
    "overflow": "[sweep]\ncontact.speed = {start = 0.0, stop = 1e300, step = 1e-300}\n",
    "ramp1e9": "[[ramp]]\nname = \"A\"\n"
               "contact.speed = {start = 0.005, stop = 0.025, num = 1000000000}\n",
    "union": "".join("[[sweep]]\ncontact.speed = {start = 0.005, stop = 0.025, num = 1000}\n"
                     f"contact.load = [{load}]\n" for load in (10, 20, 30)),
    "four": "[base]\nmesh = {resolution = \"coarse\"}\n"
            "[sweep]\ncontact.speed = [0.005, 0.008, 0.012, 0.017]\n",
    "one": "[base]\nmesh = {resolution = \"coarse\"}\n[sweep]\ncontact.speed = [0.005]\n",
    "nprocs1024": "[base]\nrun = {n_procs = 1024}\n[sweep]\ncontact.speed = [0.005]\n",
    "cells1e9": "[base]\nmesh = {size_rim = 1e-3, size_far = 1e-3, n_layers = 64}\n"
                "[sweep]\ncontact.speed = [0.005]\n",
    "steps": "[base]\nrun = {end_time = 1000.0, capillary_safety = 0.5}\n"
             "[sweep]\ncontact.speed = [0.005]\n",
}


@dataclass(frozen=True)
class Case:
    """One hostile input: ``argv`` of ``ehlfoam`` (``{spec:NAME}`` is that batch spec's file,
    ``{case}`` a written case of tests.tiny.SMALL, ``{case1024}`` one with run.n_procs =
    1024), the exit code, the words of the message, the paths it may leave (relative to
    the test's folder)."""

    name: str
    argv: tuple[str, ...]
    exit: int
    words: tuple[str, ...]
    leaves: tuple[str, ...] = ()
    env: dict[str, str] = field(default_factory=dict)


def _c(name: str, argv: str, exit: int, *words: str, leaves: tuple[str, ...] = ()) -> Case:
    return Case(name, tuple(shlex.split(argv)), exit, words, leaves)


CASES: list[Case] = [
    # ---- batches: counted before they are expanded (--max-cases)
    _c("sweep of 10^6 cases", "batch {spec:product}", 2, "1,000,000 cases",
       "1,000 contact.speed x 1,000 contact.load", "max_cases = 2,000", "--max-cases"),
    _c("range num = 1e9", "batch {spec:num1e9}", 2, "1,000,000,000 cases", "--max-cases"),
    _c("range step = 1e-12", "batch {spec:step1e-12}", 2, "20,000,000,001 cases"),
    _c("range whose count overflows", "batch {spec:overflow}", 2, "more than 10^308 cases"),
    _c("ramp of 10^9 speeds", "batch {spec:ramp1e9}", 2, "1,999,999,999 cases",
       "ramp A: 1,999,999,999 steps"),
    _c("dry run of 10^9 cases", "batch {spec:num1e9} --dry-run", 2, "1,000,000,000 cases"),
    _c("three sweeps of 1000", "batch {spec:union} --dry-run", 2, "3,000 cases"),
    _c("4 cases above --max-cases 3", "batch {spec:four} --dry-run --max-cases 3", 2,
       "4 cases", "max_cases = 3"),
    _c("4 cases within --max-cases 4", "batch {spec:four} --dry-run --max-cases 4", 0,
       "4 cases"),
    _c("--max-cases 0", "batch {spec:four} --dry-run --max-cases 0", 2, "--max-cases", ">= 1"),
    _c("--max-cases -5", "batch {spec:four} --dry-run --max-cases=-5", 2, "--max-cases"),
    _c("--max-cases nan", "batch {spec:four} --dry-run --max-cases nan", 2, "--max-cases"),
    # ---- batches: cores
    _c("batch run.n_procs = 1024", "batch {spec:nprocs1024}", 2, "run.n_procs = 1024",
       "CPU cores", "--oversubscribe"),
    _c("batch --cores 100000", "batch {spec:one} --cores 100000", 2, "--cores = 100000",
       "--oversubscribe"),
    _c("batch --jobs 100000", "batch {spec:one} --jobs 100000", 2, "--jobs = 100000",
       "--oversubscribe"),
    _c("run.n_procs beyond --slurm cores", "batch {spec:nprocs1024} --slurm cores=4", 2,
       "run.n_procs = 1024", "--slurm cores = 4"),
    # ---- batches: cases too big
    _c("batch case of 10^9 cells", "batch {spec:cells1e9} --dry-run", 2, "mesh.max_cells",
       "cells", "u05.0_flooded"),
    _c("batch case of 10^7 steps", "batch {spec:steps} --dry-run", 2, "run.max_steps",
       "time steps"),
    # ---- --slurm values (refused before dask-jobqueue writes its sbatch script)
    _c("--slurm queue with ;", "batch {spec:one} --dry-run --slurm queue=a;reboot", 2,
       "--slurm queue", "partition"),
    _c("--slurm account $(...)", "batch {spec:one} --dry-run --slurm account=$(id)", 2,
       "--slurm account"),
    _c("--slurm memory with a newline", "batch {spec:one} --dry-run --slurm "
       "'memory=4GB\n#SBATCH --wrap=id'", 2, "--slurm memory", "4GB"),
    _c("--slurm walltime 1h", "batch {spec:one} --dry-run --slurm walltime=1h", 2,
       "--slurm walltime", "HH:MM:SS"),
    _c("--slurm walltime with a command", "batch {spec:one} --dry-run --slurm "
       "'walltime=01:00:00 `id`'", 2, "--slurm walltime"),
    _c("--slurm python with a space", "batch {spec:one} --dry-run --slurm "
       "'python=/usr/bin/python3 -c import os'", 2, "--slurm python"),
    _c("--slurm cores 0", "batch {spec:one} --dry-run --slurm cores=0", 2, "--slurm cores",
       "1 <= cores"),
    _c("--slurm jobs 1e3", "batch {spec:one} --dry-run --slurm jobs=1e3", 2, "--slurm jobs"),
    _c("--slurm unknown key", "batch {spec:one} --dry-run --slurm nodes=3", 2, "KEY=VALUE"),
    _c("--slurm key twice", "batch {spec:one} --dry-run --slurm queue=a,queue=b", 2,
       "given twice"),
    # ---- case: too big to build (before the precalc and the mesher)
    _c("case of 10^9 cells", "case {toml} --out out --set mesh.size_rim=1e-3 "
       "--set mesh.size_far=1e-3 --set mesh.n_layers=64", 2, "mesh.max_cells", "cells"),
    _c("case of 10^7 time steps", "case {toml} --out out --set run.end_time=1000.0 "
       "--set run.capillary_safety=0.5", 2,
       "run.max_steps", "time steps"),
    _c("case mesh.max_cells = 0", "case {toml} --out out --set mesh.max_cells=0", 2,
       "mesh.max_cells"),
    _c("case run.max_steps = -1", "case {toml} --out out --set run.max_steps=-1", 2,
       "run.max_steps"),
    # ---- run: limits and cores
    _c("run --wall-limit -5", "run {case} --wall-limit=-5", 2, "--wall-limit", "-5", "> 0"),
    _c("run --wall-limit nan", "run {case} --wall-limit nan", 2, "--wall-limit", "nan"),
    _c("run --wall-limit inf", "run {case} --wall-limit inf", 2, "--wall-limit", "inf",
       "finite"),
    _c("run --wall-limit 0", "run {case} --wall-limit 0", 2, "--wall-limit"),
    _c("run --wall-limit 1e300", "run {case} --wall-limit 1e300", 2, "--wall-limit",
       "1e+06 s"),
    _c("run --extend 0", "run {case} --extend 0", 2, "--extend"),
    _c("run --extend nan", "run {case} --extend nan", 2, "--extend", "nan"),
    _c("run --extend inf", "run {case} --extend inf", 2, "--extend", "inf"),
    _c("run --extend 1e9 transits", "run {case} --extend 1e9", 2, "--extend",
       "run.max_steps"),
    _c("run run.n_procs = 1024", "run {case1024}", 2, "run.n_procs = 1024", "CPU cores",
       "--oversubscribe"),
]


# ------------------------------------------------------------------ helpers
def _tree(root: Path) -> dict[str, tuple[int, int]]:
    """Every path under ``root`` with its size and modification time (what was written)."""
    out = {}
    for p in root.rglob("*"):
        st = p.lstat()
        out[str(p.relative_to(root))] = (st.st_size, st.st_mtime_ns)
    return out


#: Address space a command run in-process may add (a bound that stopped working would
#: otherwise fill the machine's memory: it ends in a MemoryError here instead)
HEADROOM = 2 * 2**30


#: Seconds a command run in-process may take before it counts as a hang
HANG_S = 120


class Hang(BaseException):
    """A command ran past :data:`HANG_S`."""


def _hang(signum, frame):
    raise Hang(f"still running after {HANG_S} s")


@contextmanager
def _bounded() -> Iterator[None]:
    """Memory capped at :data:`HEADROOM` more than now, and an alarm at :data:`HANG_S`."""
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    cap = psutil.Process().memory_info().vms + HEADROOM
    resource.setrlimit(resource.RLIMIT_AS, (cap if hard == resource.RLIM_INFINITY
                                            else min(cap, hard), hard))
    previous = signal.signal(signal.SIGALRM, _hang)
    signal.alarm(HANG_S)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def _main(argv: list[str]) -> tuple[int, str, str]:
    """``ehlfoam ARGV`` in this process, its memory and time bounded: exit code, stdout,
    stderr. An exception that escapes (what the command line would print as a traceback)
    or a hang fails the test."""
    from ehlfoam.cli.main import main

    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err), _bounded():
        try:
            code = main(argv)
        except SystemExit as exc:   # argparse inside a subcommand
            code = exc.code if isinstance(exc.code, int) else 2
        except BaseException as exc:  # noqa: BLE001 - a traceback on the command line
            escaped = exc
        else:
            escaped = None
    if escaped is not None:
        pytest.fail(f"{argv}: {type(escaped).__name__} escaped (a traceback): {escaped}")
    return code, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> dict[str, Path]:
    """Cases of tests.tiny.SMALL written once (no OpenFOAM runs): one as is, one with
    run.n_procs = 1024."""
    from ehlfoam.case.writer import write_case
    from ehlfoam.foam.runtime import FoamRuntime
    from ehlfoam.spec.case import make_case_spec

    root = tmp_path_factory.mktemp("built")
    out = {}
    for key, n in (("case", 1), ("case1024", 1024)):
        spec = make_case_spec({**SMALL, "run": {**SMALL["run"], "n_procs": n}})
        # a native runtime: the parallel command of a case needs no root then
        write_case(spec, root / key, runtime=FoamRuntime.native())
        out[key] = root / key
    return out


def _argv(case: Case, folder: Path, built: dict[str, Path]) -> list[str]:
    subs = {"{case}": str(built["case"]), "{case1024}": str(built["case1024"]),
            "{toml}": str(folder / "small.toml")}
    argv = []
    for word in case.argv:
        if word.startswith("{spec:"):
            name = word[len("{spec:"):-1]
            (folder / f"{name}.toml").write_text(SPECS[name])
            word = str(folder / f"{name}.toml")
        argv.append(subs.get(word, word))
    return argv


# ------------------------------------------------------------------ the table
@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_hostile_bound(case: Case, tmp_path, monkeypatch, built):
    folder = tmp_path / "work"
    folder.mkdir()
    (folder / "small.toml").write_text(TOML_SMALL)
    argv = _argv(case, folder, built)
    monkeypatch.chdir(folder)
    before, cases_before = _tree(folder), {k: _tree(v) for k, v in built.items()}
    code, out, err = _main(argv)
    assert code == case.exit, (argv, out, err)
    assert "Traceback" not in err
    text = err if case.exit else out
    for word in case.words:
        assert word in text, (word, text)
    if case.exit:
        message = [ln for ln in err.splitlines() if ln.startswith("ehlfoam")]
        assert len(message) == 1, err            # one line says what was wrong
    left = set(_tree(folder)) - set(before) - set(case.leaves)
    assert not left, f"written: {sorted(left)}"
    for k, v in built.items():                   # the cases ran on are left as they were
        assert _tree(v) == cases_before[k], k


def test_the_table_is_large_enough():
    refused = [c for c in CASES if c.exit == 2]
    assert len(CASES) >= 15 and len(refused) >= 15
    assert len({c.name for c in CASES}) == len(CASES)


# ------------------------------------------------------------------ no expansion
@pytest.mark.parametrize("name", ["num1e9", "step1e-12", "ramp1e9", "product"])
def test_a_huge_batch_is_refused_without_being_expanded(name, tmp_path):
    """The real command, its address space capped at 3 GiB: expanding 10^9 speeds would need
    some 32 GB (a MemoryError traceback before); counted, it is refused with exit 2."""
    spec = tmp_path / f"{name}.toml"
    spec.write_text(SPECS[name])
    cap = 3 * 2**30

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (cap, cap))

    proc = subprocess.run([sys.executable, "-m", "ehlfoam", "batch", str(spec), "--dry-run"],
                          capture_output=True, text=True, preexec_fn=limit, timeout=120,
                          cwd=tmp_path, env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr and "MemoryError" not in proc.stderr
    assert " cases (" in proc.stderr and "--max-cases" in proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == [spec.name]


def test_a_range_is_counted_before_it_is_made():
    """The count is analytical: the range helpers are refused with the count whatever its
    size (10^300 values could never be made)."""
    from ehlfoam.batch.spec import SpecError, count_cases, parse_batch_spec

    n, parts = count_cases({"sweep": {"contact.speed": {"start": 0.0, "stop": 1.0,
                                                         "num": 10**300}}})
    assert n == 10**300 and parts == ["sweep: about 10^300 contact.speed"]
    with pytest.raises(SpecError, match=r"about 10\^300 cases"):
        parse_batch_spec({"sweep": {"contact.speed": {"start": 0.0, "stop": 1.0,
                                                      "num": 10**300}}})
    # the cap is the caller's: within it the plan is as before
    spec = parse_batch_spec({"sweep": {"contact.speed": {"start": 0.005, "stop": 0.025,
                                                         "num": 5}}}, max_cases=5)
    assert spec.sweep[0].root["contact.speed"] == [0.005, 0.01, 0.015, 0.02, 0.025]


# ------------------------------------------------------------------ Slurm's job script
def test_slurm_job_script_from_good_and_hostile_values():
    """Good values reach dask-jobqueue's sbatch script as given; hostile ones are refused by
    ehlfoam before a script exists (through the API too: BatchOptions.slurm)."""
    from dask_jobqueue.slurm import SLURMJob

    from ehlfoam.batch.executors import check_slurm, slurm_cluster
    from ehlfoam.errors import SpecError

    good = {"cores": 8, "memory": "16GB", "walltime": "1-02:00:00", "queue": "short.q",
            "account": "proj-42", "python": "/opt/py3.12/bin/python3", "jobs": 2}
    cluster = slurm_cluster(good, scale=False)
    try:
        script = cluster.job_script()
    finally:
        cluster.close()
    for text in ("#SBATCH -p short.q", "#SBATCH -A proj-42", "#SBATCH -t 1-02:00:00",
                 "#SBATCH --cpus-per-task=8", "/opt/py3.12/bin/python3 -m distributed"):
        assert text in script, script
    hostile = {"queue": "short\n#SBATCH --wrap='touch PWNED'", "account": "x;id",
               "memory": "16GB$(id)", "walltime": "01:00:00\nid", "python": "python3 -c 'x'",
               "cores": "4; id", "jobs": True}
    # what the check keeps out: dask-jobqueue writes a value as it is
    raw = SLURMJob(scheduler="tcp://127.0.0.1:8786", cores=1, memory="1GB",
                   queue=hostile["queue"]).job_script()
    assert "\n#SBATCH --wrap='touch PWNED'" in raw
    for key, value in hostile.items():
        with pytest.raises(SpecError, match=f"--slurm {key}"):
            check_slurm({**good, key: value})
        with pytest.raises(SpecError, match=f"--slurm {key}"):
            slurm_cluster({**good, key: value}, scale=False)


# ------------------------------------------------------------------ the hand-run Allrun
def _no_process_in(folder: Path) -> list[str]:
    """Processes still running in or with ``folder`` in their command line."""
    left = []
    for p in psutil.process_iter(["pid", "cmdline", "cwd"]):
        try:
            text = " ".join(p.info["cmdline"] or []) + " " + (p.info["cwd"] or "")
        except (psutil.Error, TypeError):
            continue
        if str(folder) in text and p.pid != os.getpid():
            left.append(f"{p.pid} {text}")
    return left


def _runtime_named(tmp_path: Path, name: str) -> Path:
    """A cache folder of that name holding the real runtime and precalcs (symlinks)."""
    from ehlfoam.paths import cache_dir

    real = cache_dir()
    hostile = tmp_path / name
    hostile.mkdir(parents=True)
    (hostile / "openfoam-trixie").symlink_to(real / "openfoam-trixie")
    (real / "precalc").mkdir(parents=True, exist_ok=True)
    (hostile / "precalc").symlink_to(real / "precalc")
    return hostile


def _write_and_run_by_hand(tmp_path: Path, monkeypatch, env: dict[str, str],
                           n_procs: int = 1) -> Path:
    monkeypatch.chdir(tmp_path)
    for k, v in env.items():
        monkeypatch.setenv(k, v)
    (tmp_path / "small.toml").write_text(TOML_SMALL)
    code, out, err = _main(["case", "small.toml", "--out", "c", "--set",
                            f"run.n_procs={n_procs}"])
    assert code == 0, err
    proc = subprocess.run(["bash", "./Allrun"], cwd=tmp_path / "c", capture_output=True,
                          text=True, timeout=120, env={k: v for k, v in os.environ.items()
                                                       if not k.startswith("EHLFOAM")})
    assert proc.returncode == 0, (proc.stdout, proc.stderr,
                                  (tmp_path / "c" / "log.interFoam").read_text()[-2000:])
    return tmp_path / "c"


def _assert_nothing_expanded(tmp_path: Path, case: Path) -> None:
    assert not list(tmp_path.rglob("PWNED")) and not list(tmp_path.rglob("BQ"))
    assert not (Path.cwd() / "PWNED").exists()
    assert "\nEnd\n" in (case / "log.interFoam").read_text()
    assert (case / "0.001").is_dir()                     # the solver reached its end time
    assert not _no_process_in(case)


@pytest.mark.openfoam
def test_allrun_expands_nothing_from_ehlfoam_cache(tmp_path, monkeypatch):
    """EHLFOAM_CACHE with $(...), backquotes, &, |, < and >: the case's Allrun runs the
    solver from that runtime and expands nothing."""
    cache = _runtime_named(tmp_path, "c$(touch${IFS}PWNED)`touch${IFS}BQ`&x|y<z>")
    case = _write_and_run_by_hand(tmp_path, monkeypatch, {"EHLFOAM_CACHE": str(cache)})
    assert f"FOAM_BIN={shlex.quote(str(cache / 'openfoam-trixie/usr/bin'))}" in \
        (case / "Allrun").read_text()
    _assert_nothing_expanded(tmp_path, case)


@pytest.mark.openfoam
@pytest.mark.skipif(os.geteuid() != 0, reason="the embedded runtime's MPI runs need root")
def test_parallel_allrun_expands_nothing_from_ehlfoam_cache(tmp_path, monkeypatch):
    cache = _runtime_named(tmp_path, "c$(touch${IFS}PWNED)`touch${IFS}BQ`")
    case = _write_and_run_by_hand(tmp_path, monkeypatch, {"EHLFOAM_CACHE": str(cache)},
                                  n_procs=2)
    assert (case / "processor1").is_dir()
    _assert_nothing_expanded(tmp_path, case)


@pytest.mark.openfoam
def test_allrun_expands_nothing_from_a_prefix_with_spaces_and_quotes(tmp_path, monkeypatch):
    """EHLFOAM_FOAM=prefix, a wrapper whose path holds $(touch PWNED), a space, both quotes,
    a backquote and ;: the Allrun runs the solver through it and expands nothing."""
    from ehlfoam.foam.runtime import FoamRuntime
    from ehlfoam.paths import cache_dir

    real = FoamRuntime.embedded(cache_dir() / "openfoam-trixie")
    folder = tmp_path / "pre $(touch PWNED) 'q\" `touch BQ`;x"
    folder.mkdir()
    wrapper = folder / "run-foam"
    launch = shlex.join(real.command("APP")[:-1])
    wrapper.write_text(f"#!/bin/sh\napp=$1; shift\n"
                       f"export WM_PROJECT_DIR={shlex.quote(str(real.project_dir))}\n"
                       f"exec {launch} {shlex.quote(str(real.root / 'usr/bin'))}/\"$app\" "
                       f"\"$@\"\n")
    wrapper.chmod(0o755)
    case = _write_and_run_by_hand(tmp_path, monkeypatch, {
        "EHLFOAM_FOAM": "prefix", "EHLFOAM_FOAM_PREFIX": shlex.quote(str(wrapper))})
    _assert_nothing_expanded(tmp_path, case)


def test_a_runtime_path_openfoam_cannot_take_is_refused(tmp_path, monkeypatch):
    """EHLFOAM_CACHE with $(touch PWNED), a space and a quote: OpenFOAM stops on its own
    application path then, so `ehlfoam case` refuses it (exit 2, naming EHLFOAM_CACHE),
    writes nothing and expands nothing."""
    cache = _runtime_named(tmp_path, "ca$(touch PWNED) y'z")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("EHLFOAM_CACHE", str(cache))
    (tmp_path / "small.toml").write_text(TOML_SMALL)
    before = _tree(tmp_path)
    code, out, err = _main(["case", "small.toml", "--out", "c"])
    assert code == 2 and "EHLFOAM_CACHE" in err and "white space" in err, err
    assert _tree(tmp_path) == before
    assert not list(tmp_path.rglob("PWNED"))
