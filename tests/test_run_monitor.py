"""The steady-state test and the mass balance of the run monitor, on synthetic histories."""

from __future__ import annotations

import pytest

from runs.case_fields import Sample
from runs.run_case import mass_balance, steady_test


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


def test_mass_balance_closes_for_a_consistent_history():
    # volume grows at q_in - q_out = 2 - 1 = 1 per second
    h = [Sample(time=t, oil_volume=5.0 + t, oil_in=2.0, oil_out=1.0, pattern={})
         for t in (0.1, 0.2, 0.3, 0.4)]
    mb = mass_balance(h)
    assert mb["oil_carried_in_m3"] == pytest.approx(0.6)
    assert mb["oil_mass_balance_error"] == pytest.approx(0.0, abs=1e-12)
    h[-1].oil_volume += 0.06     # 10 % of the oil carried in, lost or gained
    assert mass_balance(h)["oil_mass_balance_error"] == pytest.approx(0.1)
