"""The steady-state test, the mass balance and the dissolved-air budget of the run monitor, on
synthetic histories and fields."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ehlfoam.spec.case import load_case_spec
from ehlfoam.run.fields import Sample, gas_dissolution, gas_release, smeared_oil_fraction
from ehlfoam.run.monitor import (CLEARANCE_WARNING, OFF_OUTLET_WARNING, REAR_CELL_WARNING, boundary_warnings, dissolved_air_budget, mass_balance, rear_cell_warnings, rear_meniscus_cell, steady_test)
from tests.tiny import tiny_geometry as _geometry


def history(volumes, menisci, dt=0.01, state="I"):
    return [Sample(time=(k + 1) * dt, oil_volume=v, oil_in=1.0, oil_out=1.0,
                   pattern={"state": state, "inlet_meniscus_distance_over_a": m,
                            "flooded_length_over_a": 8.0, "flooded_width_over_a": 6.0,
                            "wake_gas_length_over_a": 0.0})
            for k, (v, m) in enumerate(zip(volumes, menisci))]


def test_steady_after_one_unchanged_transit():
    h = history([1.0] * 12, [3.0] * 12)
    assert steady_test(h, window=0.1, tol=0.01, length_scale=10.0) is not None


def test_not_steady_before_one_transit_has_passed():
    h = history([1.0] * 5, [3.0] * 5)
    assert steady_test(h, window=0.1, tol=0.01, length_scale=10.0) is None


@pytest.mark.parametrize("volumes, menisci", [
    ([1.0] * 11 + [1.02], [3.0] * 12),          # oil volume still changing by 2 %
    ([1.0] * 12, [3.0] * 11 + [3.2]),           # meniscus moved by 0.2 a > 0.1 a
])
def test_not_steady_while_something_changes(volumes, menisci):
    assert steady_test(history(volumes, menisci), window=0.1, tol=0.01,
                       length_scale=10.0) is None


def test_not_steady_when_the_state_flips():
    h = history([1.0] * 12, [3.0] * 12)
    h[-1].pattern["state"] = "II"
    assert steady_test(h, window=0.1, tol=0.01, length_scale=10.0) is None


def fluctuating(n, volume_drift=0.0):
    """A flooded region whose width jumps between 6.5, 5.75 and 5.75 a from write to write
    (its fingers; mean 6 a), the oil volume drifting by volume_drift per write."""
    h = history([1.0 + volume_drift * k for k in range(n)], [3.0] * n)
    for k, s in enumerate(h):
        s.pattern["flooded_width_over_a"] = 6.0 + (0.5 if k % 3 == 0 else -0.25)
    return h


def test_a_fluctuating_flow_is_steady_in_the_mean():
    # the last write differs by 0.75 a from the one a transit (10 writes) earlier
    h = fluctuating(22)
    assert steady_test(h[:11], window=0.1, tol=0.01, length_scale=10.0) is None  # < 2 windows
    assert steady_test(h, window=0.1, tol=0.01, length_scale=10.0) == "window mean"
    assert steady_test(history([1.0] * 12, [3.0] * 12), window=0.1, tol=0.01,
                       length_scale=10.0) == "last write"


@pytest.mark.parametrize("change", ["volume", "state", "width"])
def test_not_steady_in_the_mean_while_the_mean_moves(change):
    h = fluctuating(22, volume_drift=0.004 if change == "volume" else 0.0)
    if change == "state":
        h[-3].pattern["state"] = "II"
    if change == "width":       # the mean width grows by 0.2 a per transit
        for k, s in enumerate(h):
            s.pattern["flooded_width_over_a"] += 0.02 * k
    assert steady_test(h, window=0.1, tol=0.01, length_scale=10.0) is None


def test_not_steady_while_the_oil_starts_rising_again():
    """Flat for two transits, then the oil rises 1.5 % a transit (0.15 % a write) over the
    last one: the window means are 0.8 % apart and the last write's partner a transit back
    is 1.5 % below, so without the trend a 1 % test in the mean passes; with it, none."""
    h = fluctuating(32)
    for k, s in enumerate(h[21:], start=1):
        s.oil_volume = 1.0 + 0.0015 * k
    assert steady_test(h, window=0.1, tol=0.01, length_scale=10.0) is None
    assert steady_test(h, window=0.1, tol=0.02, length_scale=10.0) == "window mean"


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


def test_a_region_spilling_over_the_side_is_flagged_and_one_inside_is_not():
    from ehlfoam.run.fields import off_outlet_share
    # the coarse level at size_far 0.2 a reaching the 8 a side: 53-61 % off the outlet
    spilling = off_outlet_share({"outlet": 0.45, "side": 0.55, "inlet": 0.0})
    [warning] = boundary_warnings(spilling)
    assert warning.text.startswith("55% of the outflow left through the side or upstream")
    assert "domain.side" in warning.text
    assert boundary_warnings(off_outlet_share({"outlet": 0.996, "side": 0.004})) == []
    assert boundary_warnings(OFF_OUTLET_WARNING) == []
    assert boundary_warnings(None) == []


def test_a_region_near_an_open_boundary_is_flagged():
    # a film-resolving run's rear meniscus at 13.5 a against the 14 a outlet
    [warning] = boundary_warnings(0.0, {"flooded_clearance_over_a": 0.5,
                                        "flooded_nearest_boundary": "outlet"})
    assert warning.text.startswith("the flooded region is 0.50 a from the outlet boundary")
    assert "domain.downstream" in warning.text
    [warning] = boundary_warnings(None, {"flooded_clearance_over_a": 0.2,
                                         "flooded_nearest_boundary": "side"})
    assert "domain.side" in warning.text
    assert boundary_warnings(0.0, {"flooded_clearance_over_a": CLEARANCE_WARNING,
                                   "flooded_nearest_boundary": "side"}) == []
    assert boundary_warnings(0.0, {"flooded_clearance_over_a": None,
                                   "flooded_nearest_boundary": None}) == []
    # both at once: spilled over the side and still touching it
    assert len(boundary_warnings(0.55, {"flooded_clearance_over_a": 0.0,
                                        "flooded_nearest_boundary": "side"})) == 2


def test_the_cells_at_the_rear_meniscus_are_read_off_the_spec_and_coarse_ones_flagged():
    """The default medium level's rear meniscus (11 a behind the contact on y = 0) sits in its
    far-field cells; runs/nominal_films.toml's box puts 0.1 a cells there; an open wake has no
    rear meniscus."""
    root = Path(__file__).resolve().parents[2] / "examples" / "cases"
    nominal, films = (load_case_spec(root / n) for n in ("nominal.toml", "nominal_films.toml"))
    closed = {"state": "I", "flooded_x_max_over_a": 11.0}
    far = rear_meniscus_cell(nominal, closed)
    assert far == pytest.approx(nominal.mesh.level()["size_far"])
    assert rear_meniscus_cell(films, closed) == pytest.approx(0.1)
    # nearer the contact the cells shrink with the distance from it, below the far size
    assert rear_meniscus_cell(nominal, {**closed, "flooded_x_max_over_a": 3.0}) < far
    assert rear_meniscus_cell(nominal, {**closed, "state": "II"}) is None
    assert rear_meniscus_cell(nominal, {"state": "I", "flooded_x_max_over_a": None}) is None
    assert rear_meniscus_cell(nominal, None) is None
    [warning] = rear_cell_warnings(far)
    assert warning.text.startswith(f"the rear meniscus sits in {far:.2f} a cells")
    assert "mesh.refine" in warning.text and "nominal_films.toml" in warning.text
    assert rear_cell_warnings(0.1) == []
    assert rear_cell_warnings(REAR_CELL_WARNING) == []
    assert rear_cell_warnings(None) == []
