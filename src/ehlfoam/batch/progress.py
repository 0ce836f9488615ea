"""A batch's progress: counts, elapsed and estimated time on a rich progress bar (a terminal)
or as log lines; how far a running case got."""

from __future__ import annotations

import os
import time
from pathlib import Path

#: Without a progress bar (--quiet, not a terminal): a status line after this long in silence.
STATUS_EVERY_S = 300.0


class Progress:
    """Counts, elapsed and estimated time on a rich progress bar (a terminal) or as log
    lines."""

    def __init__(self, title: str, quiet: bool):
        from rich.console import Console
        from rich.progress import BarColumn, Progress as RichProgress, TextColumn

        self.console = Console(stderr=False)
        self.bar = not quiet and self.console.is_terminal
        self.t0 = time.monotonic()
        self.rich = RichProgress(TextColumn("{task.description}"), BarColumn(),
                                 TextColumn("{task.percentage:>3.0f}%"),
                                 TextColumn("{task.fields[counts]}"),
                                 console=self.console, disable=not self.bar, transient=False)
        self.task = self.rich.add_task(title, total=1.0, counts="")
        self.last_print = time.monotonic()

    def __enter__(self):
        self.rich.__enter__()
        return self

    def __exit__(self, *exc):
        self.rich.__exit__(*exc)

    def elapsed(self) -> float:
        return time.monotonic() - self.t0

    def update(self, fraction: float, counts: dict[str, int], eta: float | None) -> None:
        text = (f"done {counts['finished']}/{counts['total']}  running {counts['running']}  "
                f"failed {counts['failed']}  elapsed {_hms(self.elapsed())}  "
                f"eta {_hms(eta) if eta is not None else '?'}")
        self.rich.update(self.task, completed=min(max(fraction, 0.0), 1.0), counts=text)
        if not self.bar and time.monotonic() - self.last_print > STATUS_EVERY_S:
            self.log(f"status   {text}")

    def log(self, text: str) -> None:
        self.last_print = time.monotonic()
        line = f"[{_hms(self.elapsed())}] {text}"
        if self.bar:
            self.rich.console.print(line, highlight=False, soft_wrap=True)
        else:
            print(line, flush=True)


def _hms(seconds: float) -> str:
    s = int(round(max(seconds, 0.0)))
    return f"{s // 3600}:{s % 3600 // 60:02d}:{s % 60:02d}"


def sim_fraction(case: Path, end_time: float) -> float:
    """Simulated time reached over the end time, from the last row of history.csv."""
    try:
        with open(case / "history.csv", "rb") as fh:
            fh.seek(0, os.SEEK_END)
            fh.seek(max(0, fh.tell() - 400))
            last = fh.read().decode(errors="replace").strip().splitlines()[-1]
        return min(float(last.split(",")[0]) / end_time, 1.0)
    except (OSError, ValueError, IndexError):
        return 0.0

