"""One pass of the thin-film step in one numba call: the cavities and the outer air, the
menisci, the flooded cells' pressure, the test for cells below the cavitation pressure, the
oil's moves and the test for cells run dry (:meth:`ehlfoam.thinfilm.operators.Operators.step`
repeats passes until neither test opens a cell; :func:`passes` repeats them in one call where
nothing between them needs Python). The pass is the kernels of
:mod:`ehlfoam.thinfilm.kernels` and :mod:`ehlfoam.thinfilm.flux_kernels` in the order the
step takes them, with the array expressions between them as loops: bitwise the same as
calling them one by one from Python, without the returns to Python and the temporary arrays
between them, which cost a third of a step on the medium level's grid. What needs Python
stays there: a gas balance's pressures (given with the cavities they are for), the dynamic
menisci's factor (given), and the sparse LU solve where the banded Cholesky refuses the
system (the pass then stops with :data:`NEEDS_LU` and its system; :func:`after_pressure`
goes on from the pressure). Arrays are indexed ``[row, column]``: rows across the track (y),
columns along the rolling direction (x)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from ehlfoam.thinfilm.flux_kernels import face_fluxes, hold_back
from ehlfoam.thinfilm.kernels import (_bounds, _bounds_around, band_cholesky_solve,
                                      edge_connected, edge_connected_from, fill_into,
                                      meniscus_faces, pressure_in_box, pressure_system)

#: how a pass ended: the banded solve refused the system (sparse LU in Python), cells below
#: the cavitation pressure opened to gas, flooded cells that would run dry opened, or the
#: step is done (none of them)
NEEDS_LU, OPENED_TO_GAS, RAN_DRY, DONE = 0, 1, 2, 3


class PassConstants(NamedTuple):
    """What a pass reads of the grid and the model (:class:`Operators` builds it; SI): the
    gap ``h`` and the walls' layers [m], the island, the faces' conductances ``gx`` / ``gy``
    [m3/(Pa s)] and full x faces' Couette flux ``cx`` [m3/s], the films a cell beside the
    region passes on (``cap``, [m]) and the films' factor on the gap at a receding meniscus,
    the walls' speed [m/s] and the cell [m], the side row's and the last column's outflow
    conductances and the outlet's Couette flux, the supply into the first column [m3/s],
    the short-of-oil threshold [m3], Young-Laplace's 2 sigma cos(theta) [N/m], the
    cavitation pressure (gauge [Pa]; 0 without one) and whether there is one, whether the
    side is closed and whether the menisci sit within their cells."""

    h: np.ndarray
    layers: np.ndarray
    island: np.ndarray
    gx: np.ndarray
    gy: np.ndarray
    cx: np.ndarray
    cap: np.ndarray
    film: float
    u: float
    d: float
    g_side: np.ndarray
    g_out: np.ndarray
    cx_out: np.ndarray
    q_supply: np.ndarray
    short: np.ndarray
    young_laplace: float
    p_cav: float
    has_cav: bool
    closed_side: bool
    sub_cell: bool


@njit(cache=True)
def open_cells(flooded, island, closed_side, before, has_before):
    """The cavities (open cells the flooded region encloses) and the outer air (open cells
    joined to the domain's open edges), grown from ``before`` (the outer air of a flooded set
    that held this one) when ``has_before``
    (:func:`ehlfoam.thinfilm.cavity.cavities_and_outer_air`)."""
    ny, nx = flooded.shape
    gas = np.empty((ny, nx), np.bool_)
    for i in range(ny):
        for j in range(nx):
            gas[i, j] = not flooded[i, j] and not island[i, j]
    outer = edge_connected_from(gas, closed_side, before) if has_before \
        else edge_connected(gas, closed_side)
    cavity = np.empty((ny, nx), np.bool_)
    for i in range(ny):
        for j in range(nx):
            cavity[i, j] = gas[i, j] and not outer[i, j]
    return cavity, outer


@njit(cache=True)
def menisci(flooded, c, cavity, factor, gas, has_gas, k):
    """The faces' menisci, x faces then y faces: the flooded cell's conductance to the
    meniscus, its pressure [Pa] and (x faces) the gap there [m]
    (:meth:`ehlfoam.thinfilm.operators.Operators.menisci`; ``k``: :class:`PassConstants`).
    The menisci's cells (theta: 1/2 + their fill, sub-cell) are read only on the flooded
    cells' bounding box and a cell round it, where the faces with a flooded side are."""
    theta = np.ones_like(c)
    if k.sub_cell:
        fill_into(theta, c, k.h, k.layers, cavity, *_bounds_around(flooded), 0.5)
    gmx, pmx, hmx = meniscus_faces(flooded, theta, k.h, factor, k.young_laplace, k.gx,
                                   cavity, gas, k.p_cav, k.has_cav, has_gas, 1)
    gmy, pmy, _ = meniscus_faces(flooded, theta, k.h, factor, k.young_laplace, k.gy,
                                 cavity, gas, k.p_cav, k.has_cav, has_gas, 0)
    return gmx, gmy, pmx, pmy, hmx


