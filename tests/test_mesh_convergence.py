"""runs/convergence.py: the observed order and grid convergence index (Celik et al. 2008) on
metrics with a known limit: f(h) = f0 + C h^p; and the means over a window of writes that
bench/mesh_convergence.py compares."""

from __future__ import annotations

import csv
import json
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pytest

from bench.mesh_convergence import at_time
from generator.case_writer import META
from runs.convergence import METRICS, last_transit, observed_order, window_mean
from tiny import tiny_geometry


@pytest.mark.parametrize("sizes", [(0.2, 0.1, 0.05), (0.8, 0.55, 0.38), (0.05, 0.2, 0.1)])
@pytest.mark.parametrize("p", [1.0, 2.0, 0.6])
def test_a_power_law_gives_its_order_and_its_limit(sizes, p):
    f = tuple(14.0 + 3.0 * h ** p for h in sizes)
    o = observed_order(sizes, f)
    assert o["behaviour"] == "monotone"
    assert 0 < o["R"] < 1
    assert o["order"] == pytest.approx(p, rel=1e-6)
    assert o["extrapolated"] == pytest.approx(14.0, rel=1e-6)
    assert o["asymptotic"] is (0.5 <= p <= 3.0)
    assert o["sizes"] == sorted(sizes)                       # index 1 is the finest
    f1 = 14.0 + 3.0 * min(sizes) ** p
    assert o["error_fine"] == pytest.approx((f1 - 14.0) / 14.0, rel=1e-6)
    assert o["gci_fine"] == pytest.approx(1.25 * (f1 - 14.0) / f1, rel=1e-6)


def test_alternating_changes_that_shrink_are_oscillatory_convergence():
    o = observed_order((0.4, 0.2, 0.1), (12.0, 14.0, 13.5))    # +2, then -0.5
    assert o["behaviour"] == "oscillatory"
    assert o["R"] == pytest.approx(-0.25)
    assert o["order"] == pytest.approx(2.0)
    assert o["extrapolated"] == pytest.approx((4 * 13.5 - 14.0) / 3)    # beyond f1, as the sign flips


@pytest.mark.parametrize("f", [(15.66, 14.59, 13.0), (11.5, 13.7, 16.7)])
def test_changes_that_do_not_shrink_are_divergent_and_get_no_extrapolation(f):
    o = observed_order((0.2, 0.1, 0.05), f)
    assert o["behaviour"] == "divergent"
    assert abs(o["R"]) >= 1
    assert "extrapolated" not in o and "gci_fine" not in o


def test_changes_inside_the_jitter_say_nothing_about_the_order():
    f = (6.64, 6.57, 6.45)
    assert observed_order((0.8, 0.55, 0.38), f)["behaviour"] == "divergent"
    o = observed_order((0.8, 0.55, 0.38), f, noise=0.27)
    assert o["behaviour"] == "within noise"
    assert o["spread"] == pytest.approx(0.19)
    assert "order" not in o


def test_sizes_must_be_three_different_positive_values():
    with pytest.raises(ValueError, match="sizes"):
        observed_order((0.1, 0.1, 0.05), (1.0, 2.0, 3.0))
    with pytest.raises(ValueError, match="sizes"):
        observed_order((0.0, 0.1, 0.05), (1.0, 2.0, 3.0))


def test_an_order_far_from_the_schemes_is_flagged_not_asymptotic():
    o = observed_order((0.2, 0.1, 0.05), (15.57, 14.59, 13.71))   # changes 0.98, 0.88
    assert o["behaviour"] == "monotone"
    assert o["order"] == pytest.approx(0.155, abs=0.005)
    assert o["asymptotic"] is False
    assert observed_order((0.2, 0.1, 0.05), (14.4, 14.1, 14.025))["asymptotic"] is True


def _case_with_history(folder: Path, times: np.ndarray, inlet: np.ndarray) -> Path:
    """A case folder with a made-up geometry (transit 0.1 s) and a history.csv whose inlet
    meniscus is ``inlet`` and whose width grows by 1 a a second."""
    (folder / META).mkdir(parents=True)
    (folder / META / "geometry.json").write_text(json.dumps(asdict(tiny_geometry())))
    with open(folder / "history.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["time_s", "state", *METRICS])
        for t, x in zip(times, inlet):
            w.writerow([t, "I", x, 12.0 + t, 18.0, 1.5e-10])
    return folder


def test_a_window_averages_out_a_meniscus_that_jumps_write_by_write(tmp_path):
    # writes every 0.01 s (a tenth of a transit); the inlet jumps 4.5 / 5.5 a write by write
    times = np.round(np.arange(1, 61) * 0.01, 6)
    case = _case_with_history(tmp_path / "c", times, np.where(np.arange(60) % 2, 5.5, 4.5))
    one = at_time(case, 0.3)
    assert one["inlet_meniscus_distance_over_a"] in (4.5, 5.5)
    mean = at_time(case, 0.3, window=0.5)         # the writes at 0.25-0.30 s
    assert mean["writes_averaged"] == 6
    assert mean["inlet_meniscus_distance_over_a"] == pytest.approx(5.0)
    assert mean["flooded_width_over_a"] == pytest.approx(12.275)
    assert mean["jitter"]["inlet_meniscus_distance_over_a"] == pytest.approx(0.5)
    assert mean["time_s"] == pytest.approx(0.3)
    assert at_time(case, 0.9, window=0.5) is None     # the run never got there
    last = last_transit(case)                         # the writes at 0.5-0.6 s
    assert last["writes_averaged"] == 11 and last["time_s"] == pytest.approx(0.6)
    assert last == window_mean(case, None, 1.0)
    assert last["flooded_width_over_a"] == pytest.approx(12.55)
