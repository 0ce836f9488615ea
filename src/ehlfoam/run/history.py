"""``history.csv``: one row per written time of a run (:meth:`ehlfoam.run.fields.Sample.row`),
written by the run monitor, read by the reports, the convergence readings and the seeds."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from ehlfoam._io import atomic_write_text
from ehlfoam.run.fields import Sample

__all__ = ["HISTORY_FILE", "history_columns", "read_history", "write_history"]

HISTORY_FILE = "history.csv"


def write_history(case: Path, history: list[Sample]) -> None:
    """Rewrite the case's history.csv atomically from the samples (nothing for none)."""
    if not history:
        return
    buf = io.StringIO()
    rows = [s.row() for s in history]
    writer = csv.DictWriter(buf, fieldnames=list(rows[0]))
    writer.writeheader()
    writer.writerows(rows)
    atomic_write_text(case / HISTORY_FILE, buf.getvalue())


_FLAGS = {"True": True, "False": False}


def read_history(path: Path) -> dict[str, np.ndarray] | None:
    """history.csv as columns: floats (NaN for empty cells), ``state`` as text, and the
    flags written as True/False (``wake_open``, ``inlet_meniscus_at_rim``, ...) as Python
    booleans (None for empty cells), so that a written "False" does not read as true."""
    try:
        with open(path, newline="") as fh:
            return history_columns(list(csv.DictReader(fh)))
    except FileNotFoundError:
        return None


def history_columns(rows: list[dict[str, str]]) -> dict[str, np.ndarray] | None:
    """The rows of a history.csv (``csv.DictReader``'s) as :func:`read_history`'s columns;
    None for no rows."""
    if not rows:
        return None
    out: dict[str, np.ndarray] = {}
    for key in rows[0]:
        values = [r.get(key) or "" for r in rows]
        if key == "state":
            out[key] = np.array(values, dtype=object)
            continue
        if set(values) & _FLAGS.keys() and set(values) <= _FLAGS.keys() | {"", "None"}:
            out[key] = np.array([_FLAGS.get(v) for v in values], dtype=object)
            continue
        try:
            out[key] = np.array([float(v) if v not in ("", "None") else math.nan for v in values])
        except ValueError:
            out[key] = np.array(values, dtype=object)
    return out
