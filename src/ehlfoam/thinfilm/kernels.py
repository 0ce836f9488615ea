"""The thin-film step's pressure side as numba kernels: the flooded cells' pressure system
and its banded Cholesky solve, the pressure put back on the grid, the menisci on the faces
between flooded and open cells and the fill that places them, and the open cells connected
to the domain's open edges (the oil's moves: :mod:`ehlfoam.thinfilm.flux_kernels`). Each
does what the array expressions it replaced did (:mod:`ehlfoam.thinfilm.operators`,
:mod:`ehlfoam.thinfilm.cavity`), in the same order of additions: bitwise the same but for
the pressure solve. The menisci, the pressure system and the outer air's flood fill visit
only the bounding box of the flooded (or, for the fill, the non-gas) cells: outside it there
is nothing for them to do. Arrays are indexed ``[row, column]``: rows across the track (y),
columns along the rolling direction (x)."""

from __future__ import annotations

import numpy as np
from numba import njit

_BIG = float(np.finfo(np.float64).max)     # np.nan_to_num's stand-in for inf


@njit(cache=True)
def _bounds(flooded):
    """The first and last rows and columns that hold a flooded cell, ``(i0, i1, j0, j1)``
    (inclusive; ``(0, -1, 0, -1)``, empty ranges, without one): the region's bounding box,
    outside which the menisci and the pressure system have nothing to do. (Which rows and
    columns hold one, by or-ing without a test a cell, then the first and last of each.)"""
    ny, nx = flooded.shape
    rows = np.zeros(ny, np.bool_)
    cols = np.zeros(nx, np.bool_)
    for i in range(ny):
        row = False
        for j in range(nx):
            f = flooded[i, j]
            row |= f
            cols[j] |= f
        rows[i] = row
    if not rows.any():
        return 0, -1, 0, -1
    i0, i1, j0, j1 = _first(rows), ny - 1 - _first(rows[::-1]), _first(cols), \
        nx - 1 - _first(cols[::-1])
    return i0, i1, j0, j1


@njit(cache=True)
def _bounds_around(flooded):
    """:func:`_bounds` grown by a cell on each side, within the grid: the cells that are
    flooded or have a flooded 4-neighbour, and the faces with a flooded side, lie in it
    (``(0, 0, 0, 0)`` without a flooded cell)."""
    ny, nx = flooded.shape
    i0, i1, j0, j1 = _bounds(flooded)
    return max(i0 - 1, 0), min(i1 + 1, ny - 1), max(j0 - 1, 0), min(j1 + 1, nx - 1)


@njit(cache=True)
def _first(flags):
    """The index of the first True in ``flags`` (one there is)."""
    for k in range(flags.size):
        if flags[k]:
            return k
    return flags.size


@njit(cache=True)
def _numbering(flooded, by_column, bounds):
    """The flooded cells' numbers, row by row (x fastest) or column by column (y fastest),
    -1 elsewhere, and the half-bandwidth that numbering gives the system (the largest
    difference between 4-neighbours' numbers); ``bounds``: the flooded cells' bounding box
    (:func:`_bounds`)."""
    ny, nx = flooded.shape
    i0, i1, j0, j1 = bounds
    idx = np.full((ny, nx), -1, np.int64)
    n = 0
    for outer in range(j0, j1 + 1) if by_column else range(i0, i1 + 1):
        for inner in range(i0, i1 + 1) if by_column else range(j0, j1 + 1):
            i, j = (inner, outer) if by_column else (outer, inner)
            if flooded[i, j]:
                idx[i, j] = n
                n += 1
    band = 0
    for i in range(i0, i1 + 1):
        for j in range(j0, j1 + 1):
            if idx[i, j] >= 0 and i + 1 < ny and idx[i + 1, j] >= 0:
                band = max(band, idx[i + 1, j] - idx[i, j])
            if idx[i, j] >= 0 and j + 1 < nx and idx[i, j + 1] >= 0:
                band = max(band, idx[i, j + 1] - idx[i, j])
    return idx, n, band