@njit(cache=True)
def flooded_pressure(flooded, c, dt, gmx, gmy, pmx, pmy, k, max_band):
    """p on the flooded cells (NaN elsewhere) by the banded Cholesky solve, and True; or
    False where it refuses the system; and the system (CSR data, indices, indptr, the
    right-hand side and the cells' numbers: :func:`pressure_system`)."""
    if not flooded.any():
        return (np.full(flooded.shape, np.nan), True, np.empty(0), np.empty(0, np.int64),
                np.zeros(1, np.int64), np.empty(0), np.full(flooded.shape, -1, np.int64))
    data, indices, indptr, rhs, idx = pressure_system(
        flooded, c, k.h, k.d, dt, k.u, k.gx, k.gy, k.cx, gmx, gmy, pmx, pmy, k.q_supply,
        k.g_side, k.g_out, k.cx_out)
    x, ok = band_cholesky_solve(data, indices, indptr, rhs, max_band)
    p = pressure_in_box(idx, x, *_bounds(flooded)) if ok else np.full(flooded.shape, np.nan)
    return p, ok, data, indices, indptr, rhs, idx


@njit(cache=True)
def moves(flooded, p, c, dt, cavity, gmx, gmy, pmx, pmy, hmx, k):
    """The change of every cell's oil over ``dt`` [m] and the fluxes leaving through the
    last column (each row's) and the side row (each column's) [m3/s]: the faces' fluxes
    (:func:`face_fluxes`), the outlet's (Couette and Poiseuille out of a flooded cell, else
    the oil the walls carry), the side's (Poiseuille out of a flooded cell), each open cell
    held to what it holds (:func:`hold_back`)."""
    ny, nx = flooded.shape
    qx, qy, draw_x, draw_y, layer = face_fluxes(
        flooded, p, c, cavity, k.island, k.cap, k.film, hmx, k.gx, k.gy, k.cx, gmx, pmx,
        gmy, pmy, k.u, k.d)
    q_side = np.empty(nx)
    for j in range(nx):
        q_side[j] = k.g_side[j] * p[ny - 1, j] if flooded[ny - 1, j] else 0.0
    q_last = np.empty(ny)
    for i in range(ny):
        q_last[i] = (k.cx_out[i] + k.g_out[i] * p[i, nx - 1] if flooded[i, nx - 1]
                     else k.u * c[i, nx - 1] * k.d)
    qx, qy, q_last, q_side, net = hold_back(
        qx, qy, q_last, q_side, k.q_supply, c, k.d, dt, flooded, k.island, draw_x, draw_y,
        layer, k.short)
    return net * dt / (k.d * k.d), q_last, q_side


