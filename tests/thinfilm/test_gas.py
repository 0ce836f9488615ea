"""The bubble's gas balance (ehlfoam.thinfilm.gas): a closed cavity with no exchange keeps its
air and follows p V = const; one with release only fills toward the oil's saturation
pressure at the rate its closure gives (Higbie's coefficient over the meniscus area); and in
a march with the balance the gas budget and the oil close to round-off."""

from __future__ import annotations

import numpy as np
import pytest

from ehlfoam.thinfilm.gas import (GAS_CONSTANT, CavityGas, GasBalance, film_share,
                                  penetration_coefficient)
from ehlfoam.thinfilm.march import Marcher
from ehlfoam.thinfilm.problem import ThinFilmProblem
from ehlfoam.thinfilm.state import load_state, save_state

T, P_ATM, P_R = 313.15, 1.013e5, 9e4
D = 1e-6      # cells of 1 mm
H = 20e-6     # a uniform gap of 20 um


def _box(ny=5, nx=8):
    """A 5 x 8 grid of uniform gap; the cavity a 2 x 3 block enclosed by flooded cells."""
    h = np.full((ny, nx), H)
    hx, hy = np.full((ny, nx - 1), H), np.full((ny - 1, nx), H)
    cavity = np.zeros((ny, nx), bool)
    cavity[1:3, 2:5] = True
    return h, hx, hy, cavity


def _gas(solubility=0.0, diffusivity=1e-9, speed=0.01):
    k = GasBalance(solubility=solubility, diffusivity=diffusivity, temperature=T,
                   ambient=P_ATM, release=P_R)
    h, hx, hy, cavity = _box()
    return CavityGas(k, h, hx, hy, D, speed), cavity, h


def test_a_closed_cavity_with_no_exchange_keeps_its_air_and_follows_pv_constant():
    """No solubility: its air is what it opened with (at the release pressure), and as the
    oil in its cells grows and shrinks its pressure is n R T / V, p V fixed, to round-off."""
    gas, cavity, h = _gas(solubility=0.0)
    flooded = ~cavity
    outer = np.zeros_like(cavity)
    c0 = np.where(cavity, 0.5 * h, h)
    gas.advance(cavity, c0, cavity, outer, c0, flooded, 1e-3)
    n0 = gas.held()
    v0 = 6 * 0.5 * H * D * D
    assert n0 == pytest.approx(P_R * v0 / (GAS_CONSTANT * T), rel=1e-12)
    assert gas.budget["released_at_release_pressure_mol"] == pytest.approx(n0, rel=1e-12)
    for share in (0.3, 0.4, 0.2, 0.45):              # films thicker and thinner
        c = np.where(cavity, share * h, h)
        gas.advance(cavity, c, cavity, outer, c, flooded, 1e-3)
        v = 6 * (1 - share) * H * D * D
        p = gas.pressure(cavity, c)[cavity]
        assert np.allclose(p * v, P_R * v0, rtol=1e-12)
        assert gas.held() == pytest.approx(n0, rel=1e-12)
    assert abs(gas.budget_residual()) < 1e-12 * n0


def test_a_cavity_with_release_only_fills_toward_saturation_at_the_rate_of_its_closure():
    """Oil saturated at ambient around a cavity of fixed volume at the release pressure:
    dn/dt = s k_L A (p_atm - p) / (R T), k_L = 2 sqrt(D u / (pi l)) over the meniscus area
    A = 10 faces x pi h / 2 x d (no films: its cells hold no oil), so p relaxes to p_atm as
    exp(-s k_L A R T t / (V R T)); the march's p after 1, 5 and 20 relaxation times of
    steps as that, the budget all release."""
    s, diff, u = 0.09, 1e-9, 0.01
    gas, cavity, h = _gas(solubility=s, diffusivity=diff, speed=u)
    flooded, outer = ~cavity, np.zeros_like(cavity)
    c = np.where(cavity, 0.0, h)
    v = 6 * H * D * D
    area = 10 * 0.5 * np.pi * H * D
    kl = penetration_coefficient(diff, 3 * D / u)
    assert kl == pytest.approx(2 * np.sqrt(diff * u / (np.pi * 3 * D)))
    lam = s * kl * area / v
    dt = 0.05 / lam
    t = 0.0
    for n_steps in (20, 80, 300):
        for _ in range(n_steps):
            gas.advance(cavity, c, cavity, outer, c, flooded, dt)
            t += dt
        p = gas.pressure(cavity, c)[cavity][0]
        expected = P_ATM - (P_ATM - P_R) * np.exp(-lam * t)
        assert p == pytest.approx(expected, rel=1e-9)
    assert P_ATM - p < 1e-6 * P_ATM
    b = gas.budget
    assert b["dissolved_by_diffusion_mol"] == 0.0 and b["escaped_to_air_mol"] == 0.0
    assert abs(gas.budget_residual()) < 1e-12 * gas.held()


def test_a_films_share_of_its_excess_follows_the_slab_solution():
    """Nothing at Fo = 0, all of it for Fo >> 1, sqrt-law at small Fo (2 sqrt(Fo / pi))."""
    assert film_share(0.0) == 0.0
    assert film_share(5.0) == pytest.approx(1.0, abs=1e-5)
    assert film_share(1e-4) == pytest.approx(2 * np.sqrt(1e-4 / np.pi), rel=1e-3)


