"""The CPU time of a process and its descendants, read from /proc (ehlfoam.foam.cpu): what
tells the monitor a hung solver (idle, silent) from one that computes quietly."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from ehlfoam.foam.cpu import tree_cpu_s

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")


def _grown(command: str, wait: float = 1.0) -> float:
    """The CPU time [s] a shell running ``command`` in a child process uses over ``wait`` s
    (the shell itself waits: the time is its descendant's)."""
    shell = subprocess.Popen(["sh", "-c", f"{command}; true"], start_new_session=True)
    try:
        time.sleep(0.3)
        before = tree_cpu_s(shell.pid)
        time.sleep(wait)
        after = tree_cpu_s(shell.pid)
    finally:
        os.killpg(shell.pid, signal.SIGKILL)       # the shell and its child
        shell.wait()
    assert before is not None and after is not None
    return after - before


def test_a_descendant_that_computes_counts_and_one_that_waits_does_not():
    busy = _grown(f"{sys.executable} -c 'while True: pass'")
    idle = _grown("sleep 30")
    assert busy > 0.1, busy          # a core's share under load, not nothing
    assert idle < 0.02, idle         # the monitor's "no CPU" between two polls
    assert tree_cpu_s(2 ** 22 + 12345) is None   # no such process
