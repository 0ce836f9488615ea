"""Hostile inputs to every subcommand (issue 73, the "inputs" part of its suite): bad numbers,
types, NaN and inf, unknown keys, garbage, binary and huge files, folders for files, hostile
names and paths, read-only and full disks (small tmpfs mounts), corrupt case files.

One table, :data:`CASES`: each row is a scenario (a command line, the files it is given),
the exit code it must end with, the words its one message line must hold, and what it may
leave on disk. One parametrized test runs each row as a real ``ehlfoam`` process (in a
session of its own) and asserts:

- the exit code;
- the message: stderr is one line ``ehlfoam COMMAND: ...`` (after argparse's usage lines,
  for an option argparse refuses) holding the words (regular expressions), and no
  "Traceback" anywhere;
- the files: a listing (path, size, mtime) of the work folder and of the disks before and
  after is the same but for the row's ``left`` paths: nothing half-written, nothing touched;
- the processes: none of the command's session survives it, and it ends within its time
  (no hang; a precalc refused for its --out ends before any solving).

The figures the issue asks for are the table's and the results': rows tried, refused
cleanly (passed), tracebacks, partial writes, hangs and orphans (the assertion that failed).
``EHLFOAM_HOSTILE_SUMMARY=FILE`` writes them as JSON at the end of the module.

The rows that need a case folder use one written by ``ehlfoam case`` from
:data:`tests.tiny.SMALL` (seconds, no OpenFOAM run); the disks are tmpfs mounts, made when the
tests run as root (skipped otherwise).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import psutil
import pytest

from tests.tiny import SMALL, as_toml

EHLFOAM = [sys.executable, "-m", "ehlfoam"]
#: a run of a refused command must end within this [s] (a hang otherwise)
TIMEOUT_S = 60.0


@dataclass(frozen=True)
class Hostile:
    """One hostile input: ``argv`` after ``ehlfoam`` (``{work}``, ``{case}``, ``{ro}``,
    ``{full}``, ``{tight}`` replaced by the work folder, a written case copied into it and
    the disks), ``setup(work)`` making its files first, the exit ``code``, ``words`` (regular
    expressions, case-insensitive) the message must hold, the paths it may ``left`` (relative
    to the work folder), extra ``env``, ``max_s`` a time it must end within, and
    ``with_case``: the written case is copied into the work folder (as ``{case}`` does)."""

    name: str
    argv: tuple[str, ...]
    code: int
    words: tuple[str, ...]
    setup: Callable[[Path], None] | None = None
    left: tuple[str, ...] = ()
    env: dict[str, str] | None = None
    max_s: float = TIMEOUT_S
    with_case: bool = False

    @property
    def command(self) -> str:
        return next(a for a in self.argv if not a.startswith("-"))

    def needs(self, what: str) -> bool:
        return any("{" + what + "}" in a for a in self.argv)


# ------------------------------------------------------------------------- files
def spec(text: str, name: str = "spec.toml") -> Callable[[Path], None]:
    """Setup: a spec file of ``text``."""
    return lambda work: (work / name).write_text(text)


def small(**tables: dict) -> Callable[[Path], None]:
    """Setup: the tiny case's spec with ``tables`` merged in, as spec.toml."""
    data = {k: dict(v) if isinstance(v, dict) else v for k, v in SMALL.items()}
    for table, values in tables.items():
        data.setdefault(table, {}).update(values)
    return spec(as_toml(data))


def binary(name: str) -> Callable[[Path], None]:
    return lambda work: (work / name).write_bytes(bytes(range(256)) * 64)


def huge(name: str) -> Callable[[Path], None]:
    """Setup: a 50 MB file (sparse: refused by its size, never read)."""
    def make(work: Path) -> None:
        with open(work / name, "wb") as fh:
            fh.truncate(50_000_000)
    return make


def folder(name: str) -> Callable[[Path], None]:
    return lambda work: (work / name).mkdir(parents=True)


def file(name: str, text: str = "not a folder\n") -> Callable[[Path], None]:
    return lambda work: (work / name).write_text(text)


