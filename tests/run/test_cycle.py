"""A cycle of passes (supply.mode = "rig", ehlfoam.run.cycle, issue 75): `ehlfoam run` takes
the supply from the oil on the rig, pass after pass, to a periodic state, records every pass
in cycle.csv and sums it up in metrics.json; the rig's oil is kept to round-off over 100
passes; a stopped cycle goes on from its last pass; its end is told from its passes; bad
input is refused by name. OpenFOAM is never called."""

from __future__ import annotations

import csv
import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

from ehlfoam.cli.main import main
from ehlfoam.errors import SpecError
from ehlfoam.run.cycle import cycle_end
from ehlfoam.run.monitor import run_case
from ehlfoam.spec.case import make_case_spec
from ehlfoam.thinfilm.march import Marcher
from ehlfoam.tracks.rig import Rig, Tracks
from tests.run.test_thin_film import NO_FOAM, sigterm_run
from tests.tiny import THIN_FILM
from tests.tracks.test_rig import A, problem

#: the tiny thin-film contact on a small domain and 0.9 a cells, 1 um on each wall over the
#: track of a 1.3 mm disc track (a pass: 58 steps of a cell's transit), coarse reflow
RIG = {**THIN_FILM,
       "domain": {"upstream": 3.5, "downstream": 5.5, "side": 4.0},
       "supply": {**THIN_FILM["supply"], "mode": "rig", "track_radius": 1.3e-3,
                  "initial_puddle": 2.5, "disc_layer": 1e-6, "ball_layer": 1e-6},
       "thin_film": {"cell": 0.9, "courant": 1.0, "normal_length": 0.9},
       "cycle": {"passes_max": 40, "tolerance": 1e-6, "reflow_steps": 8, "refine": 1,
                 "side": 6.0}}


def _set(spec: dict) -> list[str]:
    return [item for table, values in spec.items() if isinstance(values, dict)
            for key, value in values.items()
            for item in ("--set", f"{table}.{key}={json.dumps(value)}")] + [
        "--set", 'scene="thin-film"', "--set", "name=rig"]


@pytest.fixture(autouse=True)
def no_openfoam(monkeypatch):
    for key, value in NO_FOAM.items():
        monkeypatch.setenv(key, value)


def _rows(case: Path) -> list[dict]:
    with open(case / "cycle.csv", newline="") as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> Path:
    case = tmp_path_factory.mktemp("rig") / "case"
    old = {k: os.environ.get(k) for k in NO_FOAM}
    os.environ.update(NO_FOAM)
    try:
        assert main(["case", "--out", str(case), *_set(RIG)]) == 0
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    return case


def _copy(built: Path, tmp_path: Path) -> Path:
    import shutil
    case = tmp_path / "case"
    shutil.copytree(built, case)
    return case


def test_the_cycle_settles_and_records_every_pass(built, tmp_path):
    """`ehlfoam run` makes passes until the supply and the contact's oil hold still: a row a
    pass (its supply, state, menisci, the oil in the region, the domain and on each track),
    the summary in metrics.json, the rig's oil kept to round-off, the last pass laying back
    what it took in."""
    case = _copy(built, tmp_path)
    assert main(["run", str(case), "--quiet"]) == 0
    m = json.loads((case / "metrics.json").read_text())
    rows = _rows(case)
    assert (m["status"], m["end_reason"], m["cycle_end_reason"]) == \
        ("finished", "periodic", "periodic")
    assert m["steady"] is True and m["cycle_period_passes"] == 1
    assert 3 <= m["cycle_passes"] == len(rows) < 40
    assert [int(r["pass"]) for r in rows] == list(range(1, len(rows) + 1))
    assert m["cycle_arcs"] == 1                      # r < R: one arc, a pass a disc turn
    assert m["cycle_pass_time_s"] == pytest.approx(2 * math.pi * 1.3e-3 / 0.02, rel=0.02)
    assert m["oil_rig_balance_error"] < 1e-12
    assert m["oil_rig_m3"] == pytest.approx(m["oil_disc_track_m3"] + m["oil_ball_track_m3"]
                                            + m["oil_volume_m3"], rel=1e-12)
    last = rows[-1]
    assert float(last["laid_m3"]) == pytest.approx(float(last["inlet_m3"]), rel=1e-5)
    assert float(rows[0]["inlet_m3"]) != pytest.approx(float(last["inlet_m3"]), rel=1e-3, abs=0)
    assert last["state"] in ("I", "II") and float(last["oil_region_m3"]) > 0
    assert float(last["oil_disc_track_m3"]) == pytest.approx(float(last["oil_ball_track_m3"]))
    assert (case / "tracks.npz").is_file() and (case / "state.npz").is_file()
    # the contact's film at the settled passes' inlet meniscus (the starved precalc)
    menisci = [float(r["inlet_meniscus_distance_over_a"]) for r in rows[-2:]]
    mean = min(max(sum(menisci) / 2, 0.05), 3.0)
    assert m["starved_meniscus_over_a"] == pytest.approx(mean, abs=0.026 if mean < 1 else 0.126)
    assert 0.3 < m["hc_over_hc_flooded"] <= 1.01
    assert all(0.3 < float(r["hc_over_hc_flooded"]) <= 1.01 for r in rows)   # every pass's


