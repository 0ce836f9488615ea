"""Interpolate a case's cell values onto another case's mesh, layer by layer across the gap.

Both meshes are the generator's: a 2D base mesh in (x, y) extruded across the gap h(x, y) in
layers (``ehlfoam/mesh.npz`` stores each cell's base cell, layer and volume). A cell's place
across the gap is its relative height zeta in [0, 1], the volume fraction of its column below
its centre (exact for a prism column, and the columns here are prisms to within the slope of
the ball). A value is carried over in two steps:

1. in plane: each source column's values and its layers' heights zeta, linear over a
   Delaunay triangulation of the source column centres (nearest column outside their hull);
2. across the gap: in each target column, linear in zeta between the two layers of that
   interpolated source column around each target cell (clamped at the walls), so that
   columns graded differently (``mesh.wall_cell``) map as well as evenly graded ones.

OpenFOAM's ``mapFields -consistent`` did this job before; on these meshes it crashes
(segmentation fault while interpolating, coarse to fine level of a cavitating case), and a
meshSearch in 3D has no notion of the layers, so it mixes cells of different heights across a
gap that is hundreds of times thinner than wide. The result is interpolated, not conservative:
the oil volume carried over changes by a few per cent where an interface crosses coarse cells.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.interpolate import LinearNDInterpolator, NearestNDInterpolator

from .case_fields import Structure


@dataclass(frozen=True)
class LayeredMesh:
    """A layered gap mesh as the interpolation sees it (lengths in metres)."""

    base_cell: np.ndarray   # (C,) base cell of each cell
    layer: np.ndarray       # (C,) layer of each cell, 0 on the disc
    zeta: np.ndarray        # (C,) relative height of the cell centre across the gap, 0..1
    base_xy: np.ndarray     # (B, 2) centre of each base column

    @classmethod
    def load(cls, case: str | Path) -> "LayeredMesh":
        s = Structure.load(case)
        lo, hi = relative_heights(s)
        return cls(s.base_cell, s.layer, 0.5 * (lo + hi), np.stack([s.base_x, s.base_y], axis=1))

    @property
    def shape(self) -> tuple[int, int]:
        """(base columns, layers)."""
        return len(self.base_xy), int(self.layer.max()) + 1

    def columns(self, values: np.ndarray) -> np.ndarray:
        """Cell values (C, ...) arranged as (columns, layers, ...)."""
        out = np.zeros(self.shape + values.shape[1:])
        out[self.base_cell, self.layer] = values
        return out

    def zeta_columns(self) -> np.ndarray:
        """Each cell's relative height arranged as (columns, layers): a column's own layers,
        which differ from column to column where each is graded its own way."""
        return self.columns(self.zeta)


def relative_heights(s: Structure) -> tuple[np.ndarray, np.ndarray]:
    """Each cell's bottom and top across the gap, as the volume fraction of its column below
    them (0 on the disc, 1 on the ball), (C,) each."""
    base, layer = s.base_cell, s.layer
    v = np.zeros((len(s.base_x), int(layer.max()) + 1))
    v[base, layer] = s.cell_volumes
    top = np.cumsum(v, axis=1) / v.sum(axis=1, keepdims=True)
    hi = top[base, layer]
    return hi - s.cell_volumes / v.sum(axis=1)[base], hi


def interpolate(values: np.ndarray, source: LayeredMesh, target: LayeredMesh) -> np.ndarray:
    """Cell values of ``source`` (C_s,) or (C_s, k) interpolated to the cells of ``target``."""
    values = np.asarray(values, dtype=float)
    flat = values.reshape(len(values), -1)
    n_s, l_s = source.shape
    k = flat.shape[1]
    # in plane: each source column's values and its layers' heights at the target columns
    cols = source.columns(flat).reshape(n_s, l_s * k)
    zeta_s = source.zeta_columns()                                 # (B_s, L_s)
    stacked = np.concatenate([cols, zeta_s], axis=1)
    at = LinearNDInterpolator(source.base_xy, stacked)(target.base_xy)
    outside = np.isnan(at).any(axis=1)
    if outside.any():
        at[outside] = NearestNDInterpolator(source.base_xy, stacked)(target.base_xy[outside])
    v = at[:, :l_s * k].reshape(len(at), l_s, k)
    b, zt = target.base_cell, target.zeta
    if l_s == 1:
        out = v[b, 0]
    else:
        # across the gap: linear in zeta between the two source layers around each target
        # cell, in its own column (the grading may differ from column to column)
        zs = at[:, l_s * k:][b]                                     # (C_t, L_s)
        i = np.clip((zs <= zt[:, None]).sum(axis=1) - 1, 0, l_s - 2)
        rows = np.arange(len(zt))
        z0, z1 = zs[rows, i], zs[rows, i + 1]
        w = np.clip((zt - z0) / np.maximum(z1 - z0, 1e-300), 0.0, 1.0)[:, None]
        out = (1.0 - w) * v[b, i] + w * v[b, i + 1]
    return out.reshape((len(out),) + values.shape[1:])
