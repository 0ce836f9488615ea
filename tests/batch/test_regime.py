"""Regime analysis on synthetic results rows with known answers, and its figures."""

from __future__ import annotations

import json

import pytest

from ehlfoam.batch.regime import analyse, hysteresis, transition, write_regime


def _row(u, state, supply=2.0, T=40.0, status="finished", ramp=None, step=None, direction=None):
    return {"case_id": f"u{u}_{supply}_{T}_{ramp}{step}", "speed_mm_s": str(u),
            "temperature_C": str(T), "load_N": "20.0", "supply": "layers",
            "disc_layer_um": str(supply), "ball_layer_um": str(supply), "resolution": "coarse",
            "ramp": ramp or "", "ramp_step": "" if step is None else str(step),
            "ramp_direction": direction or "", "status": status,
            "state": state if status == "finished" else ""}


def test_transition_midpoint_and_half_gap():
    t = transition([5, 8, 12, 17, 25], ["I", "I", "I", "II", "II"])
    assert t["transition_mm_s"] == 14.5 and t["uncertainty_mm_s"] == 2.5
    assert t["bracket"] == [12, 17] and t["monotonic"] and t["bound"] is None
    assert t["switches"] == [{"from": "I", "to": "II", "between": [12.0, 17.0]}]


def test_transition_bounds_and_failed_points():
    assert transition([5, 8], ["I", "I"])["bound"] == "above"
    assert transition([5, 8], ["II", "II"])["bound"] == "below"
    t = transition([5, 8, 12], ["I", "failed", "II"])      # a failed case widens the gap
    assert t["transition_mm_s"] == 8.5 and t["uncertainty_mm_s"] == 3.5
    assert transition([], [])["note"] == "no finished case"


def test_non_monotonic_is_reported():
    t = transition([5, 8, 12, 17, 25], ["I", "II", "I", "II", "II"])
    assert not t["monotonic"]
    assert t["transition_mm_s"] == 14.5 and t["uncertainty_mm_s"] == 2.5
    assert "non-monotonic" in t["note"] and "8" in t["note"]
    assert len(t["switches"]) == 3
    inverse = transition([5, 8], ["II", "I"])
    assert inverse["transition_mm_s"] is None and "no transition" in inverse["note"]


def test_lines_grouped_by_supply_and_temperature():
    rows = [_row(u, s, supply=sup) for sup, states in ((1.0, "I II II II II"),
                                                       (2.0, "I I I II II"),
                                                       (4.0, "I I I I I"))
            for u, s in zip((5, 8, 12, 17, 25), states.split())]
    rows += [_row(u, s, supply=2.0, T=60.0) for u, s in zip((5, 8, 12), ("I", "II", "II"))]
    res = analyse(rows)
    by = {(ln["supply"], ln["temperature_C"]): ln for ln in res["lines"]}
    assert by[("1um", 40.0)]["transition_mm_s"] == 6.5
    assert by[("2um", 40.0)]["transition_mm_s"] == 14.5
    assert by[("4um", 40.0)]["bound"] == "above"
    assert by[("2um", 60.0)]["transition_mm_s"] == 6.5
    assert any("2um" in line and "14.5" in line for line in res["summary"])


def _ramp_rows(up_states, down_states, speeds=(5, 8, 12, 17, 25)):
    rows = [_row(u, s, ramp="A", step=k + 1, direction="up")
            for k, (u, s) in enumerate(zip(speeds, up_states))]
    down_speeds = list(reversed(speeds))[1:]
    rows += [_row(u, s, ramp="A", step=len(speeds) + k + 1, direction="down")
             for k, (u, s) in enumerate(zip(down_speeds, down_states))]
    return rows


def test_ramp_hysteresis_width_and_uncertainty():
    # up: I until 12, II from 17 -> 14.5 +- 2.5; down (from 25 in II): II down to 12, I at 8
    # -> 10 +- 2; width 4.5 +- 4.5; 12 mm/s is I going up and II coming down
    res = analyse(_ramp_rows("I I I II II".split(), "II II I I".split()))
    rp = res["ramps"][0]
    assert rp["up"]["transition_mm_s"] == 14.5 and rp["up"]["uncertainty_mm_s"] == 2.5
    assert rp["down"]["transition_mm_s"] == 10.0 and rp["down"]["uncertainty_mm_s"] == 2.0
    assert rp["down"]["speeds_mm_s"][0] == 25.0        # the branch starts at the turning point
    h = rp["hysteresis"]
    assert h["observed"] and h["speeds_differing_mm_s"] == [12.0]
    assert h["width_mm_s"] == 4.5 and h["uncertainty_mm_s"] == 4.5
    assert h["width_bounds_mm_s"] == [0.0, 9.0]
    assert "hysteresis observed" in res["summary"][-1]


def test_ramp_without_hysteresis_and_without_transition():
    same = analyse(_ramp_rows("I I I II II".split(), "II I I I".split()))["ramps"][0]
    assert same["hysteresis"]["width_mm_s"] == 0.0 and not same["hysteresis"]["observed"]
    assert "no hysteresis resolved" in same["hysteresis"]["note"]
    never = analyse(_ramp_rows("I I I I I".split(), "I I I I".split()))["ramps"][0]
    assert never["hysteresis"]["width_mm_s"] is None
    assert "width not determined" in never["hysteresis"]["note"]


def test_one_way_ramp_has_one_branch(tmp_path):
    rows = _ramp_rows("I I II".split(), [], speeds=(8, 14, 20))
    rp = analyse(rows)["ramps"][0]
    assert rp["down"] is None and "hysteresis" not in rp
    assert rp["up"]["transition_mm_s"] == 17.0 and rp["up"]["uncertainty_mm_s"] == 3.0
    summary = analyse(rows)["summary"][0]
    assert "up I -> II at 17" in summary and "down" not in summary
    write_regime(tmp_path, rows)          # draws without a down branch


def test_hysteresis_function_directly():
    up = transition([5, 8, 12], ["I", "I", "II"])
    down = transition([12, 8, 5], ["II", "I", "I"])
    h = hysteresis({**up, "speeds_mm_s": [5, 8, 12], "states": ["I", "I", "II"]},
                   {**down, "speeds_mm_s": [12, 8, 5], "states": ["II", "I", "I"]})
    assert h["width_mm_s"] == 0.0 and h["uncertainty_mm_s"] == 4.0


def test_write_regime_files(tmp_path):
    rows = [_row(u, s, supply=sup) for sup in (1.0, 2.0)
            for u, s in zip((5, 8, 12), ("I", "I", "II"))]
    rows += [_row(8, "", supply=4.0, status="failed")]
    rows += _ramp_rows("I I II".split(), "II I".split(), speeds=(5, 8, 12))
    res = write_regime(tmp_path, rows)
    saved = json.loads((tmp_path / "regime" / "regime.json").read_text())
    assert saved["figures"] == ["regime/speed_supply.png", "regime/speed_temperature.png",
                                "regime/hysteresis.png"]
    for f in saved["figures"]:
        assert (tmp_path / f).stat().st_size > 5000
    assert saved["ramps"][0]["hysteresis"]["observed"] is True     # 8 mm/s: I up, II down
    assert res["lines"][2]["states"] == ["failed"]
    assert res["lines"][0]["transition_mm_s"] == pytest.approx(10.0)
