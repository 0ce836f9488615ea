"""What every start of a case shares: writing the start's fields as the case's initial fields
(its ``0.orig/``) with a record of where they came from, and the check that a start is of the
same contact."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import numpy as np
from foamlib import FoamFieldFile

from ehlfoam._io import atomic_write_json
from ehlfoam.case.geometry import META, load_geometry
from ehlfoam.run.fields import Structure

#: The largest median difference between a start's gaps (a thin-film state's, a snapshot's)
#: and a case's, relative to the case's: a start of the same contact differs by its
#: sampling only (under 1 %), one of another load or radius by tens of per cent.
GAP_TOLERANCE = 0.05


class RampError(RuntimeError):
    """A case cannot start from the state given (a previous ramp step with nothing written, a
    state of another contact, an unreadable start)."""


def _write_internal(path: Path, value: Any) -> None:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 1 and len(arr) in (3, 6, 9):
        # foamlib writes such scalar lists as a vector/tensor (see ehlfoam.case.writer)
        raise RampError(f"{path}: a {len(arr)}-cell field cannot be written safely")
    with FoamFieldFile(path) as f:
        f.internal_field = value


def write_seed(case: Path, fields: dict[str, Any], info: dict[str, Any]) -> dict[str, Any]:
    """Write ``fields`` (name -> internal values) as ``case``'s initial fields (``0.orig/``),
    drop a stale ``0/`` that would shadow them, and record ``info`` and the case's cell count
    in ``ehlfoam/ramp.json``; returns that record."""
    for name, value in fields.items():
        _write_internal(case / "0.orig" / name, value)
    if (case / "0").exists():      # a stale start folder would shadow 0.orig
        shutil.rmtree(case / "0")
    info = {**info, "cells": load_geometry(case).cells}
    atomic_write_json(case / META / "ramp.json", info)
    return info


def check_same_gap(their_gap: np.ndarray, s: Structure, source: str | Path) -> None:
    """Raise :class:`RampError` when ``their_gap`` [m] (a start's gaps at the case's
    columns, NaN where it has none) differs from the case's own columns' gaps (their volume
    over their footprint) by more than :data:`GAP_TOLERANCE` (median relative difference
    over the columns it covers): a start of another contact."""
    gap = s.column_gaps()
    on = np.isfinite(their_gap)
    diff = float(np.median(np.abs(their_gap[on] / gap[on] - 1.0))) if on.any() else np.inf
    if not diff <= GAP_TOLERANCE:
        raise RampError(f"{source}: its gaps differ from the case's by {diff:.1%} (median over "
                        f"the columns it covers; at most {GAP_TOLERANCE:.0%}): a start of "
                        "another contact (load, radius or oil)?")
