"""Start a 3D case from a thin-film state: the flooded region the gap-averaged model balanced.

The thin-film model (``ehl_precalc.meniscus_reynolds``) brings the nominal region to its
balance in minutes on one core; a 3D case from the spec's puddle takes hours to get there on
two. A state the model wrote (``bench/thin_film_region.py``, :mod:`ehl_precalc.thin_film_state`)
gives the 3D case its oil instead: each column of cells is oil where the model's cell is
flooded, and behind the menisci carries the model's films (its oil over the gap, c / h), half on
each wall, as the spec's supply layers are laid. Columns off the model's grid keep the spec's
own start (its supply layers). Only alpha.oil is written: velocity and pressure settle within
a few steps in this Stokes flow.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import Any

import numpy as np
from foamlib import FoamFieldFile

from ehl_precalc.outputs import atomic_write_json
from ehl_precalc.thin_film_state import load_state
from generator.case_writer import META, load_geometry

from .case_fields import Structure
from .field_mapping import relative_heights


def wall_films_alpha(column_oil: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """alpha.oil of cells spanning ``lo``-``hi`` across the gap (fractions, 0 on the disc) in
    columns holding ``column_oil`` of their gap as oil, laid as two equal films, one on each
    wall (a full column: 1 throughout)."""
    half = 0.5 * np.clip(column_oil, 0.0, 1.0)
    disc = np.clip(np.minimum(hi, half) - lo, 0.0, None)
    ball = np.clip(hi - np.maximum(lo, 1.0 - half), 0.0, None)
    return np.clip((disc + ball) / (hi - lo), 0.0, 1.0)


def seed_from_thin_film(case: str | Path, state: str | Path) -> dict[str, Any]:
    """Write the thin-film ``state``'s oil as ``case``'s initial alpha.oil (its ``0.orig/``).

    Returns (and writes to ``case/ehlfoam/ramp.json``) {"previous" (the state, relative to
    the case), "previous_time_s" (None: a state keeps no time), "method": "thin-film",
    "fields": ["alpha.oil"], "cells", "columns_seeded" (the share of columns on the
    state's grid)}.
    """
    case, state = Path(case).absolute(), Path(state).absolute()
    sol = load_state(state)
    s = Structure.load(case)
    column = sol.oil_fraction_at(s.base_x, s.base_y)
    phi = column[s.base_cell]
    lo, hi = relative_heights(s)
    path = case / "0.orig" / "alpha.oil"
    own = np.broadcast_to(np.asarray(FoamFieldFile(path).internal_field, float),
                          s.cell_volumes.shape)
    alpha = np.where(np.isnan(phi), own, wall_films_alpha(np.nan_to_num(phi), lo, hi))
    with FoamFieldFile(path) as f:
        f.internal_field = alpha
    if (case / "0").exists():   # a stale start folder would shadow 0.orig
        shutil.rmtree(case / "0")
    info = {"previous": os.path.relpath(state, case), "previous_time_s": None,
            "method": "thin-film", "fields": ["alpha.oil"], "cells": load_geometry(case).cells,
            "columns_seeded": float(np.mean(~np.isnan(column)))}
    atomic_write_json(case / META / "ramp.json", info)
    return info
