"""Regime analysis on synthetic results rows with known answers (SI: speeds in m/s)."""

from __future__ import annotations

import json

import pytest

from ehlfoam.batch.regime import analyse, hysteresis, transition, write_regime

MM = 1e-3   # a speed in mm/s, in m/s


def row(u, state, supply=2.0, T=40.0, status="finished", ramp=None, step=None, direction=None):
    """A results.csv row (strings) at ``u`` mm/s with ``supply`` um layers."""
    return {"case_id": f"u{u}_{supply}_{T}_{ramp}{step}", "contact.speed": str(u * MM),
            "contact.temperature": str(T), "contact.load": "20.0", "supply.mode": "layers",
            "supply.disc_layer": str(supply * 1e-6), "supply.ball_layer": str(supply * 1e-6),
            "mesh.resolution": "coarse",
            "ramp": ramp or "", "ramp_step": "" if step is None else str(step),
            "ramp_direction": direction or "", "status": status,
            "state": state if status == "finished" else ""}


def test_transition_midpoint_and_half_gap():
    t = transition([0.005, 0.008, 0.012, 0.017, 0.025], ["I", "I", "I", "II", "II"])
    assert t["transition_m_s"] == pytest.approx(0.0145)
    assert t["uncertainty_m_s"] == pytest.approx(0.0025)
    assert t["bracket_m_s"] == [0.012, 0.017] and t["monotonic"] and t["bound"] is None
    assert t["switches"] == [{"from": "I", "to": "II", "between_m_s": [0.012, 0.017]}]


def test_transition_bounds_and_failed_points():
    assert transition([0.005, 0.008], ["I", "I"])["bound"] == "above"
    assert transition([0.005, 0.008], ["II", "II"])["bound"] == "below"
    t = transition([0.005, 0.008, 0.012], ["I", "failed", "II"])   # a failed case widens it
    assert t["transition_m_s"] == pytest.approx(0.0085)
    assert t["uncertainty_m_s"] == pytest.approx(0.0035)
    assert transition([], [])["note"] == "no finished case"


def test_non_monotonic_is_reported():
    t = transition([0.005, 0.008, 0.012, 0.017, 0.025], ["I", "II", "I", "II", "II"])
    assert not t["monotonic"]
    assert t["transition_m_s"] == pytest.approx(0.0145)
    assert len(t["switches"]) == 3
    inverse = transition([0.005, 0.008], ["II", "I"])
    assert inverse["transition_m_s"] is None and "no transition" in inverse["note"]


def test_lines_grouped_by_supply_and_temperature():
    rows = [row(u, s, supply=sup) for sup, states in ((1.0, "I II II II II"),
                                                      (2.0, "I I I II II"),
                                                      (4.0, "I I I I I"))
            for u, s in zip((5, 8, 12, 17, 25), states.split())]
    rows += [row(u, s, supply=2.0, T=60.0) for u, s in zip((5, 8, 12), ("I", "II", "II"))]
    rows += [{**row(8, "I"), "supply.mode": "flooded", "supply.disc_layer": "",
              "supply.ball_layer": ""}]
    res = analyse(rows)
    by = {(ln["supply"], ln["contact.temperature"]): ln for ln in res["lines"]}
    assert by[("1um", 40.0)]["transition_m_s"] == pytest.approx(0.0065)
    assert by[("2um", 40.0)]["transition_m_s"] == pytest.approx(0.0145)
    assert by[("4um", 40.0)]["bound"] == "above"
    assert by[("2um", 60.0)]["transition_m_s"] == pytest.approx(0.0065)
    assert [ln["supply"] for ln in res["lines"] if ln["contact.temperature"] == 40.0] == \
        ["1um", "2um", "4um", "flooded"]
    assert by[("2um", 40.0)]["contact.speed"] == pytest.approx([0.005, 0.008, 0.012, 0.017,
                                                                 0.025])


