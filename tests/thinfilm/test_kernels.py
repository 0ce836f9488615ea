"""The thin-film step's numba kernels: the banded Cholesky solve against sparse LU, its
refusals, and the pressure solve the same whichever of the two it takes."""

from __future__ import annotations

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.linalg import spsolve

from ehlfoam.thinfilm import Grid, ThinFilmProblem
from ehlfoam.thinfilm import operators
from ehlfoam.thinfilm.kernels import band_cholesky_solve

A = 1.4e-4     # m: a contact radius's order


def five_point(mask: np.ndarray, rng: np.random.Generator) -> csr_matrix:
    """A conductance matrix on the ``mask``'s cells, numbered row by row: random positive
    conductances between 4-neighbours, and some cells tied to a fixed pressure (the
    menisci's), as the flooded region's system is."""
    ny, nx = mask.shape
    idx = -np.ones(mask.shape, dtype=np.int64)
    idx[mask] = np.arange(mask.sum())
    n = int(mask.sum())
    dense = np.zeros((n, n))
    for i in range(ny):
        for j in range(nx):
            if not mask[i, j]:
                continue
            a = idx[i, j]
            for di, dj in ((0, 1), (1, 0)):
                if i + di < ny and j + dj < nx and mask[i + di, j + dj]:
                    b, g = idx[i + di, j + dj], rng.uniform(0.1, 10.0)
                    dense[a, a] += g
                    dense[b, b] += g
                    dense[a, b] -= g
                    dense[b, a] -= g
            if i == 0 or j == 0 or rng.uniform() < 0.05:
                dense[a, a] += rng.uniform(0.1, 1.0)
    return csr_matrix(dense)


def test_the_banded_cholesky_solve_is_sparse_lus():
    rng = np.random.default_rng(7)
    yy, xx = np.mgrid[0:24, 0:40]
    mask = np.hypot((xx - 18) / 18, yy / 20) < 1.0          # a half region, ragged rows
    mat = five_point(mask, rng)
    rhs = rng.normal(size=mat.shape[0])
    x, ok = band_cholesky_solve(mat.data, mat.indices.astype(np.int64),
                                mat.indptr.astype(np.int64), rhs, 64)
    assert ok
    exact = spsolve(mat, rhs)
    assert np.max(np.abs(x - exact)) <= 1e-10 * np.max(np.abs(exact))


def test_the_banded_solve_refuses_a_wide_band_and_a_matrix_not_positive_definite():
    rng = np.random.default_rng(3)
    mat = five_point(np.ones((10, 30), dtype=bool), rng)   # a band of 30
    args = (mat.data, mat.indices.astype(np.int64), mat.indptr.astype(np.int64),
            np.ones(mat.shape[0]))
    assert band_cholesky_solve(*args, 29)[1] is False
    assert band_cholesky_solve(*args, 30)[1] is True
    assert band_cholesky_solve(-mat.data, *args[1:], 64)[1] is False


def test_the_pressure_is_the_same_by_band_or_by_sparse_lu(monkeypatch):
    """A round region on a ball's gap: its pressure solved as a band (about 30 cells wide)
    and, with the band refused, by sparse LU."""
    prob = ThinFilmProblem(gap=lambda x, y: 1e-6 + (x**2 + y**2) / (2 * 0.01), speed=0.01,
                           viscosity=0.02, surface_tension=0.03, contact_angle=15.0,
                           supply=2e-6, track_half_width=3e-4, x_range=(-8 * A, 10 * A),
                           y_max=8 * A, island_radius=A, cell=0.2 * A, initial_radius=6 * A)
    grid = Grid.build(prob)
    ops = operators.Operators(prob, grid)
    X, Y = np.meshgrid(grid.x, grid.y)
    flooded = (np.hypot(X, Y) < 6 * A) & ~grid.island
    c = np.where(flooded, ops.h, 0.3 * ops.h)
    faces = ops.menisci(flooded, c)
    dt = 0.25 * grid.cell / prob.speed
    banded = ops.pressure(flooded, c, dt, faces)
    monkeypatch.setattr(operators, "MAX_BAND", 0)
    by_lu = ops.pressure(flooded, c, dt, faces)
    assert np.isfinite(banded[flooded]).all() and np.isnan(banded[~flooded]).all()
    scale = np.max(np.abs(by_lu[flooded]))
    assert scale > 0
    assert np.max(np.abs(banded[flooded] - by_lu[flooded])) <= 1e-12 * scale