@njit(cache=True)
def pressure_system(flooded, c, h, d, dt, u, gx, gy, cx, mgx, mgy, mpx, mpy, q_supply,
                    g_side, g_out, cx_out):
    """The flooded cells' pressure system: CSR ``(data, indices, indptr)`` with sorted
    columns, the right-hand side [m3/s], and every cell's number in it (-1 off the flooded
    cells), column by column (y fastest) or row by row, whichever gives the narrower band
    (a region longer than it is wide: by column). Faces with a positive conductance (``gx``:
    x faces (ny, nx - 1), ``gy``: y faces (ny - 1, nx) [m3/(Pa s)]) join two flooded cells, or a
    flooded cell to the meniscus in its open neighbour (conductance ``mgx`` / ``mgy``,
    pressure ``mpx`` / ``mpy`` [Pa]); ``cx``: the Couette flux of a full x face [m3/s];
    the supply into the first column, the side row's and the last column's outflow
    conductances and the outlet's Couette flux."""
    ny, nx = flooded.shape
    bounds = _bounds(flooded)
    i0, i1, j0, j1 = bounds
    idx, n, band_rows = _numbering(flooded, False, bounds)
    idx_c, _, band_columns = _numbering(flooded, True, bounds)
    by_column = band_columns < band_rows
    if by_column:
        idx = idx_c
    data = np.empty(5 * n)
    indices = np.empty(5 * n, np.int64)
    indptr = np.zeros(n + 1, np.int64)
    rhs = np.empty(n)
    row_cols = np.empty(5, np.int64)
    row_vals = np.empty(5)
    k = 0
    for outer in range(j0, j1 + 1) if by_column else range(i0, i1 + 1):   # y fastest by
        for inner in range(i0, i1 + 1) if by_column else range(j0, j1 + 1):  # column, x by row
            i, j = (inner, outer) if by_column else (outer, inner)
            r = idx[i, j]
            if r < 0:
                continue
            b = ((c[i, j] - h[i, j]) * d * d / dt)
            # x faces: to the right (this cell lo), to the left (this cell hi)
            right = j + 1 < nx and gx[i, j] > 0
            left = j > 0 and gx[i, j - 1] > 0
            if right and flooded[i, j + 1]:
                b += -cx[i, j]
            if left and flooded[i, j - 1]:
                b += cx[i, j - 1]
            if right and not flooded[i, j + 1]:
                b += -cx[i, j] + mgx[i, j] * mpx[i, j]
            if left and not flooded[i, j - 1]:
                b += u * c[i, j - 1] * d + mgx[i, j - 1] * mpx[i, j - 1]
            # y faces: below (this cell lo), above (this cell hi): no Couette flux
            down = i + 1 < ny and gy[i, j] > 0
            up = i > 0 and gy[i - 1, j] > 0
            if down and not flooded[i + 1, j]:
                b += mgy[i, j] * mpy[i, j]
            if up and not flooded[i - 1, j]:
                b += mgy[i - 1, j] * mpy[i - 1, j]
            if j == 0:
                b += q_supply[i]
            if j == nx - 1:
                b += -cx_out[i]
            rhs[r] = b
            # the row's entries: its flooded neighbours, then the diagonal
            e = 0
            diag = 0.0
            if up and flooded[i - 1, j]:
                row_cols[e], row_vals[e] = idx[i - 1, j], -gy[i - 1, j]
                e += 1
                diag += gy[i - 1, j]
            elif up:
                diag += mgy[i - 1, j]
            if left and flooded[i, j - 1]:
                row_cols[e], row_vals[e] = idx[i, j - 1], -gx[i, j - 1]
                e += 1
                diag += gx[i, j - 1]
            elif left:
                diag += mgx[i, j - 1]
            if right:
                diag += gx[i, j] if flooded[i, j + 1] else mgx[i, j]
            if down:
                diag += gy[i, j] if flooded[i + 1, j] else mgy[i, j]
            if i == ny - 1:
                diag += g_side[j]
            if j == nx - 1:
                diag += g_out[i]
            if right and flooded[i, j + 1]:
                row_cols[e], row_vals[e] = idx[i, j + 1], -gx[i, j]
                e += 1
            if down and flooded[i + 1, j]:
                row_cols[e], row_vals[e] = idx[i + 1, j], -gy[i, j]
                e += 1
            row_cols[e], row_vals[e] = r, diag
            e += 1
            for t in range(1, e):               # five at most: insertion sort by column
                col, val, q = row_cols[t], row_vals[t], t
                while q > 0 and row_cols[q - 1] > col:
                    row_cols[q], row_vals[q] = row_cols[q - 1], row_vals[q - 1]
                    q -= 1
                row_cols[q], row_vals[q] = col, val
            for t in range(e):
                data[k], indices[k] = row_vals[t], row_cols[t]
                k += 1
            indptr[r + 1] = k
    return data[:k], indices[:k], indptr, rhs, idx


@njit(cache=True)
def pressure_on_grid(idx, x):
    """The flooded cells' pressures ``x`` on the grid, each at its number ``idx`` (as
    :func:`pressure_system` numbers them; -1 elsewhere), NaN elsewhere."""
    ny, nx = idx.shape
    return pressure_in_box(idx, x, 0, ny - 1, 0, nx - 1)


