"""Start a 3D case from a thin-film state: the flooded region the gap-averaged model balanced.

The thin-film model (:mod:`ehlfoam.thinfilm`) brings the nominal region to its
balance in minutes on one core; a 3D case from the spec's puddle takes hours to get there on
two. A state the model wrote (``ehlfoam thin-film``, :mod:`ehlfoam.thinfilm.state`)
gives the 3D case its oil instead: each column of cells is oil where the model's cell is
flooded, and behind the menisci carries the model's films (its oil over the gap, c / h), half on
each wall, as the spec's supply layers are laid. Columns off the model's grid keep the spec's
own start (its supply layers). Only alpha.oil is written: velocity and pressure settle within
a few steps in this Stokes flow.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
from foamlib import FoamFieldFile

from ehlfoam.thinfilm.solution import ThinFilmSolution
from ehlfoam.thinfilm.state import load_state
from ehlfoam.case.fields import wall_layers_fraction

from ehlfoam.run.fields import Structure
from ehlfoam.seed.mapping import relative_heights
from ehlfoam.seed.write import check_same_gap, write_seed


def _state_gap(sol: ThinFilmSolution, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The state's gap [m] at each point, linear between its cell centres; NaN beyond them
    and next to its island."""
    from scipy.interpolate import RegularGridInterpolator

    f = RegularGridInterpolator((sol.grid.y, sol.grid.x), sol.grid.h, bounds_error=False,
                                fill_value=np.nan)
    return f(np.column_stack([np.abs(y), x]))


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
    check_same_gap(_state_gap(sol, s.base_x, s.base_y), s, state)
    phi = column[s.base_cell]
    lo, hi = relative_heights(s)
    path = case / "0.orig" / "alpha.oil"
    own = np.broadcast_to(np.asarray(FoamFieldFile(path).internal_field, float),
                          s.cell_volumes.shape)
    half = 0.5 * np.nan_to_num(phi)     # two equal films, in fractions of the gap
    alpha = np.where(np.isnan(phi), own, wall_layers_fraction(lo, hi, 1.0, half, half))
    return write_seed(case, {"alpha.oil": alpha}, {
        "previous": os.path.relpath(state, case), "previous_time_s": None, "method": "thin-film",
        "fields": ["alpha.oil"], "columns_seeded": float(np.mean(~np.isnan(column)))})