def test_a_stopped_cycle_goes_on_from_its_last_pass(built, tmp_path):
    """A wall limit stops the cycle after a pass (end reason wall_limit, nothing lost); run
    again, it goes on with the next pass from the tracks and the state it left, the rig's
    oil still that of the start."""
    case = _copy(built, tmp_path)
    first = run_case(case, wall_limit=1e-3)
    assert (first["end_reason"], first["cycle_passes"]) == ("wall_limit", 1)
    again = run_case(case)
    rows = _rows(case)
    assert again["end_reason"] == "periodic"
    assert [int(r["pass"]) for r in rows] == list(range(1, len(rows) + 1))
    assert again["oil_rig_initial_m3"] == pytest.approx(float(rows[0]["oil_rig_initial_m3"]),
                                                        rel=1e-15)
    assert again["oil_rig_balance_error"] < 1e-12


def test_a_cycle_started_from_a_cycle_carries_its_tracks(built, tmp_path):
    """A cycle started from a settled cycle's case (a ramp's step: `ehlfoam case
    --start-from`) takes over the oil that cycle left on the tracks as well as its contact:
    at the same speed its first pass takes in what the settled passes took, so it is periodic
    in the fewest passes; at another speed the rig's oil is the first cycle's to round-off
    (the uniform layers of the spec would hold another amount)."""
    first = _copy(built, tmp_path)
    done = run_case(first)
    settled = _rows(first)
    assert done["end_reason"] == "periodic" and len(settled) >= 4
    for speed, name in ((0.02, "same"), (0.03, "faster")):
        case = tmp_path / name
        assert main(["case", "--out", str(case), *_set(RIG), "--set",
                     f"contact.speed={speed}", "--start-from", str(first)]) == 0
        ramp = json.loads((case / "ehlfoam" / "ramp.json").read_text())
        assert ramp["fields"] == ["oil", "tracks"] and (case / "ehlfoam" /
                                                         "start_tracks.npz").is_file()
        m = run_case(case)
        rows = _rows(case)
        assert m["oil_rig_initial_m3"] == pytest.approx(done["oil_rig_m3"], rel=1e-12)
        assert m["oil_rig_balance_error"] < 1e-12
        if name == "same":
            assert float(rows[0]["inlet_m3"]) == pytest.approx(
                float(settled[-1]["inlet_m3"]), rel=1e-4)
            assert m["end_reason"] == "periodic" and len(rows) == 3
    # from the spec's uniform layers the first pass took another amount
    assert float(settled[0]["inlet_m3"]) != pytest.approx(float(settled[-1]["inlet_m3"]),
                                                          rel=1e-2, abs=0)


def test_sigterm_ends_the_cycle_interrupted_and_it_goes_on_in_step(built, tmp_path):
    """SIGTERM mid-cycle: end reason interrupted, the passes made kept; the pass cut short is
    not written, so run again the cycle goes on with the next pass and the rig's oil is
    still the start's to round-off."""
    case = _copy(built, tmp_path)
    spec = json.loads((case / "ehlfoam" / "spec.json").read_text())
    spec["cycle"] |= {"tolerance": 1e-15, "passes_max": 400}
    (case / "ehlfoam" / "spec.json").write_text(json.dumps(spec))
    cycle = spec["cycle"]

    def passes_left() -> bool:     # its passes so far do not end it: it makes another
        # the tiny rig's track lies inside the ball's: one arc (test_the_cycle_settles...)
        return cycle_end(_rows(case), 1, cycle["tolerance"], cycle["period_max"]) == (None, None)

    # even at 1e-15 the cycle ends within a second: the tiny rig repeats its passes bit for
    # bit after some 27 (limit_cycle), so the signal cannot be timed
    assert sigterm_run(case, "cycle.csv", passes_left) == 1
    m = json.loads((case / "metrics.json").read_text())
    assert (m["status"], m["end_reason"]) == ("interrupted", "interrupted")
    made = len(_rows(case))
    assert made >= 1 and m["cycle_passes"] == made
    spec["cycle"]["passes_max"] = made + 2
    (case / "ehlfoam" / "spec.json").write_text(json.dumps(spec))
    again = run_case(case)
    assert again["end_reason"] == "passes_max" and len(_rows(case)) == made + 2
    assert again["oil_rig_balance_error"] < 1e-12


