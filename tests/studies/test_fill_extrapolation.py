"""bench/fill_extrapolation.py on histories with a known balance: a region filling as
V = V* - A exp(-t / tau) with its width growing along the oil held."""

from __future__ import annotations

import numpy as np
import pytest

from bench.fill_extrapolation import extrapolate, per_transit

TRANSIT = 0.1713      # s
INFLOW = 7.68e-11     # m3/s, the nominal case's supply
V_STAR = 170e-12      # m3, where the synthetic run balances


def history(tau_transits: float, transits: int = 12, writes: int = 10, noise: float = 0.0,
            seed: int = 0) -> dict[str, np.ndarray]:
    """A history.csv as read_history gives it: ``writes`` writes a transit; the fill rate is
    (V* - V) / (INFLOW tau) exactly, so the balance is V* and the width there 14 a."""
    t = np.arange(1, transits * writes + 1) * TRANSIT / writes
    tau = tau_transits * TRANSIT
    volume = V_STAR - INFLOW * tau * 0.3 * np.exp(-t / tau)   # fill rate 0.3 at t = 0
    volume = volume * (1 + noise * np.random.default_rng(seed).standard_normal(t.size))
    return {"time_s": t, "oil_volume_m3": volume, "oil_in_m3_s": np.full(t.size, INFLOW),
            "flooded_width_over_a": 14.0 + 0.05e12 * (volume - V_STAR),
            "flooded_length_over_a": np.full(t.size, 19.0),
            "inlet_meniscus_distance_over_a": np.full(t.size, np.nan)}


def test_both_readings_find_the_balance_of_an_exponential_fill():
    rows = per_transit(history(tau_transits=10), TRANSIT)
    assert len(rows) == 12
    assert rows[-1]["fill_rate"] == pytest.approx(0.3 * np.exp(-11.5 / 10), rel=0.02)
    b = extrapolate(rows, 8)
    assert b["fit_transits"] == [5, 12]
    for reading in ("linear", "exponential"):
        assert b[reading]["oil_volume_m3"] == pytest.approx(V_STAR, rel=0.005)
        assert b[reading]["flooded_width_over_a"] == pytest.approx(14.0, abs=0.02)
        assert b[reading]["flooded_length_over_a"] == pytest.approx(19.0)
        assert b[reading]["inlet_meniscus_distance_over_a"] is None   # never found
    assert b["exponential_transits_to_95pc"] == pytest.approx(30, rel=0.05)


def test_a_draining_run_balances_from_above_and_an_accelerating_one_not_at_all():
    h = history(tau_transits=10)
    h["oil_volume_m3"] = 2 * V_STAR - h["oil_volume_m3"]   # draining towards V*
    b = extrapolate(per_transit(h, TRANSIT), 8)
    for reading in ("linear", "exponential"):
        assert b[reading]["oil_volume_m3"] == pytest.approx(V_STAR, rel=0.005)
    h = history(tau_transits=10)
    h["oil_volume_m3"] = 100e-12 + INFLOW * 0.5 * h["time_s"] ** 2   # filling ever faster
    b = extrapolate(per_transit(h, TRANSIT), 8)
    assert b["linear"] is None and b["exponential"] is None


def test_too_few_transits_is_refused_with_the_count():
    rows = per_transit(history(tau_transits=10, transits=2), TRANSIT)
    with pytest.raises(ValueError, match="fit: 2 transits; at least 3"):
        extrapolate(rows, 8)


def test_half_transit_rows_halve_the_window_and_keep_the_balance():
    """--window 0.5: twice the rows, each ending half a transit after the last, the fill rate
    of the exponential at its middle, and the same balance from the last 16 rows."""
    h = history(tau_transits=10)
    h["oil_out_m3_s"] = h["oil_in_m3_s"] * 0.6
    rows = per_transit(h, TRANSIT, window=0.5)
    assert [r["transit"] for r in rows[:3]] == [0.5, 1.0, 1.5] and len(rows) == 24
    assert rows[-1]["fill_rate"] == pytest.approx(0.3 * np.exp(-11.75 / 10), rel=0.02)
    assert rows[-1]["out_over_in"] == pytest.approx(0.6)
    b = extrapolate(rows, 16)
    assert b["fit_transits"] == [4.5, 12.0]
    assert b["linear"]["oil_volume_m3"] == pytest.approx(V_STAR, rel=0.005)
