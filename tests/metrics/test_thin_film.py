"""The flow pattern of a thin-film state (ehlfoam.metrics.thin_film), read by the 3D cases'
topology code: a closed ring of oil round the contact is state I, a pocket of gas it
encloses behind the contact a bubble (state I, enclosed, its length from x = a), a wake open
to the outlet state II; the menisci are read where the model puts them within their
cells."""

from __future__ import annotations

import numpy as np
import pytest

from ehlfoam.metrics.raster import Geometry
from ehlfoam.metrics.thin_film import thin_film_pattern, thin_film_raster
from ehlfoam.thinfilm.operators import touches
from ehlfoam.thinfilm.problem import Grid
from ehlfoam.thinfilm.solution import ThinFilmSolution

A = 1.0e-4
D = 0.25 * A          # the model's cells
GEOM = Geometry(x_min=-8 * A, x_max=12 * A, y_max=8 * A, island_radius=1.5 * A, a=A)


def state(flooded_of, fill: float = 0.0, content=None) -> ThinFilmSolution:
    """A state on 0.25 a cells over GEOM: flooded where ``flooded_of(X, Y)``, the menisci
    ``fill`` into the open cells beside the flooded ones, a gap of 10 um."""
    x = GEOM.x_min + D * (np.arange(round((GEOM.x_max - GEOM.x_min) / D)) + 0.5)
    y = D * (np.arange(round(GEOM.y_max / D)) + 0.5)
    X, Y = np.meshgrid(x, y)
    island = np.hypot(X, Y) < GEOM.island_radius
    h = np.where(island, np.nan, 1e-5)
    flooded = flooded_of(X, Y) & ~island
    grid = Grid(x=x, y=y, h=h, hx=h[:, 1:], hy=h[1:], h_side=h[-1], island=island)
    c = np.where(flooded, 1e-5, 0.0) if content is None else content
    return ThinFilmSolution(grid=grid, p=np.where(flooded, 0.0, np.nan), content=c,
                            flooded=flooded, time=0.0, steps=0, flux_in=0.0, flux_out=0.0,
                            steady=False, island_radius=GEOM.island_radius,
                            fill=np.where(touches(flooded) & ~island, fill, 0.0))


def ring(X, Y):
    return np.hypot(X, Y) < 6 * A


def test_a_closed_ring_round_the_contact_is_state_I_with_its_menisci_at_the_cells_faces():
    """Without fills the menisci are the flooded cells' faces: the inlet meniscus 4.5 a
    upstream of x = -a (the ring's radius, 6 a, on the grid's faces), the width 12 a; the
    ring touches the rim everywhere: no wake, no bubble."""
    p, _ = thin_film_pattern(state(ring), GEOM)
    assert p["state"] == "I"
    assert p["inlet_meniscus_distance_over_a"] == pytest.approx(5.0, abs=0.06)
    assert p["flooded_width_over_a"] == pytest.approx(12.0, abs=0.1)
    assert p["flooded_length_over_a"] == pytest.approx(12.0, abs=0.1)
    assert p["wake_gas_length_over_a"] == 0.0 and p["bubble_length_over_a"] == 0.0
    assert not p["wake_open"] and not p["inlet_starved"]
    assert p["inlet_meniscus_shape"] == "convex"


def test_a_meniscus_is_read_where_its_fill_puts_it_within_its_cell():
    """A fill f puts each meniscus 1/2 + f cells from its flooded cell's centre
    (ThinFilmSolution.mid_gap_alpha): half a cell's fill moves the inlet meniscus half a
    cell upstream and widens the region by a cell."""
    faces, _ = thin_film_pattern(state(ring), GEOM)
    half, _ = thin_film_pattern(state(ring, fill=0.5), GEOM)
    cells = D / A
    assert half["inlet_meniscus_distance_over_a"] - faces["inlet_meniscus_distance_over_a"] \
        == pytest.approx(0.5 * cells, abs=0.06)
    assert half["flooded_width_over_a"] - faces["flooded_width_over_a"] == pytest.approx(
        cells, abs=0.1)


def test_a_pocket_of_gas_behind_the_contact_is_an_enclosed_bubble_and_an_open_wake_state_II():
    """Gas the ring encloses behind the island, to x = 3 a: state I with a bubble 2 a long
    from x = a, enclosed, and its gas volume (the gap less the oil under it); the same
    pocket run out to the outlet: state II, an open wake, no enclosed bubble."""
    def pocket(X, Y):
        return ring(X, Y) & ~((X > 0) & (X < 3 * A) & (Y < A))

    sol = state(pocket)
    p, r = thin_film_pattern(sol, GEOM)
    assert p["state"] == "I"
    assert p["bubble_enclosed"] and not p["wake_open"]
    assert p["bubble_length_over_a"] == pytest.approx(2.0, abs=0.06)
    assert p["wake_gas_length_over_a"] == pytest.approx(2.0, abs=0.06)
    assert p["enclosed_bubbles"] == 1
    X, Y = np.meshgrid(sol.grid.x, sol.grid.y)
    gas = ~sol.flooded & ~sol.grid.island & (X > 0) & (X < 3 * A) & (Y < A)
    assert p["bubble_volume_m3"] == pytest.approx(2 * gas.sum() * 1e-5 * D * D, rel=0.1)

    def wake(X, Y):
        return ring(X, Y) & ~((X > 0) & (Y < A))

    p, _ = thin_film_pattern(state(wake), GEOM)
    assert p["state"] == "II" and p["wake_open"] and not p["bubble_enclosed"]
    assert p["wake_gas_length_over_a"] == pytest.approx(11.0, abs=0.06)   # to the outlet


def test_the_raster_is_the_metrics_raster_mirrored_with_the_island_blank():
    r = thin_film_raster(state(ring), GEOM)
    assert r.x[0] == GEOM.x_min and r.x[-1] == GEOM.x_max and r.y[0] == -GEOM.y_max
    np.testing.assert_array_equal(np.isnan(r.alpha), r.island)
    both = ~r.island & ~r.island[::-1]
    np.testing.assert_allclose(r.alpha[::-1][both], r.alpha[both])       # mirrored
    assert r.dx == pytest.approx(A / 20)


def test_the_raster_interpolation_is_scipys_bilinear():
    """The separable weights give what scipy's RegularGridInterpolator (linear) gives, at
    points between, on and beyond-clipped the source nodes."""
    from scipy.interpolate import RegularGridInterpolator

    from ehlfoam.metrics.thin_film import _linear_weights

    rng = np.random.default_rng(3)
    sy, sx = np.cumsum(rng.uniform(0.5, 1.5, 9)), np.cumsum(rng.uniform(0.5, 1.5, 13))
    f = rng.uniform(size=(9, 13))
    dy = np.clip(np.linspace(sy[0] - 1, sy[-1] + 1, 31), sy[0], sy[-1])
    dx = np.clip(np.r_[np.linspace(sx[0], sx[-1], 40), sx], sx[0], sx[-1])
    ours = _linear_weights(sy, dy) @ f @ _linear_weights(sx, dx).T
    gy, gx = np.meshgrid(dy, dx, indexing="ij")
    theirs = RegularGridInterpolator((sy, sx), f)(np.column_stack([gy.ravel(), gx.ravel()]))
    assert np.allclose(ours, theirs.reshape(gy.shape), rtol=0, atol=1e-12)