def test_an_extension_does_not_apply_to_a_cycle(built, tmp_path, capsys):
    case = _copy(built, tmp_path)
    assert main(["run", str(case), "--extend", "2", "--quiet"]) == 2
    assert "does not apply to a cycle of passes" in capsys.readouterr().err


def test_the_rig_s_oil_is_kept_over_100_passes():
    """100 passes of a small region on a 1.2 mm track (four disc arcs, the ball a quarter of
    the disc's turn): the oil on the tracks and in the contact's domain is the start's to
    1e-9 (round-off: some 1e-14), while the supply moves."""
    m = Marcher(problem(supply=1e-6, cavitation_pressure=-1e4, cell=0.9 * A,
                        x_range=(-4.5 * A, 6.3 * A), y_max=4.5 * A, initial_radius=2.5 * A), courant=1.0)
    rig = Rig(track_radius=1.2e-3, ball_radius=0.3e-3, speed=m.prob.speed,
              surface_tension=0.03, viscosity=0.0216, row=m.grid.cell, rows=len(m.grid.y),
              width_rows=8, step=m.dt, reflow_steps=4, refine=1)
    tracks = Tracks.uniform(rig, 0.3e-6, 0.3e-6, 3e-4)
    start = sum(tracks.oil(rig)) + m.oil()
    supplies = []
    for _ in range(100):
        m.set_supply(tracks.inlet(rig))
        m.oil_out_rows[:] = 0.0
        side = m.oil_out_side
        for _ in range(rig.pass_steps):
            m.step()
        supplies.append(m.q_in)
        tracks.lay(rig, m.oil_out_rows, m.oil_out_side - side)
    assert rig.arcs == 4 and tracks.passes == 100
    assert abs(sum(tracks.oil(rig)) + m.oil() - start) <= 1e-9 * start
    assert max(supplies) > 1.05 * min(supplies)


def _row(took, oil, state="I"):
    return {"inlet_m3": took, "oil_domain_m3": oil, "laid_m3": took, "state": state}


def test_the_cycle_s_end_is_told_from_its_passes():
    """Still supply, oil and state over the last K + 1 passes: periodic (not while the state
    flips); a repeating pattern of
    period 2 or 3 seen three times: a limit cycle; a drift: go on."""
    steady = [_row(1.0 + 0.5 ** k, 2.0) for k in range(30)]
    assert cycle_end(steady, arcs=4, tol=1e-6, period_max=8) == ("periodic", 1)
    assert cycle_end(steady[:10], arcs=4, tol=1e-6, period_max=8) == (None, None)
    flipping = steady[:-2] + [_row(1.0, 2.0, "II"), _row(1.0, 2.0, "I")]
    assert cycle_end(flipping, arcs=4, tol=1e-6, period_max=8) == (None, None)
    two = [_row(1.0 + (k % 2), 2.0 + (k % 2), "I" if k % 2 else "II") for k in range(9)]
    assert cycle_end(two, arcs=1, tol=1e-6, period_max=8) == ("limit_cycle", 2)
    three = [_row(1.0 + (k % 3), 2.0) for k in range(9)]
    assert cycle_end(three, arcs=1, tol=1e-6, period_max=8) == ("limit_cycle", 3)
    assert cycle_end(three, arcs=1, tol=1e-6, period_max=2) == (None, None)
    drift = [_row(1.0 + 0.1 * k, 2.0) for k in range(30)]
    assert cycle_end(drift, arcs=1, tol=1e-6, period_max=8) == (None, None)


