"""Processes that die with the process that started them (Linux's parent-death signal).

A solver started by ``ehlfoam run`` must not outlive it: killed with SIGKILL, the monitor can
neither stop its solver nor mark the run, and an orphaned solver would go on writing into a
case that a second run may then start on. The kernel's parent-death signal
(``prctl(PR_SET_PDEATHSIG)``) is set in the child between fork and exec
(:func:`die_with_parent`, a ``preexec_fn``) and survives the exec of the solver, of the
embedded runtime's loader, and of ``unshare``/``chroot``/``mpirun``. Pools' worker processes set
it for themselves (:func:`set_parent_death_signal`). Elsewhere than on Linux these do nothing.

The signal is tied to the *thread* that started the child: start solvers from the thread
that waits for them (``ehlfoam run``'s main thread, a batch worker's).
"""

from __future__ import annotations

import ctypes
import os
import signal
import sys
from collections.abc import Callable

__all__ = ["PR_SET_PDEATHSIG", "die_with_parent", "set_parent_death_signal"]

PR_SET_PDEATHSIG = 1


def _prctl() -> Callable[..., int] | None:
    if not sys.platform.startswith("linux"):
        return None
    try:
        return ctypes.CDLL(None, use_errno=True).prctl
    except (OSError, AttributeError):
        return None


_PRCTL = _prctl()


def set_parent_death_signal(sig: int = signal.SIGKILL, parent: int | None = None) -> bool:
    """This process gets ``sig`` when its parent dies; if the parent (pid ``parent``) is
    already gone, it gets ``sig`` now. False where the platform cannot do it."""
    if _PRCTL is None:
        return False
    _PRCTL(PR_SET_PDEATHSIG, int(sig), 0, 0, 0)
    if parent is not None and os.getppid() != parent:
        os.kill(os.getpid(), sig)
    return True


def die_with_parent(sig: int = signal.SIGKILL) -> Callable[[], None] | None:
    """A ``preexec_fn`` for :class:`subprocess.Popen`: the child gets ``sig`` when the thread
    that started it dies (SIGKILL of the monitor included); None where the platform cannot
    do it. Everything it needs is looked up before the fork."""
    prctl = _PRCTL
    if prctl is None:
        return None
    parent = os.getpid()
    number = int(sig)
    option = PR_SET_PDEATHSIG

    def preexec() -> None:
        prctl(option, number, 0, 0, 0)
        if os.getppid() != parent:      # the parent died before prctl took effect
            os.kill(os.getpid(), number)

    return preexec
