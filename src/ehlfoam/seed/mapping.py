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
gap that is hundreds of times thinner than wide.

Interpolation alone does not conserve the oil: where an interface crosses coarse cells the
oil carried over changes, by 0.02, 0.18 and 0.68 nl of 185 nl from the study's rests to the
coarse, medium and fine following levels (2026-11-29), and a region then spends transits
shedding or drawing what the mapping added. :func:`carry_oil` puts the source's oil volume
back, by moving the interface within its cells only (:func:`conserve_oil`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.interpolate import LinearNDInterpolator, NearestNDInterpolator

from ehlfoam.run.fields import Structure


@dataclass(frozen=True)
class LayeredMesh:
    """A layered gap mesh as the interpolation sees it (lengths in metres)."""

    base_cell: np.ndarray   # (C,) base cell of each cell
    layer: np.ndarray       # (C,) layer of each cell, 0 on the disc
    zeta: np.ndarray        # (C,) relative height of the cell centre across the gap, 0..1
    base_xy: np.ndarray     # (B, 2) centre of each base column

    @classmethod
    def load(cls, case: str | Path) -> "LayeredMesh":
        return cls.of(Structure.load(case))

    @classmethod
    def of(cls, s: Structure) -> "LayeredMesh":
        """The layered mesh of a case's loaded :class:`~ehlfoam.run.fields.Structure`."""
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


#: How much two meshes' total volumes may differ and still be one domain, for
#: :func:`carry_oil`: the three following levels of the nominal case differ by 0.015 %
#: (2026-11-29); other extents differ by far more, and on another domain the source's oil
#: volume is not the target's.
SAME_DOMAIN = 0.01


def conserve_oil(alpha: np.ndarray, volumes: np.ndarray, oil_m3: float
                 ) -> tuple[np.ndarray, float]:
    """Oil fractions ``alpha`` (C,) shifted within the interface cells so that they hold
    ``oil_m3`` [m^3] in cells of ``volumes`` [m^3]: alpha + c alpha (1 - alpha), which leaves
    the full and empty cells as they are, stays in [0, 1] for |c| <= 1 and moves the
    interface by about c / 4 of a cell. Returns (fractions, c); c is clipped to [-1, 1], so
    a gap wider than the interface cells can take is only narrowed."""
    alpha = np.clip(np.asarray(alpha, dtype=float), 0.0, 1.0)
    room = volumes @ (alpha * (1.0 - alpha))
    if room <= 0.0:
        return alpha, 0.0
    c = float(np.clip((oil_m3 - volumes @ alpha) / room, -1.0, 1.0))
    return alpha + c * alpha * (1.0 - alpha), c


def carry_oil(alpha: np.ndarray, volumes: np.ndarray, source_oil_m3: float | None,
              source_volume_m3: float | None) -> tuple[np.ndarray, dict]:
    """Interpolated oil fractions ``alpha`` on cells of ``volumes`` [m^3] given the oil of
    their source (``source_oil_m3`` in a domain of ``source_volume_m3``), by
    :func:`conserve_oil` when both are known and the domains' volumes agree within
    :data:`SAME_DOMAIN`. Returns (fractions, record): {"source_m3", "interpolated_m3",
    "carried_m3", "shift", "conserved", "reason"}."""
    alpha = np.clip(np.asarray(alpha, dtype=float), 0.0, 1.0)
    interpolated = float(volumes @ alpha)
    record = {"source_m3": source_oil_m3, "interpolated_m3": interpolated,
              "carried_m3": interpolated, "shift": 0.0, "conserved": False}
    if source_oil_m3 is None or source_volume_m3 is None:
        return alpha, {**record, "reason": "the source records no oil volume, or another "
                                           "domain"}
    mismatch = abs(float(volumes.sum()) / source_volume_m3 - 1.0)
    if mismatch > SAME_DOMAIN:
        return alpha, {**record, "reason": f"the domains' volumes differ by {mismatch:.1%} "
                                           f"(one domain: within {SAME_DOMAIN:.0%})"}
    out, c = conserve_oil(alpha, volumes, source_oil_m3)
    carried = float(volumes @ out)
    conserved = abs(carried - source_oil_m3) <= 1e-9 * source_oil_m3
    return out, {**record, "carried_m3": carried, "shift": c, "conserved": conserved,
                 "reason": "" if conserved else "the interface cells cannot take the "
                                                "difference (shift clipped at 1)"}


def oil_carried(record: dict) -> str:
    """One line on how :func:`carry_oil` carried the oil over."""
    if record["source_m3"] is None:
        return f"oil: as interpolated ({record['reason']})"
    off = record["interpolated_m3"] / record["source_m3"] - 1.0
    if record["conserved"]:
        return (f"oil: the source's volume kept (interpolated it was {off:+.3%}; the "
                f"interface moved within its cells, c = {record['shift']:+.3g})")
    return (f"oil: {record['carried_m3'] / record['source_m3'] - 1.0:+.3%} of the source's "
            f"volume, not kept: {record['reason']}")
