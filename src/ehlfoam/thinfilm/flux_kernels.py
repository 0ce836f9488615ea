"""The oil's moves over a thin-film step as numba kernels: the faces' fluxes, the rounds that
hold an open cell's outflow to what it holds, every cell's net inflow, and the oil and the
flooded cells after the step. Each does what the array expressions it replaced did
(:mod:`ehlfoam.thinfilm.operators`, :mod:`ehlfoam.thinfilm.march`), bitwise the same; they
sweep the whole grid, as the films move everywhere (the pressure side's kernels:
:mod:`ehlfoam.thinfilm.kernels`). Arrays are indexed ``[row, column]``: rows across the track
(y), columns along the rolling direction (x)."""

from __future__ import annotations

import numpy as np
from numba import njit

from ehlfoam.thinfilm.kernels import _bounds, _bounds_around


@njit(cache=True)
def _read(qx, qy, q_last, q_side, q_supply, net, held, short_at, opn, cut, cells, every,
          box=(0, -1, 0, -1)):
    """Every cell's net inflow [m3/s] into ``net`` (only those of ``cells``, all in ``box``,
    rows and columns ``(i0, i1, j0, j1)`` inclusive, unless ``every``), in place, and
    whether it leaves an open cell (``opn``) short (its oil ``held`` plus its net inflow
    below ``short_at``, all [m3/s] over the step) into ``cut``; returns how many cells are
    short then, all over the grid."""
    ny, nx = net.shape
    i0, i1, j0, j1 = (0, ny - 1, 0, nx - 1) if every else box
    for i in range(i0, i1 + 1):
        for j in range(j0, j1 + 1):
            if not every and not cells[i, j]:
                continue
            v = 0.0
            if j < nx - 1:
                v -= qx[i, j]
            if j > 0:
                v += qx[i, j - 1]
            if i < ny - 1:
                v -= qy[i, j]
            if i > 0:
                v += qy[i - 1, j]
            if j == 0:
                v += q_supply[i]
            if j == nx - 1:
                v -= q_last[i]
            if i == ny - 1:
                v -= q_side[j]
            net[i, j] = v
            cut[i, j] = opn[i, j] and held[i, j] + v < short_at[i, j]
    n = 0
    for i in range(ny):
        for j in range(nx):
            n += cut[i, j]
    return n


@njit(cache=True)
def _given(qx, qy, q_last, q_side, mx, my, every):
    """What every cell gives up [m3/s]: its outgoing fluxes on the faces ``mx`` / ``my``
    mark, or, when ``every``, on all faces and through the outlet and the side."""
    ny, nx = qy.shape[0] + 1, qx.shape[1] + 1
    out = np.empty((ny, nx))
    for i in range(ny):
        for j in range(nx):
            v = 0.0
            if j < nx - 1 and (every or mx[i, j]):
                v += max(qx[i, j], 0.0)
            if j > 0 and (every or mx[i, j - 1]):
                v += max(-qx[i, j - 1], 0.0)
            if i < ny - 1 and (every or my[i, j]):
                v += max(qy[i, j], 0.0)
            if i > 0 and (every or my[i - 1, j]):
                v += max(-qy[i - 1, j], 0.0)
            if every and j == nx - 1:
                v += max(q_last[i], 0.0)
            if every and i == ny - 1:
                v += max(q_side[j], 0.0)
            out[i, j] = v
    return out


