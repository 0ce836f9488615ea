"""Which folders are ehlfoam's own cases, and which case is being run.

**The marker.** Every case :func:`ehlfoam.case.writer.write_case` writes holds
``ehlfoam/case.json`` (:data:`MARKER`): ``{"tool": "ehlfoam", "version", "written"}``. A folder
is the tool's own case when it has that file naming ``"tool": "ehlfoam"``, or (a case written
before the marker existed) both ``ehlfoam/spec.json`` and ``ehlfoam/geometry.json``.
``--overwrite`` replaces only such a folder or an empty one: anything else (a thesis, the
working folder) is refused, never emptied.

**The run lock.** ``ehlfoam/run.lock`` (:data:`RUN_LOCK`) is flock'ed by the process that runs
the case (:func:`ehlfoam.run.monitor.run_case`) and by its solver processes, which inherit the
lock's file descriptor: the lock stays held as long as any of them lives, so a case whose lock
is free has no run going on. A case being run is never overwritten; a ``running``
metrics.json whose lock is free was left by a run that was killed.
"""

from __future__ import annotations

import fcntl
import json
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO

from ehlfoam._io import atomic_write_json
from ehlfoam.case.geometry import META
from ehlfoam.errors import SpecError

__all__ = ["MARKER", "RUN_LOCK", "CaseBeingRun", "CaseBusy", "CaseExists", "NotACase",
           "check_replaceable", "hold_run_lock", "is_own_case", "lock_held", "run_lock_held",
           "write_marker"]

#: The file that marks a folder as a case ehlfoam wrote (under ``ehlfoam/``).
MARKER = "case.json"
#: The run lock (under ``ehlfoam/``).
RUN_LOCK = "run.lock"
TOOL = "ehlfoam"


class CaseExists(FileExistsError, SpecError):
    """The output folder exists and is not empty (bad input: exit 2)."""


class NotACase(CaseExists):
    """``--overwrite`` of a folder that is not a case ehlfoam wrote (nor empty)."""


class CaseBeingRun(CaseExists):
    """``--overwrite`` of a case whose run lock is held (``ehlfoam run`` or its solver)."""


class CaseBusy(RuntimeError):
    """Another process is running this case (its run lock is held)."""


def _version() -> str:
    try:
        from importlib.metadata import version

        return version(TOOL)
    except Exception:  # noqa: BLE001 - not installed (a source checkout)
        return "unknown"


def write_marker(case: Path) -> None:
    """Write ``case/ehlfoam/case.json``: the folder is a case ehlfoam wrote."""
    atomic_write_json(case / META / MARKER, {
        "tool": TOOL, "version": _version(),
        "written": time.strftime("%Y-%m-%dT%H:%M:%S%z")})


def is_own_case(folder: Path) -> bool:
    """True when ``folder`` holds a case ehlfoam wrote (module docstring)."""
    meta = Path(folder) / META
    try:
        data = json.loads((meta / MARKER).read_text())
        if isinstance(data, dict) and data.get("tool") == TOOL:
            return True
    except (OSError, ValueError):
        pass
    return (meta / "spec.json").is_file() and (meta / "geometry.json").is_file()


def run_lock_held(case: Path) -> bool:
    """True while a process holds ``case``'s run lock (a probe, released at once)."""
    return lock_held(Path(case) / META / RUN_LOCK)


def lock_held(path: Path) -> bool:
    """True if a process holds an flock on ``path`` (a probe, released at once)."""
    try:
        fh = open(path)
    except OSError:
        return False
    try:
        fcntl.flock(fh, fcntl.LOCK_SH | fcntl.LOCK_NB)
        return False
    except BlockingIOError:
        return True
    finally:
        fh.close()


@contextmanager
def hold_run_lock(case: Path) -> Iterator[IO[str] | None]:
    """Hold ``case``'s run lock (exclusive, no waiting) while the block runs; yields the lock
    file (its descriptor can be handed to child processes, which then hold the lock too), or
    None when ``case`` has no ``ehlfoam/`` folder. Raises :class:`CaseBusy` when another
    process holds it."""
    meta = Path(case) / META
    if not meta.is_dir():
        yield None
        return
    fh = open(meta / RUN_LOCK, "a")
    try:
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise CaseBusy(f"case {case} is being run by another process (its run lock "
                           f"{meta / RUN_LOCK} is held); wait for that run to end or stop "
                           "it first") from None
        yield fh
    finally:
        fh.close()


def _inside(path: Path, folder: Path) -> bool:
    try:
        path.relative_to(folder)
        return True
    except ValueError:
        return False


def check_replaceable(out: Path, overwrite: bool) -> None:
    """Raise :class:`CaseExists` unless a case may be written to ``out``: a folder that does
    not exist or is empty (but not the working folder or one holding it); with ``overwrite``
    also a case ehlfoam wrote, unless it is being run (:class:`CaseBeingRun`). Anything else
    is refused
    (:class:`NotACase`): ``--overwrite`` never empties a folder the tool did not make."""
    out = Path(out)
    if not out.exists() and not out.is_symlink():
        return
    if not out.is_dir():
        raise CaseExists(f"--out {out}: exists and is not a folder; give a new or empty "
                         "folder, or an earlier case with --overwrite")
    real, cwd = out.resolve(), Path.cwd().resolve()
    if _inside(cwd, real):
        raise NotACase(f"--out {out}: {real} is the working folder or holds it; it is never "
                       "replaced. Give the case's own folder (e.g. --out runs/NAME)")
    if not any(out.iterdir()):
        return
    if not overwrite:
        raise CaseExists(f"output folder {out} exists and is not empty (use --overwrite to "
                         "replace an earlier case written by ehlfoam)")
    if not is_own_case(out):
        raise NotACase(f"--out {out} --overwrite: {real} is not a case written by ehlfoam "
                       f"(no {META}/{MARKER}) and not empty; --overwrite replaces only an "
                       "earlier case or an empty folder. Give a new folder")
    if run_lock_held(out):
        raise CaseBeingRun(f"--out {out} --overwrite: case {real} is being run (its run "
                           f"lock {META}/{RUN_LOCK} is held); stop that run first or give "
                           "another folder")
