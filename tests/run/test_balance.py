"""The run's balances (oil, dissolved air) and the gas and smeared oil a written time gives,
on synthetic histories and fields."""

from __future__ import annotations

import numpy as np
import pytest

from ehlfoam.run.balance import dissolved_air_budget, mass_balance
from ehlfoam.run.fields import Sample, gas_dissolution, gas_release, smeared_oil_fraction
from tests.tiny import tiny_geometry as _geometry


def test_mass_balance_closes_for_a_consistent_history():
    # volume grows at q_in - q_out = 2 - 1 = 1 per second
    h = [Sample(time=t, oil_volume=5.0 + t, oil_in=2.0, oil_out=1.0, pattern={})
         for t in (0.1, 0.2, 0.3, 0.4)]
    mb = mass_balance(h)
    assert mb["oil_carried_in_m3"] == pytest.approx(0.6)
    assert mb["oil_mass_balance_error"] == pytest.approx(0.0, abs=1e-12)
    h[-1].oil_volume += 0.06     # 10 % of the oil carried in, lost or gained
    assert mass_balance(h)["oil_mass_balance_error"] == pytest.approx(0.1)


def test_gas_release_sums_kunz_vaporisation_below_the_release_pressure():
    # k (pSat - p) alpha V per cell below pSat, doubled for the half domain: cell 1 is
    # 10 kPa below pSat and half oil, cell 2 all oil at pSat, cell 3 above it
    geom = _geometry(gas_release_rate=1e-3, release_pressure_gauge=-1e4)
    p = np.array([-2e4, -1e4, 0.0])
    alpha, volumes = np.array([0.5, 1.0, 1.0]), np.array([2e-12, 1e-12, 1e-12])
    assert gas_release(p, alpha, volumes, geom) == pytest.approx(2 * 1e-3 * 1e4 * 0.5 * 2e-12)
    assert gas_release(p, alpha, volumes, _geometry()) is None          # releases nothing
    assert gas_release(None, alpha, volumes, geom) is None              # no p written


def test_gas_dissolution_sums_kunz_condensation_above_the_release_pressure():
    # C alpha^2 (1 - alpha) V per cell above pSat, doubled for the half domain: cell 1 is
    # below pSat (nothing), cell 2 two-thirds oil above it, cell 3 all oil (no gas to lose)
    geom = _geometry(gas_release_rate=1e-3, release_pressure_gauge=-1e4,
                     gas_dissolution_rate=100.0)
    p = np.array([-2e4, 0.0, 0.0])
    alpha, volumes = np.array([0.5, 2.0 / 3.0, 1.0]), np.array([1e-12, 3e-12, 1e-12])
    expected = 2 * 100.0 * (4.0 / 27.0) * 3e-12
    assert gas_dissolution(p, alpha, volumes, geom) == pytest.approx(expected)
    assert gas_dissolution(p, alpha, volumes, _geometry(gas_release_rate=1e-3)) is None
    assert gas_dissolution(None, alpha, volumes, geom) is None


def test_dissolved_air_budget_compares_the_release_with_all_the_oil():
    # 1 m3 of oil at the start, 2 m3/s in for 1 s: 3 m3 of oil holding 0.1 x 3 m3 of air;
    # 0.15 m3/s of gas released for 1 s is half of it, and 0.15 / (0.1 x 2) of the
    # dissolved air the supply brings in per second
    h = [Sample(time=t, oil_volume=1.0, oil_in=2.0, oil_out=2.0,
                pattern={"gas_release_m3_s": 0.15}) for t in (0.0, 0.5, 1.0)]
    b = dissolved_air_budget(h, air_solubility=0.1, window=0.6)
    assert b["dissolved_air_m3"] == pytest.approx(0.3)
    assert b["gas_released_m3"] == pytest.approx(0.15)
    assert b["gas_release_over_dissolved_air"] == pytest.approx(0.5)
    assert b["gas_release_over_dissolved_inflow"] == pytest.approx(0.75)
    h[0].pattern["gas_release_m3_s"] = 1.0      # before the window: only the total sees it
    b = dissolved_air_budget(h, air_solubility=0.1, window=0.6)
    assert b["gas_released_m3"] == pytest.approx(0.25 * 1.15 + 0.5 * 0.15)
    assert b["gas_release_over_dissolved_inflow"] == pytest.approx(0.75)
    for s in h:
        s.pattern["gas_release_m3_s"] = None                        # a scene without release
    assert dissolved_air_budget(h, air_solubility=0.1, window=0.6) == {}


def test_smeared_oil_fraction_counts_the_oil_in_cells_that_are_neither_oil_nor_air():
    # oil volumes 1 + 1 + 0 + 0.99 + 0.01 + 1 = 4 (the overshoot 1.2 clipped to 1; unclipped
    # the share would be 1 / 4.2); only the half-full cell (volume 2) is smeared: 0.99 and
    # 0.01 lie outside (0.02, 0.98)
    alpha = np.array([1.0, 0.5, 0.0, 0.99, 0.01, 1.2])
    volumes = np.array([1.0, 2.0, 3.0, 1.0, 1.0, 1.0])
    assert smeared_oil_fraction(alpha, volumes) == pytest.approx(1.0 / 4.0)
    assert smeared_oil_fraction(np.zeros(3), np.ones(3)) is None        # no oil
    assert smeared_oil_fraction(np.full(2, 0.5), np.ones(2)) == pytest.approx(1.0)