def test_the_outer_air_is_the_gas_that_touches_the_open_edges_also_around_a_compact_region():
    """The outer air as scipy's labelling finds it: the 4-connected gas regions that touch
    the first or last column or (unless closed) the last row, on grids whose other cells
    form a compact region with holes (a bounding box well inside the grid, on an edge, or
    the whole grid), as the flood fill fills only that box."""
    from ehlfoam.thinfilm.kernels import edge_connected
    from scipy import ndimage

    rng = np.random.default_rng(11)
    enclosed = 0
    for k in range(300):
        closed = bool(k % 2)
        ny, nx = rng.integers(3, 30), rng.integers(3, 40)
        solid = np.zeros((ny, nx), bool)
        a, b = sorted(rng.integers(0, ny, 2)), sorted(rng.integers(0, nx, 2))
        solid[a[0]:a[1] + 1, b[0]:b[1] + 1] = rng.random((a[1] - a[0] + 1, b[1] - b[0] + 1)) < 0.7
        gas = ~solid
        labels, _ = ndimage.label(gas)
        edges = np.zeros_like(gas)
        edges[:, 0] = edges[:, -1] = True
        edges[-1, :] |= not closed
        touching = np.unique(labels[edges & gas])
        expected = np.isin(labels, touching[touching > 0]) & gas
        assert (edge_connected(gas, closed) == expected).all()
        enclosed += int((gas & ~expected).any())
    assert enclosed > 20                  # holes the region encloses: cavities, not air


def test_the_outer_air_grown_from_a_smaller_gas_is_the_outer_air_found_anew():
    """Opening flooded cells only adds gas: the outer air grown from the one before (the
    step's second and later passes) is the one a flood fill from the edges finds, with a
    closed side or an open one, including cavities the new gas joins to the outer air."""
    from ehlfoam.thinfilm.kernels import edge_connected, edge_connected_from
    from scipy import ndimage

    rng = np.random.default_rng(7)
    joined = 0
    for k in range(300):
        closed = bool(k % 2)
        gas = rng.random((rng.integers(3, 30), rng.integers(3, 40))) < rng.uniform(0.3, 0.7)
        more = gas | (rng.random(gas.shape) < rng.uniform(0.0, 0.2))
        before = edge_connected(gas, closed)
        grown = edge_connected_from(more, closed, before)
        assert (grown == edge_connected(more, closed)).all()
        # against scipy: the 4-connected regions of the gas that touch the open edges
        labels, _ = ndimage.label(more)
        edges = np.zeros_like(more)
        edges[:, 0] = edges[:, -1] = True
        edges[-1, :] |= not closed
        touching = np.unique(labels[edges & more])
        assert (grown == (np.isin(labels, touching) & more)).all()
        joined += int((grown & gas & ~before).any())
    assert joined > 10          # the new gas did join enclosed gas to the outer air


def _bubble_behind_the_contact() -> ThinFilmProblem:
    """A small problem whose march floods a region with a cavity behind the contact."""
    return ThinFilmProblem(gap=lambda x, y: 1e-6 + (x**2 + y**2) / (2 * 0.01), speed=0.01,
                           viscosity=0.02, surface_tension=0.03, contact_angle=15.0,
                           supply=2e-6, track_half_width=3e-4, x_range=(-8 * A, 10 * A),
                           y_max=8 * A, island_radius=A, cell=0.4 * A, initial_radius=6 * A,
                           cavitation_pressure=-1e4)


def test_a_march_is_the_same_whether_its_passes_solve_by_band_or_by_sparse_lu(monkeypatch):
    """The step's passes (one kernel each) go on from a pressure that sparse LU solved in
    Python where the band is refused: a march with a bubble behind the contact takes the
    same cells to flood, open and cavitate either way, its oil the same to round-off."""
    from ehlfoam.thinfilm.march import Marcher
    prob = _bubble_behind_the_contact()
    runs = []
    for band in (operators.MAX_BAND, 0):
        monkeypatch.setattr(operators, "MAX_BAND", band)
        m = Marcher(prob)
        for _ in range(60):
            m.step()
        runs.append(m)
    by_band, by_lu = runs
    assert by_band.cavity().any()                  # the bubble is there
    assert np.array_equal(by_band.flooded, by_lu.flooded)
    assert np.max(np.abs(by_band.c - by_lu.c)) <= 1e-9 * np.max(by_band.c)
    assert abs(by_band.oil() - by_lu.oil()) <= 1e-12 * by_band.oil()



def test_a_march_is_bitwise_the_same_with_its_passes_in_one_call_or_one_call_each(
        monkeypatch):
    """Without a gas balance, with static menisci, a step's passes run in one call
    (pass_kernels.passes): a march with a bubble behind the contact is bitwise the one that
    calls one pass at a time from Python (as the gas balance and the dynamic menisci do)."""
    from ehlfoam.thinfilm.march import Marcher
    prob = _bubble_behind_the_contact()
    runs = []
    for one_call in (True, False):
        monkeypatch.setattr(operators.Operators, "static_menisci",
                            property(lambda self, v=one_call: v))
        m = Marcher(prob)
        for _ in range(60):
            m.step()
        runs.append(m)
    together, each = runs
    assert together.cavity().any() and together._dry + together._cavitated > 0
    assert np.array_equal(together.flooded, each.flooded)
    assert np.array_equal(together.c, each.c) and np.array_equal(together.p, each.p,
                                                                 equal_nan=True)

