"""The flow-pattern metrics of a thin-film state (:mod:`ehlfoam.thinfilm`), read by the same
topology code as the 3D cases' (:func:`ehlfoam.metrics.pattern.flow_pattern_from_raster`).

The model's cells are a regular grid over the half domain; what a 3D case's mid-gap oil
fraction would read in each of them (:meth:`ThinFilmSolution.mid_gap_alpha`: 1 in the
flooded region, the menisci where the model puts them within their cells, 0 where the walls
carry only films or layers) is resampled onto the metrics' raster (a/20 pixels, the half
domain mirrored) linearly between the cell centres, as the 3D cases' cell centres are
(bilinear here, on the Delaunay triangles there; the edge cells' values beyond the outer
centres), and the pattern is read off that raster. SI inside; lengths out as ratios to a.
"""

from __future__ import annotations

import functools

import numpy as np
from scipy import ndimage
from scipy.sparse import csr_matrix

from ehlfoam.metrics.pattern import pattern_and_bubble
from ehlfoam.metrics.raster import DEFAULT_CELL_OVER_A, Geometry, Raster, _grid
from ehlfoam.thinfilm.solution import ThinFilmSolution

__all__ = ["thin_film_pattern", "thin_film_raster"]


def _outside_island(values: np.ndarray, island: np.ndarray) -> np.ndarray:
    """``values`` with each island cell given its nearest outside cell's value (so that the
    interpolation next to the rim reads the cells there, not across the island)."""
    if not island.any() or island.all():
        return values
    return values[_nearest_outside(island.shape, island.tobytes())]


@functools.lru_cache(maxsize=8)
def _nearest_outside(shape: tuple[int, int], island: bytes) -> tuple[np.ndarray, np.ndarray]:
    """Each cell's nearest cell off the island (the island's cells packed in ``island``):
    the same at every reading of a run."""
    mask = np.frombuffer(island, dtype=bool).reshape(shape)
    nearest = ndimage.distance_transform_edt(mask, return_distances=False,
                                             return_indices=True)
    return nearest[0], nearest[1]


def _linear_weights(src: np.ndarray, dst: np.ndarray) -> csr_matrix:
    """The sparse matrix W with W @ f = f linearly interpolated from ascending ``src`` to
    ``dst`` (``dst`` within [src[0], src[-1]]): two weights a row."""
    k = np.clip(np.searchsorted(src, dst, side="right") - 1, 0, len(src) - 2)
    t = (dst - src[k]) / (src[k + 1] - src[k])
    rows = np.arange(len(dst))
    return csr_matrix((np.concatenate([1.0 - t, t]),
                       (np.concatenate([rows, rows]), np.concatenate([k, k + 1]))),
                      shape=(len(dst), len(src)))


@functools.lru_cache(maxsize=8)
def _weights(y: bytes, x: bytes, ys: bytes, xs: bytes) -> tuple[csr_matrix, csr_matrix]:
    """The bilinear map's two one-dimensional weights from the cell centres ``y``, ``x``
    to the pixel centres ``ys``, ``xs`` (float64 arrays packed as bytes; the pixels beyond
    the outer centres take the edge cells' values): the same at every reading of a run."""
    y, x, ys, xs = (np.frombuffer(b) for b in (y, x, ys, xs))
    return (_linear_weights(y, np.clip(ys, y[0], y[-1])),
            _linear_weights(x, np.clip(xs, x[0], x[-1])))


@functools.lru_cache(maxsize=8)
def _pixels(geom: Geometry, cell: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The raster's pixel centres x, y [m] and its island (read-only): the same at every
    reading of a run."""
    xs, ys = _grid(geom, cell)
    X, Y = np.meshgrid(xs, ys)
    island = X**2 + Y**2 <= geom.island_radius**2
    for arr in (xs, ys, island):
        arr.flags.writeable = False
    return xs, ys, island


def thin_film_raster(sol: ThinFilmSolution, geom: Geometry,
                     cell: float | None = None) -> Raster:
    """The state's mid-gap oil fraction on the metrics' raster of ``geom`` (a half domain,
    mirrored; pixels of ``cell`` [m], by default a/20): linear between the model's cell
    centres, the outer cells' values beyond them, NaN on the island."""
    grid = sol.grid
    alpha = _outside_island(np.nan_to_num(sol.mid_gap_alpha()), grid.island)
    y = np.concatenate([-grid.y[::-1], grid.y])
    xs, ys, island = _pixels(geom, float(cell if cell is not None
                                         else DEFAULT_CELL_OVER_A * geom.a))
    # bilinear on the regular grid, as two sparse one-dimensional linear maps (a small
    # share of a point-by-point interpolator's cost: the run reads its oil a few times a transit)
    wy, wx = _weights(y.tobytes(), grid.x.tobytes(), ys.tobytes(), xs.tobytes())
    values = np.clip(np.asarray(wy @ np.vstack([alpha[::-1], alpha]) @ wx.T), 0, 1)
    values[island] = np.nan
    return Raster(x=xs, y=ys, alpha=values, island=island, geom=geom)


def _bubble_volume(r: Raster, sol: ThinFilmSolution, mask: np.ndarray) -> float:
    """Gas [m3, whole contact] in the model's cells under the bubble's footprint (``mask``,
    the :func:`~ehlfoam.metrics.pattern.bubble_mask` pixels, at their centres): their gap
    less their oil."""
    if not mask.any():
        return 0.0
    grid = sol.grid
    ix = np.clip(np.rint((grid.x - r.x[0]) / r.dx).astype(int), 0, len(r.x) - 1)
    iy = np.clip(np.rint((grid.y - r.y[0]) / r.dy).astype(int), 0, len(r.y) - 1)
    under = mask[np.ix_(iy, ix)] & ~grid.island
    gas = np.where(under, np.nan_to_num(grid.h) - sol.content, 0.0)
    return 2.0 * float(np.clip(gas, 0.0, None).sum()) * grid.cell ** 2


def thin_film_pattern(sol: ThinFilmSolution, geom: Geometry) -> tuple[dict, Raster]:
    """The flow-pattern metrics of the state (:func:`flow_pattern_from_raster`'s keys, and
    ``bubble_volume_m3``: the gas under the bubble, whole contact) and the raster they were
    read from."""
    r = thin_film_raster(sol, geom)
    pattern, bubble = pattern_and_bubble(r)
    pattern["bubble_volume_m3"] = _bubble_volume(r, sol, bubble)
    return pattern, r