@njit(cache=True)
def hold_back(qx, qy, q_last, q_side, q_supply, c, d, dt, flooded, island, draw_x, draw_y,
              layer, short):
    """Cut back the fluxes out of open cells (neither ``flooded`` nor ``island``) that would
    give more than they hold (their oil ``c`` [m] on cells of ``d`` [m] over the step ``dt``
    [s]; short below ``short`` / dt [m3/s]): first on the faces where the flooded region
    draws on them (``draw_x`` / ``draw_y``), then, after the films the cells
    behind a receding meniscus (``layer``) lay are drawn from the cell before them, on every
    face and through the outlet and the side. Each round scales every short cell's outgoing
    fluxes by what it can give, at most 100 rounds a pass. Returns the new qx, qy, q_last,
    q_side and every cell's net inflow with them [m3/s] (:func:`_read`;
    :func:`ehlfoam.thinfilm.pass_kernels.moves`).

    The net inflow and which cells are short are read over the grid at the start and after
    each round that scaled fluxes, and on the cells beside the films' faces after those are
    drawn: bitwise what reading them anew before every round gives, at a fraction of the
    sweeps (most steps scale nothing)."""
    qx, qy = qx.copy(), qy.copy()
    q_last, q_side = q_last.copy(), q_side.copy()
    ny, nx = c.shape
    held = np.empty((ny, nx))              # [m3/s] over the step
    short_at = np.empty((ny, nx))
    opn = np.empty((ny, nx), np.bool_)
    for i in range(ny):
        for j in range(nx):
            held[i, j] = c[i, j] * d * d / dt
            short_at[i, j] = short[i, j] / dt
            opn[i, j] = not flooded[i, j] and not island[i, j]
    net = np.empty((ny, nx))
    cut = np.zeros((ny, nx), np.bool_)     # the open cells short of oil
    state = (q_supply, net, held, short_at, opn, cut)
    n_short = _read(qx, qy, q_last, q_side, *state, cut, True)
    n_short = _rounds(qx, qy, q_last, q_side, state, n_short, draw_x, draw_y, False)
    touched = np.zeros((ny, nx), np.bool_)
    i0, i1, j0, j1 = _bounds(layer)             # the films' cells, and the cells before them
    j0 = max(j0 - 1, 0)
    for i in range(i0, i1 + 1):
        for j in range(max(j0, 1), j1 + 1):
            if layer[i, j] and opn[i, j]:
                before = qx[i, j - 1]
                qx[i, j - 1] += max(-(held[i, j] + net[i, j]), 0.0)
                if qx[i, j - 1] != before or before == 0.0:   # a zero may change its sign
                    touched[i, j - 1] = touched[i, j] = True
    n_short = _read(qx, qy, q_last, q_side, *state, touched, False, (i0, i1, j0, j1))
    _rounds(qx, qy, q_last, q_side, state, n_short, draw_x, draw_y, True)
    return qx, qy, q_last, q_side, net


@njit(cache=True)
def _rounds(qx, qy, q_last, q_side, state, n_short, draw_x, draw_y, every):
    """The hold-back's rounds (:func:`hold_back`), in place, on the faces ``draw_x`` /
    ``draw_y`` or, when ``every``, on every face and through the outlet and the side: each
    scales the short cells' outgoing fluxes by what they can give, and the net inflows and
    the short cells are read again; until none is short, none that is can give, or 100
    rounds. ``state``: the supply, the net inflows, the oil held, the short thresholds, the
    open cells and the short ones. Returns how many cells are short at the end."""
    q_supply, net, held, short_at, opn, cut = state
    ny, nx = net.shape
    for _ in range(100):
        if n_short == 0:
            break
        give = _given(qx, qy, q_last, q_side, draw_x, draw_y, every)
        scale = np.ones((ny, nx))
        scaled = False
        for i in range(ny):
            for j in range(nx):
                if cut[i, j] and give[i, j] > 0:
                    room = (held[i, j] + net[i, j] + give[i, j]) / give[i, j]
                    scale[i, j] = min(max(room, 0.0), 1.0 - 1e-12)
                    scaled = True
        if not scaled:
            break
        for i in range(ny):
            for j in range(nx - 1):
                if every or draw_x[i, j]:
                    qx[i, j] *= scale[i, j] if qx[i, j] > 0 else scale[i, j + 1]
        for i in range(ny - 1):
            for j in range(nx):
                if every or draw_y[i, j]:
                    qy[i, j] *= scale[i, j] if qy[i, j] > 0 else scale[i + 1, j]
        if every:
            for i in range(ny):
                q_last[i] *= scale[i, nx - 1]
            for j in range(nx):
                q_side[j] *= scale[ny - 1, j]
        n_short = _read(qx, qy, q_last, q_side, q_supply, net, held, short_at, opn, cut,
                        cut, True)
    return n_short


@njit(cache=True)
def _poiseuille(f_lo, f_hi, p_lo, p_hi, g, g_m, p_m):
    """Poiseuille flux lo -> hi [m3/s] across one face: between two flooded cells, or from a
    flooded cell to the meniscus in its open neighbour; none between open cells."""
    if f_lo and f_hi:
        return g * (p_lo - p_hi)
    if f_lo:
        return g_m * (p_lo - p_m)
    if f_hi:
        return g_m * (p_m - p_hi)
    return 0.0


