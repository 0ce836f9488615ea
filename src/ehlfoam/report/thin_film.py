"""A thin-film case's state (``DIR/state.npz``) as the report's pictures read a 3D case's
fields (:class:`ehlfoam.report.fields.Fields`): one "column" per model cell outside the
island, its mid-gap oil fraction as the metrics read it
(:meth:`~ehlfoam.thinfilm.solution.ThinFilmSolution.mid_gap_alpha`) on the metrics' own
raster (:func:`ehlfoam.metrics.thin_film.thin_film_raster`) and its gauge pressure (the
flooded cells' solved pressure, the cavities' cavitation pressure, ambient in the outer
air), so that the top view and the pressure map draw a thin-film case as they draw a 3D
one. The model is gap-averaged: there is no side view and no transient to animate.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ehlfoam.case.geometry import CaseGeometry
from ehlfoam.metrics import pattern as flow
from ehlfoam.metrics.thin_film import thin_film_pattern
from ehlfoam.run.fields import pattern_geometry
from ehlfoam.run.thin_film import STATE_FILE
from ehlfoam.thinfilm.solution import ThinFilmSolution
from ehlfoam.thinfilm.state import load_state

__all__ = ["ThinFilmFields", "load_thin_film_fields"]


@dataclass(frozen=True)
class _Columns:
    """The model's cells outside the island as a 3D case's base cells: their centres [m]."""

    base_x: np.ndarray
    base_y: np.ndarray


@dataclass(eq=False)
class ThinFilmFields:
    """A thin-film state, read as :class:`ehlfoam.report.fields.Fields` is read by the top
    view and the pressure map: ``time`` [s], ``folder`` (the state file), ``geom``,
    ``structure`` (the cells outside the island), per cell ``pressure`` [Pa, gauge] and
    ``mid_alpha``, the ``raster`` and the ``pattern`` of the metrics."""

    time: float
    folder: Path
    geom: CaseGeometry
    sol: ThinFilmSolution

    @functools.cached_property
    def _outside(self) -> np.ndarray:
        return ~self.sol.grid.island

    @functools.cached_property
    def structure(self) -> _Columns:
        X, Y = np.meshgrid(self.sol.grid.x, self.sol.grid.y)
        return _Columns(X[self._outside], Y[self._outside])

    @functools.cached_property
    def pressure(self) -> np.ndarray:
        """Gauge pressure per cell [Pa]."""
        return self.sol.gauge_pressure()[self._outside]

    def mid_gap(self, values: np.ndarray) -> np.ndarray:
        """Per cell, the value (the model has one value across the gap)."""
        return values

    @functools.cached_property
    def mid_alpha(self) -> np.ndarray:
        """The oil fraction a 3D case's mid-gap would read, per cell."""
        return self.sol.mid_gap_alpha()[self._outside]

    @functools.cached_property
    def _read(self) -> tuple[dict, flow.Raster]:
        return thin_film_pattern(self.sol, pattern_geometry(self.geom))

    @property
    def raster(self) -> flow.Raster:
        """The metrics' raster of the state (a/20, the half domain mirrored)."""
        return self._read[1]

    @property
    def pattern(self) -> dict:
        """Its flow-pattern metrics (as metrics.json's)."""
        return self._read[0]


def load_thin_film_fields(case: str | os.PathLike,
                          geom: CaseGeometry) -> ThinFilmFields | None:
    """The state a thin-film case's run ended with, or None when it has not run. Raises
    (OSError, ValueError, KeyError) when the file is there but unreadable."""
    path = Path(case) / STATE_FILE
    if not path.is_file():
        return None
    sol = load_state(path)
    return ThinFilmFields(time=sol.time, folder=path, geom=geom, sol=sol)
