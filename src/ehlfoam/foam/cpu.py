"""The CPU time a solver's processes have used, read from outside (Linux ``/proc``).

The monitor tells a solver that hangs from one that computes quietly by it: a solver waiting
forever on a lock (a crash handler that a signal interrupted inside the C library, a
deadlock) writes nothing to its log and uses no CPU. Elsewhere than on Linux nothing is
known (None).
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["tree_cpu_s"]

_PROC = Path("/proc")
_TICKS = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100


def tree_cpu_s(pid: int) -> float | None:
    """The CPU time [s] (user and system) process ``pid`` and its descendants (an MPI run's
    ranks) have used so far; None where ``/proc`` cannot say (gone, not Linux, or a kernel
    that does not list a process's children: a rank left out would read as idle)."""
    total, todo, seen = None, [pid], set()
    while todo:
        p = todo.pop()
        if p in seen:
            continue
        seen.add(p)
        ticks = _ticks(p)
        if ticks is None:
            continue
        total = (total or 0.0) + ticks / _TICKS
        for task in _tasks(p):
            children = _children(task / "children")
            if children is None:
                return None
            todo.extend(children)
    return total


def _ticks(pid: int) -> int | None:
    """utime + stime of process ``pid`` (all its threads) in clock ticks."""
    try:
        stat = (_PROC / str(pid) / "stat").read_text()
        fields = stat[stat.rindex(")") + 2:].split()   # from the state on (field 3)
        return int(fields[11]) + int(fields[12])        # fields 14 and 15
    except (OSError, ValueError, IndexError):
        return None


def _tasks(pid: int) -> list[Path]:
    try:
        return list((_PROC / str(pid) / "task").iterdir())
    except OSError:
        return []


def _children(path: Path) -> list[int] | None:
    """The pids a task's ``children`` file lists; None where the kernel has no such file; none
    where the task has gone."""
    try:
        return [int(c) for c in path.read_text().split()]
    except FileNotFoundError:
        return None if path.parent.exists() else []
    except (OSError, ValueError):
        return []
