"""What the hostile scenarios need to watch processes (a helper module, not a test): the
process tree a command started, and what of it (or anything working in the test's folders)
is still alive after a kill. Zombies (dead, not yet reaped by an init that does not reap)
count as gone."""

from __future__ import annotations

import os
import subprocess
import time
from pathlib import Path


def _stat(pid: int) -> tuple[str, int, int] | None:
    """(state, parent pid, start time in clock ticks) of a process, None when gone."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    rest = text[text.rindex(")") + 2:].split()
    return rest[0], int(rest[1]), int(rest[19])


def _pids() -> list[int]:
    return [int(d) for d in os.listdir("/proc") if d.isdigit()]


def tree(root: int) -> dict[int, int]:
    """``root`` and all its descendants now: pid -> start time (a pid reused later is
    another process)."""
    parents: dict[int, list[int]] = {}
    starts: dict[int, int] = {}
    for pid in _pids():
        st = _stat(pid)
        if st is not None and st[0] != "Z":
            parents.setdefault(st[1], []).append(pid)
            starts[pid] = st[2]
    out: dict[int, int] = {}
    todo = [root]
    while todo:
        pid = todo.pop()
        if pid in starts and pid not in out:
            out[pid] = starts[pid]
            todo += parents.get(pid, [])
    return out


def command_line(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(
            errors="replace").strip()
    except OSError:
        return "?"


def _describe(pid: int) -> str:
    return f"{pid} {command_line(pid)[:160]}"


def alive(procs: dict[int, int]) -> list[str]:
    """The processes of ``procs`` still alive (not zombies)."""
    out = []
    for pid, start in procs.items():
        st = _stat(pid)
        if st is not None and st[0] != "Z" and st[2] == start:
            out.append(_describe(pid))
    return out


def working_in(folders: list[Path]) -> list[str]:
    """Live processes (but this one) whose working folder is inside ``folders`` or whose
    command line names one of them."""
    roots = [str(Path(f).resolve()) for f in folders]
    out = []
    for pid in _pids():
        if pid == os.getpid():
            continue
        st = _stat(pid)
        if st is None or st[0] == "Z":
            continue
        try:
            cwd = os.readlink(f"/proc/{pid}/cwd")
        except OSError:
            cwd = ""
        cmd = command_line(pid)
        if any(cwd == r or cwd.startswith(r + "/") or r in cmd for r in roots):
            out.append(_describe(pid))
    return out


def survivors(procs: dict[int, int], folders: list[Path], timeout: float = 30.0) -> list[str]:
    """What is still alive of ``procs`` or working in ``folders`` once ``timeout`` seconds
    passed (returns as soon as nothing is)."""
    deadline = time.monotonic() + timeout
    while True:
        left = sorted(set(alive(procs)) | set(working_in(folders)))
        if not left or time.monotonic() > deadline:
            return left
        time.sleep(0.2)


def kill_all(procs: dict[int, int]) -> None:
    """SIGKILL what is left of ``procs`` (a test's clean-up after a failed assertion)."""
    for pid, start in procs.items():
        st = _stat(pid)
        if st is not None and st[2] == start:
            try:
                os.kill(pid, 9)
            except OSError:
                pass


def wait_for(predicate, proc: subprocess.Popen | None, timeout: float, what: str,
             step: float = 0.01) -> None:
    """Poll ``predicate`` until true; fail with ``what`` after ``timeout`` seconds or when
    ``proc`` ended first."""
    deadline = time.monotonic() + timeout
    while not predicate():
        if proc is not None and proc.poll() is not None:
            out = proc.stdout.read() if proc.stdout else ""
            raise AssertionError(f"ended (exit {proc.returncode}) before {what}: {out[-2000:]}")
        if time.monotonic() > deadline:
            raise AssertionError(f"no {what} within {timeout:g} s")
        time.sleep(step)
