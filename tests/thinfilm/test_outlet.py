"""The thin-film model's outlet (ehlfoam.thinfilm.cavity): gas at the cavitation pressure
where the oil would fall below it, Elrod-Adams's film content carried through it. A strip's
inlet meniscus held at the cavitation pressure where its own suction is stronger (the 1D
theory), a bubble behind a contact once the pressure there would fall below the cavitation
pressure (enclosed: state I), none below it, the oil kept to round-off, and which gas is a
cavity."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from ehlfoam.metrics.raster import Geometry
from ehlfoam.metrics.thin_film import thin_film_pattern
from ehlfoam.thinfilm import ThinFilmProblem, landau_levich, solve_thin_film
from ehlfoam.thinfilm.cavity import cavities, outer_air
from ehlfoam.thinfilm.march import Marcher

ETA, U, SIGMA, THETA = 0.02, 0.01, 0.03, 15.0
COS = np.cos(np.radians(THETA))


def strip_gap(x, y):
    """A gap that does not vary along y: 20 um at x = 0, a 10 mm radius."""
    return 20e-6 + np.asarray(x) ** 2 / (2 * 0.01) + 0 * np.asarray(y)


def test_a_strip_inlet_meniscus_is_held_at_the_cavitation_pressure_where_it_would_pull_harder():
    """A strip fed s passes it as Landau-Levich films behind its rear meniscus (f h = s),
    and its inlet meniscus sits where the Reynolds rise to the rear,
    int 12 eta u (h - s) / h^3 dx, equals the rear's pressure less the inlet's. Without an
    outlet the inlet's is Young-Laplace's, 2.9 kPa of suction just past the gap's minimum;
    with a cavitation pressure of half that the oil there cannot hold it: the inlet's
    pressure is the cavitation pressure, and the meniscus sits 5 cells downstream, where the
    1D theory puts it (within the model's half cell); the rear meniscus stays."""
    s, cell = 4e-6, 5e-5
    h_rear = s / landau_levich(ETA, U, SIGMA)
    x_rear = np.sqrt(2 * 0.01 * (h_rear - 20e-6))
    p_rear = -2 * SIGMA * COS / h_rear

    def inlet(p_in):
        def mismatch(x):
            rise = quad(lambda t: 12 * ETA * U * (strip_gap(t, 0) - s) / strip_gap(t, 0) ** 3,
                        x, x_rear)[0]
            return rise - (p_rear - p_in(x))
        xs = np.linspace(-1.9e-3, 0.99 * x_rear, 80)
        k = np.nonzero(np.diff(np.sign([mismatch(x) for x in xs])))[0][0]
        return brentq(mismatch, xs[k], xs[k + 1])

    free = inlet(lambda x: -2 * SIGMA * COS / strip_gap(x, 0))
    p_cav = 0.5 * (p_rear - 2 * SIGMA * COS / strip_gap(free, 0))
    held = inlet(lambda x: max(-2 * SIGMA * COS / strip_gap(x, 0), p_cav))
    assert held - free > 5 * cell                       # the floor moves it
    prob = ThinFilmProblem(gap=strip_gap, speed=U, viscosity=ETA, surface_tension=SIGMA,
                           contact_angle=THETA, supply=s, track_half_width=1.0,
                           x_range=(-2e-3, 3e-3), y_max=2 * cell, island_radius=0.0,
                           cell=cell, initial_radius=0.8e-3, closed_side=True,
                           cavitation_pressure=p_cav)
    sol = solve_thin_film(prob, transits_max=10, tolerance=0.0, transit_length=5e-3)
    row = sol.flooded[0]
    assert (sol.flooded == row).all()
    first, last = np.nonzero(row)[0][[0, -1]]
    x = sol.grid.x
    assert abs(x[first] - cell / 2 - cell * sol.fill[0, first - 1] - held) <= 0.6 * cell
    assert abs(x[last] + cell / 2 + cell * sol.fill[0, last + 1] - x_rear) <= 0.5 * cell
    assert np.nanmin(sol.p) >= p_cav * (1 + 1e-9)
    assert not sol.cavity.any()                         # its gas is the outer air
    assert sol.mass_balance_error < 1e-12


A = 1.37e-4


def ball_gap(x, y):
    """A rigid ball on a flat: 1 um at the contact, R = 9.525 mm."""
    return 1e-6 + (np.asarray(x) ** 2 + np.asarray(y) ** 2) / (2 * 9.525e-3)


def ball_problem(**kw) -> ThinFilmProblem:
    base = dict(gap=ball_gap, speed=0.008, viscosity=0.0216, surface_tension=SIGMA,
                contact_angle=THETA, supply=16e-6, track_half_width=3e-4,
                x_range=(-11 * A, 19 * A), y_max=11 * A, island_radius=1.5 * A,
                cell=0.4 * A, initial_radius=7 * A)
    return ThinFilmProblem(**(base | kw))


GEOM = Geometry(x_min=-11 * A, x_max=19 * A, y_max=11 * A, island_radius=1.5 * A, a=A)


def _run(p_cav):
    sol = solve_thin_film(ball_problem(cavitation_pressure=p_cav), transits_max=6,
                          tolerance=0.0, transit_length=10 * A)
    return sol, thin_film_pattern(sol, GEOM)[0]


def test_a_bubble_forms_behind_the_contact_where_the_oil_would_fall_below_the_cavitation_pressure():
    """Without an outlet the oil behind the island holds -11.8 kPa; an outlet below that
    changes nothing; at -5 kPa and -2 kPa the cells there open to gas at the cavitation
    pressure, a bubble the region encloses (state I), longer the higher the pressure, and no
    flooded cell is left below it. The oil is kept to round-off all along."""
    free, pat_free = _run(None)
    low = float(np.nanmin(free.p))
    assert -13e3 < low < -10e3
    below, pat_below = _run(1.5 * low)
    assert not below.cavity.any()
    np.testing.assert_array_equal(below.flooded, free.flooded)
    lengths = []
    for p_cav in (-5e3, -2e3):
        sol, pat = _run(p_cav)
        assert sol.cavity.any()
        X, _ = np.meshgrid(sol.grid.x, sol.grid.y)
        assert (X[sol.cavity] > 0).all()                  # behind the contact
        assert np.nanmin(sol.p) >= p_cav * (1 + 1e-9)
        assert pat["state"] == "I" and pat["bubble_enclosed"] and not pat["wake_open"]
        assert pat["bubble_length_over_a"] > 0.5
        assert pat["bubble_volume_m3"] > 0
        assert sol.mass_balance_error < 1e-12
        assert sum(r["cells_opened_to_gas"] for r in sol.history) > 0
        lengths.append(pat["bubble_length_over_a"])
    assert pat_free["bubble_length_over_a"] == pat_below["bubble_length_over_a"] == 0.0
    assert lengths[1] > lengths[0] + 0.5


def test_the_oil_is_kept_to_round_off_through_the_outlet_step_by_step():
    """Over every step of a march whose cells keep opening to gas and filling again, the oil
    in the domain changes by what came in less what left through the outlet and the side,
    to round-off."""
    m = Marcher(ball_problem(cavitation_pressure=-2e3), transit_length=10 * A)
    oil = m.oil()
    for _ in range(3 * m.steps_per_transit):
        before = (m.oil_in, m.oil_out_outlet + m.oil_out_side)
        m.step()
        gained = m.oil() - oil
        came = (m.oil_in - before[0]) - (m.oil_out_outlet + m.oil_out_side - before[1])
        assert gained == pytest.approx(came, abs=1e-12 * m.q_in * m.dt * 1e3)
        assert (m.c >= -1e-12 * m.h.max()).all()     # no cell gives more than it holds
        oil = m.oil()
    opened = sum(r["cells_opened_to_gas"] for r in m.history)
    assert opened > 0 and m.cavity().any()
    assert m.mass_balance_error() < 1e-12


def test_gas_the_region_encloses_is_a_cavity_and_gas_open_to_the_edges_is_outer_air():
    """Open cells reaching the upstream column, the outlet column or the side row (unless it
    is closed) through other open cells are outer air; the rest, enclosed by the flooded
    cells, the island and the symmetry plane y = 0, are cavities."""
    flooded = np.ones((6, 10), bool)
    island = np.zeros_like(flooded)
    island[0, 3:5] = True
    flooded[island] = False
    flooded[0:2, 5:7] = False                      # a pocket behind the island, on y = 0
    flooded[3, 0:3] = False                        # a finger in from the upstream edge
    cav = cavities(flooded, island)
    assert cav[0:2, 5:7].all() and cav.sum() == 4
    assert outer_air(~flooded & ~island)[3, 0:3].all()
    flooded[0:2, 7:10] = False                     # the pocket opens to the outlet
    assert not cavities(flooded, island).any()
    side = np.ones((4, 5), bool)
    side[2:4, 2] = False                           # open to the side row
    assert not cavities(side, np.zeros_like(side)).any()
    assert cavities(side, np.zeros_like(side), closed_side=True)[2:4, 2].all()


@pytest.mark.parametrize("value", [0.0, 1e3, float("nan")])
def test_a_cavitation_pressure_at_or_above_ambient_is_refused(value):
    with pytest.raises(ValueError, match="cavitation_pressure .* is out of range: must be "
                                         "None or a finite gauge pressure < 0 Pa"):
        ball_problem(cavitation_pressure=value)
