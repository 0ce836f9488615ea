"""The run monitor's steady-state tests on synthetic histories."""

from __future__ import annotations

import pytest

from ehlfoam.run.fields import Sample
from ehlfoam.run.steady import steady_test


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