def corrupt(rel: str, data: bytes = b"garbage {{{ ;;\n\x00\x01") -> Callable[[Path], None]:
    """Setup: the case's file ``rel`` overwritten with garbage."""
    return lambda work: (work / "case" / rel).write_bytes(data)


def batch_spec(sweep: str, name: str = "b.toml") -> Callable[[Path], None]:
    """Setup: a batch spec of the tiny case with the sweep table ``sweep``."""
    base = "".join(f"[base.{k}]\n" + "".join(f"{kk} = {json.dumps(vv)}\n"
                                              for kk, vv in v.items())
                   for k, v in SMALL.items() if isinstance(v, dict))
    return spec(base + "[sweep]\n" + sweep, name)


def both(*steps: Callable[[Path], None]) -> Callable[[Path], None]:
    return lambda work: [s(work) for s in steps] and None


FOAM_PATH = r"OpenFOAM cannot take this path"
NO_TEXT = r"not a text file"

# ------------------------------------------------------------------------- the table
CASES: list[Hostile] = [
    # doctor
    Hostile("doctor workdir is a file", ("doctor", "--workdir", "f"), 2,
            (r"--workdir f: is a file, not a folder",), setup=file("f")),
    Hostile("doctor workdir has a space", ("doctor", "--workdir", "{work}/a b"), 2,
            (r"--workdir", FOAM_PATH, "a space")),
    Hostile("doctor workdir read-only", ("doctor", "--workdir", "{ro}/check"), 2,
            (r"--workdir .*/check: read-only file system",)),
    Hostile("doctor unknown runtime kind", ("doctor",), 2,
            (r"configuration error", "EHLFOAM_FOAM"), env={"EHLFOAM_FOAM": "bogus"}),
    # precalc
    Hostile("precalc load nan", ("precalc", "--load", "nan", "--out", "p"), 2,
            (r"--load nan: not a finite number", r"valid range 0 < load")),
    Hostile("precalc speed inf", ("precalc", "--speed", "inf", "--out", "p"), 2,
            (r"--speed inf: not a finite number",)),
    Hostile("precalc load true", ("precalc", "--load", "true", "--out", "p"), 2,
            (r"--load true: not a number",)),
    Hostile("precalc grid a fraction", ("precalc", "--grid", "12.5", "--out", "p"), 2,
            (r"--grid 12.5: not an integer",)),
    Hostile("precalc spec load = true", ("precalc", "spec.toml", "--out", "p"), 2,
            (r"load = True: a boolean is not a number",), setup=spec("load = true\n")),
    Hostile("precalc spec speed a string", ("precalc", "spec.toml", "--out", "p"), 2,
            (r"speed = '0.02': a string is not a number",), setup=spec('speed = "0.02"\n')),
    Hostile("precalc spec unknown key", ("precalc", "spec.toml", "--out", "p"), 2,
            (r"lode: unknown key", r"valid here: load"), setup=spec("lode = 20\n")),
    Hostile("precalc spec binary", ("precalc", "b.toml", "--out", "p"), 2,
            (r"spec file = 'b.toml'", NO_TEXT), setup=binary("b.toml")),
    Hostile("precalc spec 50 MB", ("precalc", "h.toml", "--out", "p"), 2,
            (r"50.0 MB is too large for a spec",), setup=huge("h.toml")),
    Hostile("precalc spec a folder", ("precalc", "d", "--out", "p"), 2,
            (r"spec file = 'd': is a folder",), setup=folder("d")),
    # the default grid solves for a minute: refused in seconds, before solving
    Hostile("precalc out is a file", ("precalc", "--out", "f"), 2,
            (r"--out f: is a file, not a folder",), setup=file("f"), max_s=20.0),
    Hostile("precalc out read-only", ("precalc", "--out", "{ro}/p"), 2,
            (r"--out .*/p: read-only file system",), max_s=20.0),
    Hostile("precalc out on a full disk", ("precalc", "--out", "{full}/p"), 2,
            (r"--out .*/p: no space left on device: .* MB free",), max_s=20.0),
    # thin-film
    Hostile("thin-film set load true", ("thin-film", "--out", "t", "--set", "contact.load=true"),
            2, (r"contact.load = True: a boolean is not a number",)),
    Hostile("thin-film cell nan", ("thin-film", "--out", "t", "--cell", "nan"), 2,
            (r"argument --cell: nan is out of range",)),
    Hostile("thin-film domain inf", ("thin-film", "--out", "t", "--domain", "-11", "inf", "11"),
            2, (r"argument --domain: 'inf' is not a finite number",)),
    Hostile("thin-film out is a file", ("thin-film", "--out", "f"), 2,
            (r"--out f: is a file, not a folder",), setup=file("f"), max_s=20.0),
    # case: --set
    Hostile("case set without =", ("case", "--out", "c", "--set", "contact.speed"), 2,
            (r"--set 'contact.speed': expected KEY=VALUE",)),
    Hostile("case set a key below a value", ("case", "--out", "c", "--set", "contact.speed.x=1"),
            2, (r"contact.speed.x: contact.speed is a value, not a table",)),
    Hostile("case set an unknown table", ("case", "--out", "c", "--set", "contract.speed=1"), 2,
            (r"contract: unknown key \(valid here: .*contact",)),
    Hostile("case set load true", ("case", "--out", "c", "--set", "contact.load=true"), 2,
            (r"contact.load = True: a boolean is not a number", r"valid range 0 < contact.load")),
    Hostile("case set a quoted number", ("case", "--out", "c", "--set", 'contact.speed="0.02"'), 2,
            (r"contact.speed = '0.02': a string is not a number",)),
    Hostile("case set n_layers true", ("case", "--out", "c", "--set", "mesh.n_layers=true"), 2,
            (r"mesh.n_layers = True: a boolean is not an integer",)),
    Hostile("case set n_layers 3.0", ("case", "--out", "c", "--set", "mesh.n_layers=3.0"), 2,
            (r"mesh.n_layers = 3.0: 3.0 is not an integer \(write 3\)",)),
    Hostile("case set speed nan", ("case", "--out", "c", "--set", "contact.speed=nan"), 2,
            (r"contact.speed = nan: Input should be a finite number",)),
    Hostile("case set broken TOML list", ("case", "--out", "c", "--set", "mesh.refine=[1"), 2,
            (r"--set mesh.refine=\[1: not a valid TOML value",)),
    Hostile("case set a bare word for a number", ("case", "--out", "c", "--set", "contact.load=heavy"),
            2, (r"contact.load = 'heavy': a string is not a number",)),
    # case: the spec file
    Hostile("case spec a folder", ("case", "d", "--out", "c"), 2,
            (r"spec file = 'd': is a folder, not a TOML file",), setup=folder("d")),
    Hostile("case spec binary", ("case", "b.toml", "--out", "c"), 2,
            (r"spec file = 'b.toml'", NO_TEXT), setup=binary("b.toml")),
    Hostile("case spec 50 MB", ("case", "h.toml", "--out", "c"), 2,
            (r"spec file = 'h.toml': 50.0 MB is too large",), setup=huge("h.toml")),
    Hostile("case spec missing", ("case", "none.toml", "--out", "c"), 2,
            (r"spec file = 'none.toml': no such file or directory",)),
    Hostile("case spec garbage", ("case", "spec.toml", "--out", "c"), 2,
            (r"spec file = 'spec.toml': not valid TOML",), setup=spec("[contact\nload = \n")),
    Hostile("case spec load = true", ("case", "spec.toml", "--out", "c"), 2,
            (r"contact.load = True: a boolean is not a number",), setup=small(contact={"load": True})),
    Hostile("case spec n_layers = true", ("case", "spec.toml", "--out", "c"), 2,
            (r"mesh.n_layers = True: a boolean is not an integer",),
            setup=small(mesh={"n_layers": True})),
    Hostile("case spec numbers as strings", ("case", "spec.toml", "--out", "c"), 2,
            (r"contact.load = '25': a string is not a number",
             r"contact.speed = '0.02': a string is not a number"),
            setup=small(contact={"load": "25", "speed": "0.02"})),
    Hostile("case spec unknown key", ("case", "spec.toml", "--out", "c"), 2,
            (r"mesh.levels: unknown key \(valid here: resolution",),
            setup=small(mesh={"levels": 3})),
    Hostile("case spec inf", ("case", "spec.toml", "--out", "c"), 2,
            (r"physics.surface_tension = inf: Input should be a finite number",),
            setup=spec("[physics]\nsurface_tension = inf\n")),
    Hostile("case mesh too big", ("case", "spec.toml", "--out", "c"), 2,
            (r"cells|quads",), setup=small(mesh={"size_rim": 0.001, "size_far": 0.001})),
    # case: --out
    Hostile("case out is a file", ("case", "spec.toml", "--out", "f"), 2,
            (r"--out f: is a file, not a folder",), setup=both(small(), file("f"))),
    Hostile("case out below a file", ("case", "spec.toml", "--out", "f/c"), 2,
            (r"--out f/c: .*/f is a file, not a folder",), setup=both(small(), file("f"))),
    Hostile("case out read-only", ("case", "spec.toml", "--out", "{ro}/new/c"), 2,
            (r"--out .*/new/c: read-only file system \(.*\)",), setup=small()),
    Hostile("case out on a full disk", ("case", "spec.toml", "--out", "{full}/c"), 2,
            (r"--out .*/c: no space left on device",), setup=small()),
    Hostile("case out fills the disk while written", ("case", "spec.toml", "--out", "{tight}/c"),
            2, (r"no space left on device",),
            setup=small(mesh={"n_layers": 10, "size_rim": 0.15, "size_far": 0.6})),
    Hostile("case out has a space", ("case", "spec.toml", "--out", "a b/c"), 2,
            (r"--out a b/c: " + FOAM_PATH, r"a space at character"), setup=small()),
    Hostile("case out has a quote", ("case", "spec.toml", "--out", "it's"), 2,
            (FOAM_PATH, r"a single quote"), setup=small()),
    Hostile("case out has a command substitution", ("case", "spec.toml", "--out", "$(touch pwned)"),
            2, (FOAM_PATH, r"a '\$'",), setup=small()),
    Hostile("case out has a backslash", ("case", "spec.toml", "--out", "a\\b"), 2,
            (FOAM_PATH, r"a backslash", r"turns it into '/'"), setup=small()),
    Hostile("case out has a tab", ("case", "spec.toml", "--out", "a\tb"), 2,
            (FOAM_PATH, r"a tab"), setup=small()),
    Hostile("case out has a glob", ("case", "spec.toml", "--out", "c*"), 2,
            (FOAM_PATH, r"a '\*'"), setup=small()),
    # run
    Hostile("run no such case", ("run", "nope"), 2, (r"CASE nope: no such folder",)),
    Hostile("run a file", ("run", "f"), 2, (r"CASE f: is a file, not a case folder",),
            setup=file("f")),
    Hostile("run a folder that is no case", ("run", "d"), 2,
            (r"CASE d: not a case folder written by `ehlfoam case`",), setup=folder("d")),
    Hostile("run corrupt controlDict", ("run", "{case}"), 2,
            (r"system/controlDict is not a valid OpenFOAM dictionary \(line 1, column \d+",),
            setup=corrupt("system/controlDict")),
    Hostile("run corrupt spec.json", ("run", "{case}"), 2,
            (r"ehlfoam/spec.json is corrupt \(Invalid JSON", r"--overwrite"),
            setup=corrupt("ehlfoam/spec.json")),
    Hostile("run corrupt geometry.json", ("run", "{case}"), 2,
            (r"ehlfoam/geometry.json is corrupt \(Expecting value",),
            setup=corrupt("ehlfoam/geometry.json")),
    Hostile("run spec.json of the wrong shape", ("run", "{case}"), 2,
            (r"ehlfoam/spec.json is corrupt \(contact.load: Input should be a valid number",),
            setup=corrupt("ehlfoam/spec.json", b'{"contact": {"load": true}}')),
    Hostile("run binary geometry.json", ("run", "{case}"), 2,
            (r"ehlfoam/geometry.json is corrupt \(.*utf-8",),
            setup=corrupt("ehlfoam/geometry.json", bytes(range(128, 256)))),
    Hostile("run case path has a space", ("run", "a b/case"), 2,
            (r"CASE a b/case: " + FOAM_PATH,),
            setup=lambda work: shutil.copytree(work / "case", work / "a b" / "case"),
            with_case=True),
    Hostile("run read-only case", ("run", "{ro}/case"), 2,
            (r"CASE .*/case: read-only file system",)),
    Hostile("run wall limit nan", ("run", "{case}", "--wall-limit", "nan"), 2,
            (r"argument --wall-limit: nan \(valid range: finite, > 0\)",)),
    Hostile("run wall limit -5", ("run", "{case}", "--wall-limit=-5"), 2,
            (r"argument --wall-limit: -5.0 \(valid range",)),
    # band
    Hostile("band size nan", ("band", "{case}", "--size", "nan", "--half-width", "1"), 2,
            (r"--size = nan a is out of range",)),
    Hostile("band corrupt geometry.json", ("band", "{case}", "--size", "0.1", "--half-width",
                                           "1"), 2,
            (r"ehlfoam/geometry.json is corrupt",), setup=corrupt("ehlfoam/geometry.json")),
    Hostile("band case not run", ("band", "{case}", "--size", "0.1", "--half-width", "1"), 2,
            (r"has no written time folders",)),
    # snapshot
    Hostile("snapshot out is a folder", ("snapshot", "{case}", "d"), 2,
            (r"OUT d: is a folder \(give a file name\)",), setup=folder("d")),
    Hostile("snapshot out read-only", ("snapshot", "{case}", "{ro}/s.npz"), 2,
            (r"OUT .*/s.npz: read-only file system",)),
    Hostile("snapshot corrupt spec.json", ("snapshot", "{case}", "s.npz"), 2,
            (r"ehlfoam/spec.json is corrupt",), setup=corrupt("ehlfoam/spec.json")),
    # report
    Hostile("report no such folder", ("report", "nope"), 2, (r"DIR nope: no such folder",)),
    Hostile("report a file", ("report", "f"), 2, (r"DIR f: is a file",), setup=file("f")),
    Hostile("report corrupt spec.json", ("report", "{case}"), 2,
            (r"ehlfoam/spec.json is corrupt",), setup=corrupt("ehlfoam/spec.json")),
    Hostile("report read-only case", ("report", "{ro}/case"), 2,
            (r"DIR .*/case: read-only file system",)),
    # batch
    Hostile("batch spec binary", ("batch", "b.toml", "--out", "o"), 2, (NO_TEXT,),
            setup=binary("b.toml")),
    Hostile("batch spec 50 MB", ("batch", "h.toml", "--out", "o"), 2,
            (r"50.0 MB is too large",), setup=huge("h.toml")),
    Hostile("batch sweep of strings", ("batch", "b.toml", "--out", "o"), 2,
            (r"contact.speed = '0.02': a string is not a number",),
            setup=batch_spec('contact.speed = ["0.02"]\n')),
    Hostile("batch sweep of booleans", ("batch", "b.toml", "--out", "o"), 2,
            (r"contact.load = True: a boolean is not a number",),
            setup=batch_spec("contact.load = [true]\n")),
    Hostile("batch range of strings", ("batch", "b.toml", "--out", "o"), 2,
            (r"range start and stop must be (finite )?numbers",),
            setup=batch_spec('contact.speed = {start = "0.01", stop = 0.02, num = 2}\n')),
    Hostile("batch unknown key", ("batch", "b.toml", "--out", "o"), 2,
            (r"unknown key",), setup=both(batch_spec("contact.speed = [0.01]\n"),
                                          lambda w: open(w / "b.toml", "a").write("[extra]\n"))),
    Hostile("batch out has a space", ("batch", "b.toml", "--out", "a b"), 2,
            (r"--out a b: " + FOAM_PATH,), setup=batch_spec("contact.speed = [0.01]\n")),
    Hostile("batch default folder has a space", ("batch", "my batch.toml"), 2,
            (r"batch folder = 'runs/my batch': " + FOAM_PATH,),
            setup=batch_spec("contact.speed = [0.01]\n", "my batch.toml")),
    Hostile("batch out is a file", ("batch", "b.toml", "--out", "f"), 2,
            (r"--out f: is a file, not a folder",),
            setup=both(batch_spec("contact.speed = [0.01]\n"), file("f"))),
    Hostile("batch out read-only", ("batch", "b.toml", "--out", "{ro}/o"), 2,
            (r"--out .*/o: read-only file system",), setup=batch_spec("contact.speed = [0.01]\n")),
    Hostile("batch dry-run out with a semicolon", ("batch", "b.toml", "--out", "a;b", "--dry-run"),
            2, (FOAM_PATH, r"a ';'"), setup=batch_spec("contact.speed = [0.01]\n")),
    # foam
    Hostile("foam a path for APP", ("foam", "../../bin/sh"), 2,
            (r"APP = '../../bin/sh' is not a plain application name",)),
    Hostile("foam a shell line for APP", ("foam", "checkMesh; touch pwned"), 2,
            (r"is not a plain application name",)),
]