@njit(cache=True)
def face_fluxes(flooded, p, c, cavity, island, cap, film, hx_m, gx, gy, cx, mgx, mpx, mgy,
                mpy, u, d):
    """The faces' fluxes lo -> hi before any open cell is held to what it holds [m3/s]
    (:func:`ehlfoam.thinfilm.pass_kernels.moves`): on x faces Poiseuille where a side
    is flooded plus what the walls carry (a full gap, Couette, out of a flooded cell; the
    films f h a receding meniscus lays out of the cell behind one, h its gap there
    ``hx_m``; at most the films ``cap`` out of an open cell beside the region; else the
    cell's oil, all of a cavity's), on y faces Poiseuille alone; the faces on which an open
    cell gives to a flooded one; and the cells behind a receding meniscus.

    Off the flooded cells' bounding box and a cell round it, no face has a flooded side
    and no cell a flooded neighbour: there the walls carry each cell's oil on through its
    x faces and nothing crosses the y faces, the same sums in a loop without the tests."""
    ny, nx = flooded.shape
    qx = np.empty((ny, nx - 1))
    qy = np.empty((ny - 1, nx))
    draw_x = np.zeros((ny, nx - 1), np.bool_)
    draw_y = np.zeros((ny - 1, nx), np.bool_)
    layer = np.zeros((ny, nx), np.bool_)
    i0, i1, j0, j1 = _bounds_around(flooded)
    for i in range(ny):
        for j in range(nx - 1):
            if i < i0 or i > i1 or j < j0 or j > j1:
                qx[i, j] = 0.0 + u * c[i, j] * d * (1.0 if gx[i, j] > 0 else 0.0)
                continue
            fl, fr = flooded[i, j], flooded[i, j + 1]
            touch = False
            if not fl and not island[i, j] and not cavity[i, j]:
                touch = ((i > 0 and flooded[i - 1, j]) or (i + 1 < ny and flooded[i + 1, j])
                         or (j > 0 and flooded[i, j - 1]) or fr)
            carry = min(c[i, j], cap[i, j]) if touch and not fr else c[i, j]
            if (j > 0 and flooded[i, j - 1] and not fl and not fr
                    and not cavity[i, j]):      # behind a receding meniscus: its films
                carry = film * hx_m[i, j - 1]
                layer[i, j] = True
            q = _poiseuille(fl, fr, p[i, j], p[i, j + 1], gx[i, j], mgx[i, j], mpx[i, j])
            q += cx[i, j] if fl else u * carry * d * (1.0 if gx[i, j] > 0 else 0.0)
            qx[i, j] = q
            draw_x[i, j] = (not fl and fr and q > 0) or (fl and not fr and q < 0)
    for i in range(ny - 1):
        for j in range(nx):
            if i < i0 or i > i1 or j < j0 or j > j1:
                qy[i, j] = 0.0
                continue
            lo, hi = flooded[i, j], flooded[i + 1, j]
            q = _poiseuille(lo, hi, p[i, j], p[i + 1, j], gy[i, j], mgy[i, j], mpy[i, j])
            qy[i, j] = q
            draw_y[i, j] = (not lo and hi and q > 0) or (lo and not hi and q < 0)
    return qx, qy, draw_x, draw_y, layer


@njit(cache=True)
def advance_oil(c, dc, h, opened, cavitated, island):
    """Every cell's oil after a step, ``c + dc`` [m], and the cells flooded then: full to
    their gap ``h`` (within 1e-9 of it), not opened within the step (``opened``,
    ``cavitated``), not ``island`` (:meth:`ehlfoam.thinfilm.march.March._advance`)."""
    ny, nx = c.shape
    c_new = np.empty((ny, nx))
    flooded = np.empty((ny, nx), np.bool_)
    for i in range(ny):
        for j in range(nx):
            v = c[i, j] + dc[i, j]
            c_new[i, j] = v
            flooded[i, j] = (v >= h[i, j] * (1.0 - 1e-9) and not opened[i, j]
                             and not cavitated[i, j] and not island[i, j])
    return c_new, flooded