@pytest.mark.parametrize("override, words", [
    ({"supply.disc_oil": -1e-9}, "supply.disc_oil = -1e-09: Input should be greater than 0 "
                                 "(valid range 0 < supply.disc_oil <= 1e-05 m3)"),
    ({"supply.ball_oil": 0.0}, "supply.ball_oil = 0.0: Input should be greater than 0"),
    ({"supply.disc_layer": 0.0, "supply.ball_layer": 0.0}, "leave no oil on the rig"),
    ({"supply.track_radius": 1e-3}, "supply.track_radius = 0.001 m is out of range: must "
                                    "be > 0.001233 m, the contact's domain length"),
    ({"cycle.side": 2.0}, "cycle.side = 2 a is out of range: must be in [4, 1000] a"),
    ({"scene": "interface"}, 'supply.mode = "rig" needs scene = "thin-film"'),
    ({"cycle.passes_max": 0}, "cycle.passes_max = 0"),
])
def test_bad_rig_input_is_refused_by_name(override, words):
    spec = {k: v for k, v in RIG.items()}
    with pytest.raises(SpecError) as err:
        make_case_spec(spec, **override)
    assert words in str(err.value)


def test_oil_volumes_set_the_mean_layers_over_the_tracks():
    """disc_oil over 2 pi r by the track's width, ball_oil over 2 pi R by it."""
    from ehlfoam.spec.cycle import rig_layers
    spec = make_case_spec(RIG, **{"supply.disc_oil": 1e-9, "supply.ball_oil": 2e-10})
    disc, ball = rig_layers(spec)
    width = 2 * RIG["supply"]["track_half_width"]
    assert disc == pytest.approx(1e-9 / (2 * np.pi * 1.3e-3 * width))
    assert ball == pytest.approx(2e-10 / (2 * np.pi * spec.contact.radius * width))


def test_a_batch_over_rig_cases_keeps_the_rig_supply(tmp_path):
    """A sweep of the tracks' layers over a "rig" base stays "rig" (a layer alone means
    "layers" otherwise), its ids say so, and a case's CPU estimate counts its passes."""
    from ehlfoam.batch.plan import est_cpu_s, load_plan
    spec = tmp_path / "rig.toml"
    spec.write_text('name = "rigmap"\n[base]\nscene = "thin-film"\n'
                    'supply = { mode = "rig", track_radius = 0.039 }\n'
                    'cycle = { passes_max = 20 }\n[[sweep]]\ncontact.speed = [0.008, 0.017]\n'
                    'supply = [{disc_layer = 0.6e-6, ball_layer = 0.6e-6}]\n')
    _, plan = load_plan(spec)
    assert [p.spec.supply.mode for p in plan] == ["rig", "rig"]
    assert [p.id for p in plan] == ["u08.0_s0.6um-rig_T40_F20_tf-medium",
                                    "u17.0_s0.6um-rig_T40_F20_tf-medium"]
    assert plan[0].params["supply.disc_layer"] == 0.6e-6
    layers = make_case_spec(plan[0].spec.model_dump(), **{"supply.mode": "layers"})
    assert est_cpu_s(plan[0].spec) > 10 * est_cpu_s(layers)


def test_a_settled_cycle_is_confirmed_in_3d_at_the_supply_it_settled_on(built, tmp_path):
    """A rig map's 3D confirmation (ehlfoam.batch.confirm) takes in, as a "layers" supply,
    the band of oil the tracks bring the contact's rows after the cycle's last pass: the
    same oil on those rows, the rig-only keys and the cycle left behind."""
    from ehlfoam.batch.confirm import confirm_spec
    from ehlfoam.batch.spec import BatchSpec
    from ehlfoam.case.geometry import load_spec_of
    from ehlfoam.run.cycle import settled_supply
    from ehlfoam.thinfilm.state import load_state

    case = _copy(built, tmp_path)
    run_case(case)
    band = settled_supply(case)
    tracks, grid = Tracks.load(case / "tracks.npz"), load_state(case / "state.npz").grid
    rows = len(grid.y)
    inlet = tracks.disc[tracks.next_arc, :rows].sum() * grid.cell
    width = band["supply.track_half_width"] - band["supply.track_inner_half_width"]
    assert band["supply.disc_layer"] * width == pytest.approx(inlet, rel=1e-12)
    assert 0 < width <= rows * grid.cell
    batch = BatchSpec.model_validate({"base": {}, "sweep": [{"contact.speed": [0.02]}],
                                      "confirm": {"rung": "coarse"}})
    spec = confirm_spec(batch, load_spec_of(case), band)
    assert (spec.scene, spec.supply.mode) == ("gas-release", "layers")
    assert spec.supply.disc_layer == pytest.approx(band["supply.disc_layer"])
    assert spec.supply.track_half_width == pytest.approx(band["supply.track_half_width"])
    start = confirm_spec(batch, load_spec_of(case))            # before the map: the start's
    assert start.supply.disc_layer == pytest.approx(1e-6)
