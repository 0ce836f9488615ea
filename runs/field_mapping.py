"""Interpolate a case's cell values onto another case's mesh, layer by layer across the gap.

Both meshes are the generator's: a 2D base mesh in (x, y) extruded across the gap h(x, y) in
layers (``ehlfoam/mesh.npz`` stores each cell's base cell, layer and volume). A cell's place
across the gap is its relative height zeta in [0, 1], the volume fraction of its column below
its centre (exact for a prism column, and the columns here are prisms to within the slope of
the ball). A value is carried over in two steps:

1. across the gap: in every source column, linear in zeta onto the target's layer heights
   (the mean zeta of each target layer; the grading is the same in every column, to 4e-4
   in zeta where the columns lean along the levels' normals, ``mesh.columns = "normal"``);
2. in plane: linear over a Delaunay triangulation of the source column centres, nearest column
   outside their hull.

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

    def layer_zeta(self) -> np.ndarray:
        """The mean relative height of each layer."""
        return np.bincount(self.layer, self.zeta) / np.bincount(self.layer)


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
    cols = source.columns(flat)                               # (B_s, L_s, k)
    z_s, z_t = source.layer_zeta(), target.layer_zeta()
    # across the gap: the same weights in every column (the grading is the same everywhere)
    w = np.stack([np.interp(z_t, z_s, np.eye(len(z_s))[j]) for j in range(len(z_s))], axis=1)
    across = np.einsum("tj,bjk->btk", w, cols)                # (B_s, L_t, k)
    flat_cols = across.reshape(len(across), -1)
    inside = LinearNDInterpolator(source.base_xy, flat_cols)(target.base_xy)
    outside = np.isnan(inside).any(axis=1)
    if outside.any():
        inside[outside] = NearestNDInterpolator(source.base_xy, flat_cols)(
            target.base_xy[outside])
    on_target = inside.reshape(len(target.base_xy), len(z_t), -1)
    out = on_target[target.base_cell, target.layer]
    return out.reshape((len(out),) + values.shape[1:])