def ramp_rows(up_states, down_states, speeds=(5, 8, 12, 17, 25)):
    rows = [row(u, s, ramp="A", step=k + 1, direction="up")
            for k, (u, s) in enumerate(zip(speeds, up_states))]
    down_speeds = list(reversed(speeds))[1:]
    rows += [row(u, s, ramp="A", step=len(speeds) + k + 1, direction="down")
             for k, (u, s) in enumerate(zip(down_speeds, down_states))]
    return rows


def test_ramp_hysteresis_width_and_uncertainty():
    # up: I until 12, II from 17 -> 14.5 +- 2.5; down (from 25 in II): II down to 12, I at 8
    # -> 10 +- 2; width 4.5 +- 4.5; 12 mm/s is I going up and II coming down
    res = analyse(ramp_rows("I I I II II".split(), "II II I I".split()))
    rp = res["ramps"][0]
    assert rp["up"]["transition_m_s"] == pytest.approx(0.0145)
    assert rp["up"]["uncertainty_m_s"] == pytest.approx(0.0025)
    assert rp["down"]["transition_m_s"] == pytest.approx(0.010)
    assert rp["down"]["uncertainty_m_s"] == pytest.approx(0.002)
    assert rp["down"]["contact.speed"][0] == 0.025     # the branch starts at the turning point
    h = rp["hysteresis"]
    assert h["observed"] and h["speeds_differing_m_s"] == [0.012]
    assert h["width_m_s"] == pytest.approx(0.0045)
    assert h["uncertainty_m_s"] == pytest.approx(0.0045)
    assert h["width_bounds_m_s"] == pytest.approx([0.0, 0.009])


def test_ramp_without_hysteresis_and_without_transition():
    same = analyse(ramp_rows("I I I II II".split(), "II I I I".split()))["ramps"][0]
    assert same["hysteresis"]["width_m_s"] == 0.0 and not same["hysteresis"]["observed"]
    assert "no hysteresis resolved" in same["hysteresis"]["note"]
    never = analyse(ramp_rows("I I I I I".split(), "I I I I".split()))["ramps"][0]
    assert never["hysteresis"]["width_m_s"] is None
    assert "width not determined" in never["hysteresis"]["note"]


def test_one_way_ramp_has_one_branch():
    rp = analyse(ramp_rows("I I II".split(), [], speeds=(8, 14, 20)))["ramps"][0]
    assert rp["down"] is None and "hysteresis" not in rp
    assert rp["up"]["transition_m_s"] == pytest.approx(0.017)
    assert rp["up"]["uncertainty_m_s"] == pytest.approx(0.003)


def test_hysteresis_function_directly():
    up = transition([0.005, 0.008, 0.012], ["I", "I", "II"])
    down = transition([0.012, 0.008, 0.005], ["II", "I", "I"])
    h = hysteresis({**up, "contact.speed": [0.005, 0.008, 0.012], "states": ["I", "I", "II"]},
                   {**down, "contact.speed": [0.012, 0.008, 0.005],
                    "states": ["II", "I", "I"]})
    assert h["width_m_s"] == 0.0 and h["uncertainty_m_s"] == pytest.approx(0.004)


def test_write_regime_file(tmp_path):
    rows = [row(u, s, supply=sup) for sup in (1.0, 2.0)
            for u, s in zip((5, 8, 12), ("I", "I", "II"))]
    rows += [row(8, "", supply=4.0, status="failed")]
    rows += ramp_rows("I I II".split(), "II I".split(), speeds=(5, 8, 12))
    res = write_regime(tmp_path, rows)
    saved = json.loads((tmp_path / "regime" / "regime.json").read_text())
    assert saved == json.loads(json.dumps(res))
    assert saved["ramps"][0]["hysteresis"]["observed"] is True     # 8 mm/s: I up, II down
    assert res["lines"][2]["states"] == ["failed"]
    assert res["lines"][0]["transition_m_s"] == pytest.approx(0.010)
