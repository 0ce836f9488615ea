"""Start a thin-film case (``scene = "thin-film"``) from a thin-film state, and find the state
of a thin-film case that another case starts from.

A thin-film case starts from the oil of a state the model wrote: a ``state.npz`` (of a
thin-film case's run, or of ``ehlfoam thin-film``), or a thin-film case folder that has run
(its ``state.npz``), on any grid; the march interpolates it onto its own
(:class:`~ehlfoam.thinfilm.march.Marcher`). The state is copied into the case
(``ehlfoam/start.npz``), so that the case runs by itself. A cycle of passes (``supply.mode =
"rig"``) started from a cycle's case also takes over the oil that cycle left on the tracks
(``ehlfoam/start_tracks.npz``): a ramp's step carries the rig's state to the next speed. A 3D case or snapshot cannot start
one: the model's oil is not a 3D field. A 3D case starts from a thin-film case folder as from
its ``state.npz`` (:mod:`ehlfoam.seed.thin_film`).
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import Any

import numpy as np

from ehlfoam._io import atomic_write_json
from ehlfoam.case.geometry import META, load_geometry, load_spec_of
from ehlfoam.case.thin_film import START, is_thin_film_case
from ehlfoam.gap.field import GapField
from ehlfoam.run.cycle import START_TRACKS, TRACKS_FILE
from ehlfoam.run.thin_film import STATE_FILE
from ehlfoam.seed.write import GAP_TOLERANCE, RampError
from ehlfoam.thinfilm.state import load_state

__all__ = ["check_thin_film_start", "seed_thin_film_case", "thin_film_state_of"]


def thin_film_state_of(source: str | Path) -> Path | None:
    """The state file a source names: a thin-film case folder's ``state.npz`` (which must
    exist: the case must have run), a ``.npz`` itself; None for anything else (a 3D case, a
    folder that is no thin-film case)."""
    source = Path(source)
    if source.is_dir() and is_thin_film_case(source):
        state = source / STATE_FILE
        if not state.is_file():
            raise RampError(f"thin-film case {source} has no {STATE_FILE}: run it first "
                            f"(ehlfoam run {source})")
        return state
    return source if source.suffix == ".npz" else None


def check_thin_film_start(source: str | Path) -> Path:
    """The state a thin-film case can start from ``source`` (a thin-film state, or a
    thin-film case that has run), read to check it; raise :class:`RampError` naming what it
    is instead. Call it before writing anything."""
    state = thin_film_state_of(source)
    if state is None:
        raise RampError(f"{source} is not a thin-film state: a thin-film case starts from a "
                        "state.npz written by a thin-film run (ehlfoam run, ehlfoam "
                        "thin-film) or a thin-film case folder that has run, not from a 3D "
                        "case or snapshot")
    try:
        load_state(state)
    except Exception as err:  # noqa: BLE001 - any damage: missing arrays, zlib, zip CRC
        raise RampError(f"{source} is not a thin-film state ({type(err).__name__}: "
                        f"{' '.join(str(err).split())[:200]})") from None
    return state


def seed_thin_film_case(case: str | Path, source: str | Path) -> dict[str, Any]:
    """Copy the thin-film state of ``source`` into the thin-film ``case`` as the state it
    starts from (``ehlfoam/start.npz``), after checking that it is of the same contact (its
    gaps within :data:`~ehlfoam.seed.write.GAP_TOLERANCE` of the case's, median). Returns
    (and writes to ``ehlfoam/ramp.json``) the record of the start, as the 3D seeds do."""
    case = Path(case).absolute()
    state = check_thin_film_start(source).absolute()
    sol = load_state(state)
    gap = GapField.load(case / "precalc")
    X, Y = np.meshgrid(sol.grid.x, sol.grid.y)
    ok = np.isfinite(sol.grid.h)
    theirs, ours = sol.grid.h[ok], gap(X[ok], Y[ok])
    off = float(np.median(np.abs(theirs - ours) / ours)) if ok.any() else np.inf
    if not off <= GAP_TOLERANCE:
        raise RampError(f"{source}: its gaps differ from this case's by {off:.1%} (median; "
                        f"at most {GAP_TOLERANCE:.0%}): a state of another contact")
    shutil.copyfile(state, case / META / f".{START}.tmp")
    os.replace(case / META / f".{START}.tmp", case / META / START)
    info = {"previous": os.path.relpath(state, case), "previous_time_s": sol.time,
            "method": "thin-film state", "fields": ["oil"],
            "cells": load_geometry(case).cells, "gap_difference": off}
    tracks = state.parent / TRACKS_FILE
    if _is_rig(case) and state.name == STATE_FILE and tracks.is_file():
        shutil.copyfile(tracks, case / META / f".{START_TRACKS}.tmp")
        os.replace(case / META / f".{START_TRACKS}.tmp", case / META / START_TRACKS)
        info["tracks"] = os.path.relpath(tracks, case)
        info["fields"] = ["oil", "tracks"]
    atomic_write_json(case / META / "ramp.json", info)
    return info


def _is_rig(case: Path) -> bool:
    """The case takes its supply from the oil on the rig (a cycle of passes)."""
    return load_spec_of(case).supply.mode == "rig"
