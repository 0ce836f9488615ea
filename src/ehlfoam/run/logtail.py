"""The solver log read as it grows: the time steps (each one's simulated time and deltaT),
the run of consecutive collapsed steps the monitor calls divergence, whether it grew since
the last read, and whether a backtrace has begun (a crash handler at work)."""

from __future__ import annotations

import bisect
import math
import re
from array import array
from pathlib import Path

__all__ = ["LogTail"]

_STEP_OR_TIME = re.compile(r"^(deltaT|Time) = ([-+0-9.eE]+)\s*$", re.M)
#: a crash handler's first words: OpenFOAM's backtrace, UCX's
_BACKTRACE = re.compile(rb"^#0 +Foam::error::printStack|Caught signal \d+", re.M)


class LogTail:
    """Incremental reader of the solver log: its time steps (each one's time and deltaT),
    the run of consecutive collapsed steps, whether the last :meth:`update` found it grown,
    and whether a backtrace has begun."""

    def __init__(self, path: Path):
        self.path, self.offset, self.small_steps = path, 0, 0
        self.times, self.dts = array("d"), array("d")
        self._dt = math.nan
        self.backtrace, self.grew, self._size = False, False, 0

    @property
    def steps(self) -> int:
        return len(self.times)

    @property
    def last_dt(self) -> float:
        return self.dts[-1] if self.dts else self._dt

    @property
    def last_time(self) -> float:
        return self.times[-1] if self.times else math.nan

    def steps_until(self, t: float) -> tuple[int, float]:
        """(steps up to time ``t`` [s], the deltaT of the last of them)."""
        n = bisect.bisect_right(self.times, t * (1.0 + 1e-9))
        return n, (self.dts[n - 1] if n else math.nan)

    def update(self, dt_floor: float) -> None:
        try:
            with open(self.path, "rb") as fh:
                fh.seek(self.offset)
                chunk = fh.read()
        except FileNotFoundError:
            self.grew = False
            return
        self.grew = self.offset + len(chunk) > self._size
        self._size = max(self._size, self.offset + len(chunk))
        # a handler may hang in the middle of a line: its words are looked for in that too
        self.backtrace = self.backtrace or _BACKTRACE.search(chunk) is not None
        cut = chunk.rfind(b"\n") + 1
        self.offset += cut
        text = chunk[:cut].decode("utf-8", "replace")
        for m in _STEP_OR_TIME.finditer(text):
            value = float(m.group(2))
            if m.group(1) == "deltaT":
                self._dt = value
                self.small_steps = self.small_steps + 1 if value < dt_floor else 0
            else:
                self.times.append(value)
                self.dts.append(self._dt)
