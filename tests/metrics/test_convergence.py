"""ehlfoam.metrics.convergence: the observed order and grid convergence index (Celik et al.
2008) on metrics with a known limit: f(h) = f0 + C h^p; the means over a window of writes that
it compares; and the rest a metric relaxes to, from runs that approach it."""

from __future__ import annotations

import csv
import json
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pytest

from ehlfoam.case.geometry import META
from ehlfoam.metrics.convergence import METRICS, last_transit, observed_order, rest_value, window_mean
from tests.tiny import tiny_geometry


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


def _case_with_history(folder: Path, times: np.ndarray, inlet: np.ndarray,
                       width: np.ndarray | None = None) -> Path:
    """A case folder with a made-up geometry (transit 0.1 s) and a history.csv whose inlet
    meniscus is ``inlet`` and whose width is ``width`` (default: growing by 1 a a second)."""
    (folder / META).mkdir(parents=True)
    (folder / META / "geometry.json").write_text(json.dumps(asdict(tiny_geometry())))
    width = 12.0 + times if width is None else width
    with open(folder / "history.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["time_s", "state", *METRICS])
        for t, x, y in zip(times, inlet, width):
            w.writerow([t, "I", x, y, 18.0, 1.5e-10])
    return folder


def test_a_window_averages_out_a_meniscus_that_jumps_write_by_write(tmp_path):
    # writes every 0.01 s (a tenth of a transit); the inlet jumps 4.5 / 5.5 a write by write
    times = np.round(np.arange(1, 61) * 0.01, 6)
    case = _case_with_history(tmp_path / "c", times, np.where(np.arange(60) % 2, 5.5, 4.5))
    mean = window_mean(case, 0.3, 0.5)            # the writes at 0.25-0.30 s
    assert mean["writes_averaged"] == 6
    assert mean["inlet_meniscus_distance_over_a"] == pytest.approx(5.0)
    assert mean["flooded_width_over_a"] == pytest.approx(12.275)
    assert mean["jitter"]["inlet_meniscus_distance_over_a"] == pytest.approx(0.5)
    assert mean["time_s"] == pytest.approx(0.3)
    assert window_mean(case, 0.005, 0.5) is None      # before the first write
    last = last_transit(case)                         # the writes at 0.5-0.6 s
    assert last["writes_averaged"] == 11 and last["time_s"] == pytest.approx(0.6)
    assert last == window_mean(case, None, 1.0)
    assert last["flooded_width_over_a"] == pytest.approx(12.55)
    assert last["states"] == ["I"]
    inlet = window_mean(case, 0.3, 0.5, keys=("inlet_meniscus_distance_over_a",))
    assert set(inlet) - {"time_s", "state", "states", "writes_averaged", "jitter"} == {
        "inlet_meniscus_distance_over_a"}
    assert inlet["jitter"] == {"inlet_meniscus_distance_over_a": pytest.approx(0.5)}


def _relaxing(t: np.ndarray, start: float, rest: float = 15.07, tau: float = 0.23) -> np.ndarray:
    """A metric relaxing from ``start`` at t[0] to ``rest`` with time constant ``tau``."""
    return rest + (start - rest) * np.exp(-(t - t[0]) / tau)


def test_runs_from_both_sides_give_the_rest_they_relax_to():
    above, below = np.arange(1, 16) * 0.012, np.arange(1, 17) * 0.012
    runs = [(above, _relaxing(above, 15.45)), (below, _relaxing(below, 14.86))]
    r = rest_value(runs)
    assert r["rest"] == pytest.approx(15.07, abs=1e-6)
    assert r["tau"] == pytest.approx(0.23, rel=1e-4)
    assert r["rms"] < 1e-8
    low, high = r["bracket"]
    assert low == pytest.approx(runs[1][1][-1]) and high == pytest.approx(runs[0][1][-1])
    assert low < 15.07 < high
    assert r["runs"][0]["rate"] < 0 < r["runs"][1]["rate"]
    # a write-to-write jitter of 0.003 a still reads the rest within 0.02 a
    rng = np.random.default_rng(1)
    noisy = rest_value([(t, f + rng.normal(0.0, 0.003, t.size)) for t, f in runs])
    assert noisy["rest"] == pytest.approx(15.07, abs=0.02)
    assert 0 < noisy["rest_sd"] < 0.05
    assert noisy["consistent"] is True                # each run alone finds the same rest
    for run in noisy["runs"]:
        assert abs(run["alone"]["rest"] - 15.07) < 3 * run["alone"]["rest_sd"]


def test_runs_relaxing_to_different_rests_are_not_one_relaxation():
    # from above to 15.07 in 0.23 transits, from below to 14.88 in 0.05 (it stalls early):
    # the joint fit still returns a value between the two and fits them within 1.5 times the
    # jitter, but the runs' own fits say it is not one rest
    rng = np.random.default_rng(2)
    above, below = np.arange(1, 20) * 0.012, np.arange(1, 14) * 0.012
    runs = [(above, _relaxing(above, 15.45) + rng.normal(0.0, 0.003, above.size)),
            (below, _relaxing(below, 14.86, rest=14.88, tau=0.05)
             + rng.normal(0.0, 0.003, below.size))]
    r = rest_value(runs)
    assert r["consistent"] is False
    assert r["runs"][0]["alone"]["rest"] == pytest.approx(15.07, abs=0.05)
    assert r["runs"][1]["alone"]["rest"] == pytest.approx(14.88, abs=0.01)
    assert 14.88 < r["rest"] < 15.07 and r["rms"] < 0.0045


def test_a_run_still_on_a_straight_line_fixes_no_rest_of_its_own():
    # S11 from above at 0.07-0.24 transits: a steady fall, no curvature to read a rest from
    above, below = np.arange(6, 20) * 0.012, np.arange(2, 10) * 0.012
    runs = [(above, 15.42 - 1.8 * (above - above[0])),
            (below, _relaxing(below, 14.86, rest=14.88, tau=0.03))]
    r = rest_value(runs)
    assert r["runs"][0]["alone"]["fixed"] is False
    assert r["runs"][1]["alone"]["fixed"] is True
    assert r["runs"][1]["alone"]["rest"] == pytest.approx(14.88, abs=1e-4)
    assert r["consistent"] is None                    # one own rest: nothing to compare


def test_one_run_that_got_there_gives_its_rest_and_no_bracket():
    t = np.arange(5, 92) * 0.012
    r = rest_value([(t, _relaxing(t, 15.3, rest=14.87, tau=0.2))])
    assert r["rest"] == pytest.approx(14.87, abs=1e-6)
    assert r["bracket"] is None
    assert r["consistent"] is None and r["runs"][0]["alone"] is None   # nothing to compare


def test_too_few_writes_are_refused():
    t = np.array([0.1, 0.2])
    with pytest.raises(ValueError, match="at least two writes"):
        rest_value([(t, t), (t[:1], t[:1])])
    with pytest.raises(ValueError, match="4 in all"):
        rest_value([(t, t)])