@njit(cache=True)
def after_pressure(flooded, p, c, dt, cavity, gmx, gmy, pmx, pmy, hmx, opened, cavitated,
                   k):
    """The pass from the pressure ``p`` on: the flooded cells below the cavitation pressure
    open to gas (marked in ``cavitated``; :data:`OPENED_TO_GAS`); else the oil's moves
    (:func:`moves`), and the flooded cells they would leave short of oil open (marked in
    ``opened``; :data:`RAN_DRY`), or the step is :data:`DONE`. Returns how it ended, the
    flooded cells after it (a new array where it opened some), and the moves (empty but on
    :data:`DONE`). Both tests read the flooded cells' bounding box only."""
    ny, nx = flooded.shape
    i0, i1, j0, j1 = _bounds(flooded)
    if k.has_cav:
        floor = k.p_cav - 1e-9 * abs(k.p_cav)
        low = np.zeros((ny, nx), np.bool_)
        found = False
        for i in range(i0, i1 + 1):
            for j in range(j0, j1 + 1):
                if flooded[i, j] and p[i, j] < floor:
                    low[i, j] = True
                    found = True
        if found:
            return (OPENED_TO_GAS, _opened(flooded, low, cavitated), np.empty((0, 0)),
                    np.empty(0), np.empty(0))
    dc, q_last, q_side = moves(flooded, p, c, dt, cavity, gmx, gmy, pmx, pmy, hmx, k)
    dry = np.zeros((ny, nx), np.bool_)
    found = False
    for i in range(i0, i1 + 1):
        for j in range(j0, j1 + 1):
            if flooded[i, j] and c[i, j] + dc[i, j] < 0.0:
                dry[i, j] = True
                found = True
    if found:
        return RAN_DRY, _opened(flooded, dry, opened), np.empty((0, 0)), np.empty(0), np.empty(0)
    return DONE, flooded, dc, q_last, q_side


@njit(cache=True)
def _opened(flooded, cells, marks):
    """``flooded`` without ``cells`` (a new array), ``cells`` marked in ``marks``."""
    out = flooded.copy()
    i0, i1, j0, j1 = _bounds(cells)
    for i in range(i0, i1 + 1):
        for j in range(j0, j1 + 1):
            if cells[i, j]:
                out[i, j] = False
                marks[i, j] = True
    return out


@njit(cache=True)
def one_pass(flooded, c, dt, cavity, outer, find_cells, has_before, factor, gas, has_gas,
             opened, cavitated, k, max_band):
    """One pass of the step from the flooded cells ``flooded``: the cavities and the outer
    air (:func:`open_cells`, grown from ``outer`` when ``has_before``; none without a
    cavitation pressure) when ``find_cells``, else ``cavity`` and ``outer`` as given; the
    menisci (``factor``: the dynamic menisci's on every cell; ``gas``: the cavities' gas
    pressures, gauge [Pa], when ``has_gas``), the pressure, and :func:`after_pressure`.
    Returns how it ended, the flooded cells after it, the cavities and the outer air it
    used, p, the moves, the menisci (:func:`menisci`) and, where it ended
    :data:`NEEDS_LU`, the pressure system (:func:`flooded_pressure`)."""
    if find_cells:
        if k.has_cav:
            cavity, outer = open_cells(flooded, k.island, k.closed_side, outer, has_before)
        else:
            cavity = np.zeros(flooded.shape, np.bool_)
    faces = menisci(flooded, c, cavity, factor, gas, has_gas, k)
    gmx, gmy, pmx, pmy, hmx = faces
    p, ok, data, indices, indptr, rhs, idx = flooded_pressure(flooded, c, dt, gmx, gmy, pmx,
                                                              pmy, k, max_band)
    system = data, indices, indptr, rhs, idx
    if not ok:
        return (NEEDS_LU, flooded, cavity, outer, p, np.empty((0, 0)), np.empty(0),
                np.empty(0), faces, system)
    status, flooded, dc, q_last, q_side = after_pressure(
        flooded, p, c, dt, cavity, gmx, gmy, pmx, pmy, hmx, opened, cavitated, k)
    return status, flooded, cavity, outer, p, dc, q_last, q_side, faces, system


@njit(cache=True)
def passes(flooded, c, dt, outer, has_before, factor, opened, cavitated, k, max_band):
    """The passes of a step without a gas balance and with a menisci's factor that does not
    change from pass to pass (the static menisci's), in one call: :func:`one_pass` after
    :func:`one_pass` from ``flooded`` (``outer``: the outer air of the pass before, when
    ``has_before``; each pass's cavities and outer air found anew, the outer air grown from
    the last), until one ends :data:`DONE` or :data:`NEEDS_LU`, or 1000 passes. Returns
    the last pass's :func:`one_pass` result: the same passes as one call a pass, without a
    return to Python between them."""
    none = np.zeros(flooded.shape, np.bool_)
    for _ in range(1000):
        result = one_pass(flooded, c, dt, none, outer, True, has_before, factor, k.h, False,
                          opened, cavitated, k, max_band)
        if result[0] == DONE or result[0] == NEEDS_LU:
            break
        flooded = result[1]
        if k.has_cav:
            outer, has_before = result[3], True
    return result