def test_a_cavity_reaching_the_outer_air_gives_it_its_air_and_one_that_closes_dissolves():
    """All of a cavity's air escapes when its cells join the outer air, and dissolves when
    they all flood; the budget says so."""
    gas, cavity, h = _gas(solubility=0.0)
    flooded = ~cavity
    c = np.where(cavity, 0.5 * h, h)
    gas.advance(cavity, c, cavity, np.zeros_like(cavity), c, flooded, 1e-3)
    n0 = gas.held()
    gas.advance(cavity, c, np.zeros_like(cavity), cavity.copy(), c, flooded, 1e-3)
    assert gas.held() == 0.0 and gas.budget["escaped_to_air_mol"] == pytest.approx(n0)
    gas.advance(cavity, c, cavity, np.zeros_like(cavity), c, flooded, 1e-3)
    n1 = gas.held()
    gas.advance(cavity, c, np.zeros_like(cavity), np.zeros_like(cavity), h,
                np.ones_like(cavity), 1e-3)
    assert gas.budget["dissolved_on_collapse_mol"] == pytest.approx(n1)
    assert abs(gas.budget_residual()) < 1e-12 * n0


A = 1.37e-4


def _ball(**kw):
    base = dict(gap=lambda x, y: 1e-6 + (np.asarray(x) ** 2 + np.asarray(y) ** 2) / (2 * 9.525e-3),
                speed=0.008, viscosity=0.0216, surface_tension=0.03, contact_angle=15.0,
                supply=16e-6, track_half_width=3e-4, x_range=(-11 * A, 19 * A),
                y_max=11 * A, island_radius=1.5 * A, cell=0.4 * A, initial_radius=7 * A,
                cavitation_pressure=-8e3)
    return ThinFilmProblem(**(base | kw))


def test_a_march_with_the_balance_keeps_its_oil_and_closes_its_gas_budget(tmp_path):
    """A rigid ball whose exit falls below the release pressure: a bubble opens at it, fills
    with air toward the oil's saturation (ambient) within a few transits, enclosed; the oil
    is kept to round-off and the budget (released, dissolved, escaped) closes to round-off
    of the air held. Its state keeps the air: a march from it goes on with it, and the
    state's pressure in the bubble is its gas's."""
    k = GasBalance(solubility=0.09, diffusivity=1e-9, temperature=T, ambient=P_ATM,
                   release=P_ATM - 8e3)
    prob = _ball(gas=k)
    m = Marcher(prob, transit_length=10 * A)
    for _ in range(6 * m.steps_per_transit):
        m.step()
    assert m.cavity().any()
    assert m.mass_balance_error() < 1e-12
    g = m.gas
    assert g.held() > 0
    assert abs(g.budget_residual()) < 1e-9 * g.held()
    assert g.budget["released_by_diffusion_mol"] > 0
    p = m.history[-1]["gas_pressure_Pa"]
    assert P_ATM - 8e3 < p < 1.05 * P_ATM     # filled from the release pressure
    assert p > m.history[0]["gas_pressure_Pa"]
    save_state(m.solution(), tmp_path / "state.npz")
    sol = load_state(tmp_path / "state.npz")
    gauge = sol.gauge_pressure()[sol.cavity]
    assert np.allclose(gauge, g.pressure(m.cavity(), m.c)[m.cavity()] - P_ATM)
    assert gauge.max() > -8e3 + 1.0            # above the release pressure: its gas's
    again = Marcher(prob, start=sol, transit_length=10 * A)
    assert again.gas.held() == pytest.approx(g.held(), rel=1e-12)
    again.step()
    assert abs(again.gas.budget_residual()) < 1e-9 * g.held()


def test_a_state_on_another_grid_hands_its_bubble_its_air():
    """A march on cells half the size, started from a state on the coarser cells, starts
    with the state's air in its bubble (not empty at the release pressure, to fill again by
    diffusion over tens of transits), its pressure near the state's."""
    k = GasBalance(solubility=0.09, diffusivity=1e-9, temperature=T, ambient=P_ATM,
                   release=P_ATM - 8e3)
    coarse = Marcher(_ball(gas=k), transit_length=10 * A)
    for _ in range(6 * coarse.steps_per_transit):
        coarse.step()
    sol = coarse.solution()
    fine = Marcher(_ball(gas=k, cell=0.2 * A), start=sol, transit_length=10 * A)
    assert fine.cavity().any()
    assert fine.gas.held() == pytest.approx(coarse.gas.held(), rel=1e-12)
    p_coarse = coarse.gas.pressure(coarse.cavity(), coarse.c)[coarse.cavity()].max()
    p_fine = fine.gas.pressure(fine.cavity(), fine.c)[fine.cavity()].max()
    assert p_fine == pytest.approx(p_coarse, rel=0.1)
    assert p_fine > P_ATM - 8e3 + 1.0          # above the release pressure: its air's
    fine.step()
    assert abs(fine.gas.budget_residual()) < 1e-9 * fine.gas.held()


def test_the_gas_needs_an_outlet_and_its_constants_are_checked():
    k = GasBalance(solubility=0.09, diffusivity=1e-9, temperature=T, ambient=P_ATM,
                   release=P_R)
    with pytest.raises(ValueError, match="gas"):
        _ball(gas=k, cavitation_pressure=None)
    with pytest.raises(ValueError, match="release"):
        GasBalance(solubility=0.09, diffusivity=1e-9, temperature=T, ambient=P_ATM,
                   release=P_ATM)