@njit(cache=True)
def pressure_in_box(idx, x, i0, i1, j0, j1):
    """:func:`pressure_on_grid` with the numbered cells looked for on rows ``i0``-``i1`` and
    columns ``j0``-``j1`` only (inclusive: a box that holds them all)."""
    ny, nx = idx.shape
    p = np.full((ny, nx), np.nan)
    for i in range(i0, i1 + 1):
        for j in range(j0, j1 + 1):
            if idx[i, j] >= 0:
                p[i, j] = x[idx[i, j]]
    return p


@njit(cache=True)
def fill(c, h, layers, cavity):
    """How far into each cell a meniscus beside it reaches, 0-1
    (:meth:`ehlfoam.thinfilm.operators.Operators.fill`): the bulk oil ``c - layers`` over
    the room ``h - layers`` for it; in a ``cavity`` cell, ``c / h``."""
    ny, nx = c.shape
    out = np.empty((ny, nx))
    fill_into(out, c, h, layers, cavity, 0, ny - 1, 0, nx - 1, 0.0)
    return out


@njit(cache=True)
def fill_into(out, c, h, layers, cavity, i0, i1, j0, j1, plus):
    """:func:`fill` into ``out`` on rows ``i0``-``i1`` and columns ``j0``-``j1``
    (inclusive), in place, ``plus`` added unless it is 0 (so that a fill of -0 stays
    one)."""
    for i in range(i0, i1 + 1):
        for j in range(j0, j1 + 1):
            if cavity[i, j]:
                v = c[i, j] / (h[i, j] if h[i, j] > 0 else 1.0)
            else:
                room = h[i, j] - layers[i, j]
                v = (c[i, j] - layers[i, j]) / (room if room > 0 else 1.0)
            v = min(max(v, 0.0), 1.0)
            out[i, j] = plus + v if plus != 0.0 else v


@njit(cache=True)
def meniscus_faces(flooded, theta, h, factor, young_laplace, g, cavity, gas, p_cav,
                   has_cav, has_gas, axis):
    """On every face along ``axis`` (1: x faces (ny, nx - 1), 0: y faces (ny - 1, nx)) the
    flooded cell's conductance to a meniscus in its open neighbour (``g`` / theta), the
    meniscus's pressure [Pa] and the gap there [m], as
    :meth:`ehlfoam.thinfilm.operators.Operators.menisci` defines them (``factor``: the
    dynamic menisci's factor on every cell; ``gas``: every cell's gas pressure, gauge [Pa],
    NaN off the cavities, used when ``has_gas``; ``p_cav`` when ``has_cav``); 0 outside the
    flooded cells' bounding box, where no face has a flooded side to read them."""
    ny, nx = flooded.shape
    fy, fx = (ny, nx - 1) if axis == 1 else (ny - 1, nx)
    g_m = np.zeros((fy, fx))
    p_m = np.zeros((fy, fx))
    h_m = np.zeros((fy, fx))
    i0, i1, j0, j1 = _bounds(flooded)        # the faces with a flooded side, and 0 elsewhere
    if axis == 1:
        j0, j1 = max(j0 - 1, 0), min(j1, fx - 1)
    else:
        i0, i1 = max(i0 - 1, 0), min(i1, fy - 1)
    for i in range(i0, i1 + 1):
        for j in range(j0, j1 + 1):
            i2, j2 = (i, j + 1) if axis == 1 else (i + 1, j)
            hi_open = flooded[i, j] and not flooded[i2, j2]
            if hi_open:     # the flooded cell lo, the meniscus in hi
                th, hf, ho = theta[i2, j2], h[i, j], h[i2, j2]
                fac, in_cav, pg = factor[i2, j2], cavity[i2, j2], gas[i2, j2]
            else:
                th, hf, ho = theta[i, j], h[i2, j2], h[i, j]
                fac, in_cav, pg = factor[i, j], cavity[i, j], gas[i, j]
            hm = hf + th * (ho - hf)
            safe = hm if hm > 0 else 1.0
            suction = fac * young_laplace / safe
            p = -suction if hm > 0 else 0.0
            if has_cav:
                if not has_gas:
                    p = p_cav if in_cav else max(p, p_cav)
                else:
                    if np.isnan(pg):
                        pg = 0.0
                    elif np.isinf(pg):
                        pg = _BIG if pg > 0 else -_BIG
                    p = max(pg + p if in_cav else p, p_cav)
            g_m[i, j] = g[i, j] / th
            p_m[i, j] = p
            h_m[i, j] = hm
    return g_m, p_m, h_m