def _hold_back_read_anew(qx, qy, q_last, q_side, q_supply, c, d, dt, flooded, island,
                         draw_x, draw_y, layer, short):
    """The hold-back with the net inflow read anew over the whole grid before every round
    and after the films are drawn: what the kernel must give, bitwise."""
    from ehlfoam.thinfilm.flux_kernels import _given
    qx, qy, q_last, q_side = qx.copy(), qy.copy(), q_last.copy(), q_side.copy()
    held, short_at = c * d * d / dt, short / dt
    opn = ~flooded & ~island
    for only_draws in (True, False):
        mx = draw_x if only_draws else np.ones_like(draw_x)
        my = draw_y if only_draws else np.ones_like(draw_y)
        if not only_draws:
            net = _net_inflow(qx, qy, q_last, q_side, q_supply)
            for i, j in zip(*np.nonzero(layer & opn)):
                if j > 0:
                    qx[i, j - 1] += max(-(held[i, j] + net[i, j]), 0.0)
        for _ in range(100):
            net = _net_inflow(qx, qy, q_last, q_side, q_supply)
            cut = opn & (held + net < short_at)
            if not cut.any():
                break
            give = _given(qx, qy, q_last, q_side, mx, my, not only_draws)
            cut = cut & (give > 0)
            if not cut.any():
                break
            scale = np.ones_like(c)
            room = (held + net + give)[cut] / give[cut]
            scale[cut] = np.minimum(np.maximum(room, 0.0), 1.0 - 1e-12)
            qx[mx] *= np.where(qx > 0, scale[:, :-1], scale[:, 1:])[mx]
            qy[my] *= np.where(qy > 0, scale[:-1], scale[1:])[my]
            if not only_draws:
                q_last *= scale[:, -1]
                q_side *= scale[-1]
    return qx, qy, q_last, q_side, _net_inflow(qx, qy, q_last, q_side, q_supply)


def _net_inflow(qx, qy, q_last, q_side, q_supply):
    """Every cell's net inflow, its faces' fluxes added in the kernels' order."""
    net = np.zeros((qy.shape[0] + 1, qx.shape[1] + 1))
    net[:, :-1] -= qx
    net[:, 1:] += qx
    net[:-1] -= qy
    net[1:] += qy
    net[:, 0] += q_supply
    net[:, -1] -= q_last
    net[-1] -= q_side
    return net


def test_the_hold_back_reads_the_net_inflow_anew_only_where_the_fluxes_changed():
    """The hold-back reads the net inflow anew only where the fluxes changed (beside the
    films drawn from a cell): bitwise what reading it anew over the whole grid each time
    gives, on grids where open cells run short and films are drawn (from any column on: the
    cells before the first films' are read again too)."""
    from ehlfoam.thinfilm.flux_kernels import hold_back
    rng = np.random.default_rng(11)
    drawn = 0
    for _ in range(200):
        ny, nx = rng.integers(3, 12, size=2)
        qx = rng.normal(0.0, 1.0, (ny, nx - 1))
        qy = rng.normal(0.0, 0.5, (ny - 1, nx))
        q_last, q_side = rng.normal(0.5, 1.0, ny), rng.normal(0.0, 0.3, nx)
        q_supply = rng.uniform(0.0, 1.0, ny)
        c = rng.uniform(0.0, 1.0, (ny, nx))
        flooded = rng.uniform(size=(ny, nx)) < 0.3
        island = rng.uniform(size=(ny, nx)) < 0.05
        draw_x = rng.uniform(size=(ny, nx - 1)) < 0.3
        draw_y = rng.uniform(size=(ny - 1, nx)) < 0.3
        layer = (rng.uniform(size=(ny, nx)) < 0.4) & ~flooded
        layer[:, :rng.integers(0, nx)] = False         # films from any column on
        qx[rng.uniform(size=qx.shape) < 0.2] = 0.0     # zeros, whose sign may change
        args = (qx, qy, q_last, q_side, q_supply, c, 1.0, 1.0, flooded, island, draw_x,
                draw_y, layer, -1e-12 * np.ones((ny, nx)))
        got, want = hold_back(*args), _hold_back_read_anew(*args)
        assert np.array_equal(_net_inflow(*got[:4], q_supply), want[4])
        for a, b in zip(got, want):
            assert np.array_equal(a, b) and np.array_equal(np.signbit(a), np.signbit(b))
        drawn += int(np.any(got[0] > qx))
    assert drawn > 20                                  # films were drawn on many grids


def test_the_bounding_box_is_that_of_the_flooded_cells():
    """The kernels' bounding box of the flooded cells (rows and columns, inclusive; empty
    ranges without one) is that of numpy's nonzero, on random grids sparse and empty."""
    from ehlfoam.thinfilm.kernels import _bounds
    rng = np.random.default_rng(5)
    for _ in range(500):
        mask = rng.uniform(size=rng.integers(1, 25, size=2)) < rng.uniform(0.0, 0.1)
        rows, cols = np.nonzero(mask)
        want = (0, -1, 0, -1) if rows.size == 0 else \
            (rows.min(), rows.max(), cols.min(), cols.max())
        assert _bounds(mask) == want
