"""Reynolds flow in a given rigid gap around an island: the check for the single-phase CFD.

Steady, incompressible, isoviscous Reynolds equation for two surfaces both moving at (u, 0):

    div( h^3 / (12 eta) grad p ) = u dh/dx

on a rectangle with p = 0 (gauge) on its edges and no flow through the island (the unmeshed
contact of the CFD cases). Cell-centred finite volumes on a uniform grid: the flux through a
face is u h_f e_x . n - h_f^3 / (12 eta) dp/dn with h_f the gap at the face centre; faces on
the island carry no flux; the domain edge is a Dirichlet face half a cell away. Solved with
scipy's sparse direct solver. SI units.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.linalg import spsolve


@dataclass
class RigidReynolds:
    """Solution on the grid: x (nx,), y (ny,) cell centres [m], p (ny, nx) [Pa] (NaN in the
    island), h (ny, nx) [m]."""

    x: np.ndarray
    y: np.ndarray
    p: np.ndarray
    h: np.ndarray

    def line(self, y0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """p along the grid row nearest to y0: (x, p)."""
        j = int(np.argmin(np.abs(self.y - y0)))
        return self.x, self.p[j]


def solve_rigid_reynolds(gap: Callable[[np.ndarray, np.ndarray], np.ndarray],
                         x_range: tuple[float, float], y_range: tuple[float, float],
                         cell: float, viscosity: float, speed: float,
                         island_radius: float) -> RigidReynolds:
    """Solve on cells of size ``cell`` [m] covering x_range x y_range [m] with a circular
    island of radius ``island_radius`` [m] at the origin. ``gap(x, y)`` gives h [m]."""
    if not (viscosity > 0 and cell > 0 and island_radius >= 0):
        raise ValueError("viscosity, cell must be > 0 and island_radius >= 0")
    nx = int(round((x_range[1] - x_range[0]) / cell))
    ny = int(round((y_range[1] - y_range[0]) / cell))
    dx = (x_range[1] - x_range[0]) / nx
    dy = (y_range[1] - y_range[0]) / ny
    x = x_range[0] + dx * (np.arange(nx) + 0.5)
    y = y_range[0] + dy * (np.arange(ny) + 0.5)
    X, Y = np.meshgrid(x, y)
    solid = np.hypot(X, Y) < island_radius
    h = np.where(solid, np.nan, gap(X, Y) if not solid.any() else _gap_outside(gap, X, Y, solid))
    idx = -np.ones((ny, nx), dtype=np.int64)
    fluid = ~solid
    idx[fluid] = np.arange(fluid.sum())
    rows, cols, vals = [], [], []
    rhs = np.zeros(fluid.sum())
    k = 1.0 / (12.0 * viscosity)

    def add(r, c, v):
        rows.append(r), cols.append(c), vals.append(v)

    # x faces between (j, i) and (j, i+1), plus the two boundary columns
    for axis, (d_n, d_t) in ((1, (dx, dy)), (0, (dy, dx))):
        n_along = nx if axis == 1 else ny
        for i in range(-1, n_along):
            lo = np.take(idx, i, axis=axis) if i >= 0 else None
            hi = np.take(idx, i + 1, axis=axis) if i + 1 < n_along else None
            if axis == 1:
                xf = x_range[0] + dx * (i + 1)
                hf = gap(np.full(ny, xf), y)
            else:
                yf = y_range[0] + dy * (i + 1)
                hf = gap(x, np.full(nx, yf))
            cond = k * hf**3 / d_n * d_t          # Poiseuille conductance of the face
            couette = speed * hf * d_t if axis == 1 else np.zeros_like(hf)  # flux lo -> hi
            if lo is None or hi is None:          # domain edge, p = 0 half a cell away
                cell_ids = hi if lo is None else lo
                ok = cell_ids >= 0
                c2 = 2.0 * cond[ok]
                ids = cell_ids[ok]
                add(ids, ids, c2)
                # outflow of the cell through this face: +couette on the hi side of the domain
                sign = -1.0 if lo is None else 1.0
                np.add.at(rhs, ids, -sign * couette[ok])
                continue
            ok = (lo >= 0) & (hi >= 0)           # faces on the island carry no flux
            a, b, c, q = lo[ok], hi[ok], cond[ok], couette[ok]
            add(a, a, c), add(b, b, c), add(a, b, -c), add(b, a, -c)
            np.add.at(rhs, a, -q)
            np.add.at(rhs, b, q)
    A = coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                   shape=(len(rhs), len(rhs))).tocsr()
    sol = spsolve(A, rhs)
    p = np.full((ny, nx), np.nan)
    p[fluid] = sol
    return RigidReynolds(x=x, y=y, p=p, h=h)


def _gap_outside(gap, X, Y, solid):
    h = np.full(X.shape, np.nan)
    h[~solid] = gap(X[~solid], Y[~solid])
    return h
