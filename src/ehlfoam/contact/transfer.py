"""Grid transfers of the multigrid solver (:mod:`ehlfoam.contact.multigrid`) between a grid
and the one of every other point: full-weighting restriction, the pressure's restriction
that keeps the cavitation boundary sharp, bilinear and cubic (FMG) interpolation.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import minimum_filter


def restrict_full_weighting(r: np.ndarray) -> np.ndarray:
    rc = np.zeros(((r.shape[0] + 1) // 2, (r.shape[1] + 1) // 2))
    rc[1:-1, 1:-1] = (
        4.0 * r[2:-2:2, 2:-2:2]
        + 2.0 * (r[2:-2:2, 1:-3:2] + r[2:-2:2, 3:-1:2] + r[1:-3:2, 2:-2:2] + r[3:-1:2, 2:-2:2])
        + r[1:-3:2, 1:-3:2] + r[1:-3:2, 3:-1:2] + r[3:-1:2, 1:-3:2] + r[3:-1:2, 3:-1:2]
    ) / 16.0
    return rc


def restrict_pressure(P: np.ndarray, p_floor: float) -> np.ndarray:
    """Coarse pressure: full weighting where the 3x3 fine neighbourhood is pressurised,
    injection near the cavitation boundary and the domain boundary (keeps P >= 0 sharp)."""
    Pc = P[::2, ::2].copy()
    fw = restrict_full_weighting(P)
    allpos = minimum_filter(P > p_floor, size=3, mode="constant", cval=False)[::2, ::2]
    allpos[[0, -1], :] = allpos[:, [0, -1]] = False
    Pc[allpos] = fw[allpos]
    return Pc


def cubic_midpoints(c: np.ndarray, axis: int) -> np.ndarray:
    """Values halfway between the points of ``c`` along ``axis``: four-point (cubic)
    interpolation, two-point next to the ends."""
    c = np.moveaxis(c, axis, 0)
    mid = 0.5 * (c[:-1] + c[1:])
    if c.shape[0] >= 4:
        mid[1:-1] = (9.0 * (c[1:-2] + c[2:-1]) - (c[:-3] + c[3:])) / 16.0
    return np.moveaxis(mid, 0, axis)


def prolong_cubic(c: np.ndarray) -> np.ndarray:
    """Fourth-order (cubic) interpolation to the next finer grid: the FMG interpolation of
    the pressure (Venner & Lubrecht), whose O(h^4) error leaves the film's O(h^2)
    discretisation error of the finer grid to the cycles."""
    ny, nx = 2 * c.shape[0] - 1, 2 * c.shape[1] - 1
    rows = np.empty((c.shape[0], nx))
    rows[:, ::2] = c
    rows[:, 1::2] = cubic_midpoints(c, 1)
    f = np.empty((ny, nx))
    f[::2] = rows
    f[1::2] = cubic_midpoints(rows, 0)
    return f


def prolong_bilinear(c: np.ndarray) -> np.ndarray:
    ny, nx = 2 * c.shape[0] - 1, 2 * c.shape[1] - 1
    f = np.zeros((ny, nx))
    f[::2, ::2] = c
    f[::2, 1::2] = 0.5 * (c[:, :-1] + c[:, 1:])
    f[1::2, :] = 0.5 * (f[:-1:2, :] + f[2::2, :])
    return f