# ------------------------------------------------------------------------- the machinery
def _listing(*roots: Path) -> dict[str, tuple[int, int]]:
    """Every file and folder under ``roots``: path -> (size, mtime_ns) (folders: size -1)."""
    out = {}
    for root in roots:
        for dirpath, dirnames, filenames in os.walk(root):
            for name in dirnames + filenames:
                p = Path(dirpath) / name
                st = p.lstat()
                out[str(p)] = (-1 if p.is_dir() else st.st_size, st.st_mtime_ns)
    return out


def _mount(path: Path, size: str) -> bool:
    path.mkdir(parents=True, exist_ok=True)
    return subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)],
                          capture_output=True).returncode == 0


@pytest.fixture(scope="module")
def written_case(tmp_path_factory) -> Path:
    """A case of the tiny spec written by ``ehlfoam case`` (no OpenFOAM run)."""
    root = tmp_path_factory.mktemp("written")
    (root / "small.toml").write_text(as_toml(SMALL))
    proc = subprocess.run([*EHLFOAM, "case", "small.toml", "--out", "case"], cwd=root,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return root / "case"


@pytest.fixture(scope="module")
def disks(tmp_path_factory, written_case):
    """Three small tmpfs disks: ``ro`` read-only (holding a copy of the case), ``full`` (no
    byte free), ``tight`` (1.25 MiB: room for the checks, not for a 4,000-cell case).
    Unmounted at the end."""
    if os.geteuid() != 0:
        pytest.skip("the disks are tmpfs mounts: needs root")
    root = tmp_path_factory.mktemp("disks")
    made = []
    for name, size in (("ro", "4m"), ("full", "256k"), ("tight", "1280k")):
        if not _mount(root / name, size):
            for path in made:
                subprocess.run(["umount", "-l", str(path)], check=False)
            pytest.skip("cannot mount a tmpfs here")
        made.append(root / name)
    shutil.copytree(written_case, root / "ro" / "case")
    subprocess.run(["mount", "-o", "remount,ro", str(root / "ro")], check=True)
    with open(root / "full" / "filler", "wb") as fh:
        try:
            while True:
                fh.write(b"\0" * 65536)
                fh.flush()
        except OSError:
            pass
    yield {"ro": root / "ro", "full": root / "full", "tight": root / "tight"}
    for path in made:
        subprocess.run(["umount", "-l", str(path)], check=False)


RESULTS: list[dict] = []


@pytest.fixture(scope="module", autouse=True)
def summary():
    """The suite's figures, at the end (``EHLFOAM_HOSTILE_SUMMARY=FILE`` writes them)."""
    yield
    keys = ("refused cleanly", "traceback", "partial write", "hang", "orphan", "wrong outcome")
    figures = {"inputs tried": len(RESULTS)} | {k: sum(r["outcome"] == k for r in RESULTS)
                                                 for k in keys}
    target = os.environ.get("EHLFOAM_HOSTILE_SUMMARY")
    if target:
        Path(target).write_text(json.dumps({"figures": figures, "rows": RESULTS}, indent=1))


def _survivors(sid: int) -> list[psutil.Process]:
    out = []
    for proc in psutil.process_iter():
        try:
            if os.getsid(proc.pid) == sid:
                out.append(proc)
        except (ProcessLookupError, PermissionError, psutil.Error):
            continue
    return out


def _run(row: Hostile, work: Path, argv: list[str]) -> tuple[int | None, str, bool, list]:
    """Run ``ehlfoam ARGV`` in a session of its own: (exit code, stderr, whether it hung,
    the processes of its session that outlived it: killed, but reported)."""
    proc = subprocess.Popen([*EHLFOAM, *argv], cwd=work, env={**os.environ, **(row.env or {})},
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        _, err = proc.communicate(timeout=row.max_s)
        hung = False
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, 9)
        _, err = proc.communicate()
        hung = True
    survivors = _survivors(proc.pid)
    for p in survivors:
        p.kill()
    return proc.returncode, err, hung, survivors


def _message(err: str) -> list[str]:
    """The message lines of stderr (after argparse's usage lines, where argparse refused)."""
    lines = err.strip().splitlines()
    if lines and lines[0].startswith("usage:"):
        lines = [line for line in lines if line.startswith("ehlfoam ")]
    return lines


@pytest.mark.parametrize("row", CASES, ids=[c.name for c in CASES])
def test_a_hostile_input_is_refused_cleanly(row: Hostile, tmp_path: Path, request) -> None:
    work = tmp_path / "work"
    work.mkdir()
    places = {"work": str(work)}
    if row.needs("case") or row.with_case:
        shutil.copytree(request.getfixturevalue("written_case"), work / "case")
        places["case"] = str(work / "case")
    roots = [work]
    if any(row.needs(d) for d in ("ro", "full", "tight")):
        disks = request.getfixturevalue("disks")
        places |= {k: str(v) for k, v in disks.items()}
        roots += list(disks.values())
    if row.setup is not None:
        row.setup(work)
    before = _listing(*roots)
    argv = [a.format(**places) for a in row.argv]
    code, err, hung, survivors = _run(row, work, argv)
    after = _listing(*roots)
    allowed = [str(work / p) for p in row.left]
    changed = sorted(p for p in set(before) | set(after)
                     if before.get(p) != after.get(p)
                     and not any(p == a or p.startswith(a + os.sep) for a in allowed))
    lines = _message(err)
    clean = (code == row.code and len(lines) == 1
             and lines[0].startswith(f"ehlfoam {row.command}: ")
             and all(re.search(w, lines[0], re.I) for w in row.words))
    outcome = ("hang" if hung else "orphan" if survivors else
               "traceback" if "Traceback" in err else "partial write" if changed else
               "refused cleanly" if clean else "wrong outcome")
    RESULTS.append({"name": row.name, "argv": argv, "code": code, "outcome": outcome,
                    "message": lines[-1] if lines else ""})
    assert not hung, f"still running after {row.max_s} s: {err}"
    assert not survivors, f"processes outlived the command: {survivors}"
    assert "Traceback" not in err, err
    assert code == row.code, (code, err)
    assert len(lines) == 1 and lines[0].startswith(f"ehlfoam {row.command}: "), err
    for w in row.words:
        assert re.search(w, lines[0], re.I), (w, lines[0])
    assert not changed, f"files changed or left: {changed}"