@njit(cache=True)
def edge_connected(gas, closed_side):
    """The cells of ``gas`` (bool, ny x nx) connected through other gas cells (4-neighbours)
    to the first and last columns and, unless ``closed_side``, the last row.

    Outside the bounding box of the other cells every cell is gas, connected to the first
    or last column through that outside (its rows above and below the box span the grid,
    its columns beside it reach the first or last column): those are taken as connected at
    once and only the box is flood filled, from its open edges and from beside its
    outside."""
    ny, nx = gas.shape
    i0, i1, j0, j1 = _bounds(np.logical_not(gas))
    out = np.zeros(gas.shape, np.bool_)
    if i1 < 0:                                  # all gas
        out[:, :] = True
        return out
    for i in range(ny):
        for j in range(nx):
            if i < i0 or i > i1 or j < j0 or j > j1:
                out[i, j] = True
    return _grow(gas, closed_side, out)


@njit(cache=True)
def edge_connected_from(gas, closed_side, before):
    """:func:`edge_connected` of ``gas`` given ``before``, that of a gas it holds (the open
    cells before some flooded ones opened): grown from it, the same cells at a fraction of
    the cost."""
    return _grow(gas, closed_side, before.copy())


@njit(cache=True)
def _grow(gas, closed_side, out):
    """``out`` (the cells known connected to the edges) grown, in place, by every gas cell
    connected to the edges or to ``out`` through gas cells: seeded from the gas cells on
    the edges or beside ``out``, flooded from there."""
    ny, nx = gas.shape
    stack = np.empty(ny * nx, np.int64)
    top = 0
    for i in range(ny):
        for j in range(nx):
            if not gas[i, j] or out[i, j]:
                continue
            seed = j == 0 or j == nx - 1 or (i == ny - 1 and not closed_side)
            seed = seed or (i > 0 and out[i - 1, j]) or (i + 1 < ny and out[i + 1, j])
            seed = seed or (j > 0 and out[i, j - 1]) or (j + 1 < nx and out[i, j + 1])
            if seed:
                out[i, j] = True
                stack[top] = i * nx + j
                top += 1
    while top > 0:
        top -= 1
        i, j = divmod(stack[top], nx)
        for di, dj in ((-1, 0), (1, 0), (0, -1), (0, 1)):
            a, b = i + di, j + dj
            if 0 <= a < ny and 0 <= b < nx and gas[a, b] and not out[a, b]:
                out[a, b] = True
                stack[top] = a * nx + b
                top += 1
    return out


@njit(cache=True)
def band_cholesky_solve(data, indices, indptr, rhs, max_band):
    """x of A x = rhs for the symmetric positive definite CSR matrix ``(data, indices,
    indptr)`` by a banded Cholesky factorisation L L^T (row by row, the band of L stored a
    row at a time, each row from its first entry in A on), and True; or an empty x and
    False when its half-bandwidth exceeds ``max_band`` or a pivot is not positive. Numbered
    along the region's narrower side, the band is its width in cells. Single-threaded by
    design: LAPACK's banded Cholesky through a threaded BLAS spent tens of times the CPU on
    these few hundred unknowns on a busy machine."""
    n = rhs.size
    first = np.arange(n)              # L's rows start where A's do (its profile)
    for i in range(n):
        for k in range(indptr[i], indptr[i + 1]):
            first[i] = min(first[i], indices[k])
    band = np.max(np.arange(n) - first) if n else 0
    if band > max_band:
        return np.empty(0), False
    low = np.zeros((n, band + 1))     # low[i, band + k - i] = L[i, k], k in i - band .. i
    for i in range(n):
        for k in range(indptr[i], indptr[i + 1]):
            j = indices[k]
            if j <= i:
                low[i, band + j - i] = data[k]
    for i in range(n):
        for j in range(first[i], i + 1):
            s = low[i, band + j - i]
            for k in range(max(first[i], first[j]), j):
                s -= low[i, band + k - i] * low[j, band + k - j]
            if j < i:
                low[i, band + j - i] = s / low[j, band]
            elif s > 0.0:
                low[i, band] = np.sqrt(s)
            else:
                return np.empty(0), False
    x = rhs.copy()
    for i in range(n):                # L y = rhs
        s = x[i]
        for k in range(first[i], i):
            s -= low[i, band + k - i] * x[k]
        x[i] = s / low[i, band]
    for i in range(n - 1, -1, -1):    # L^T x = y
        s = x[i]
        for k in range(i + 1, min(n, i + band + 1)):
            s -= low[k, band + i - k] * x[k]
        x[i] = s / low[i, band]
    return x, True
