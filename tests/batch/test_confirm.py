"""3D confirmations of a thin-film map (issue 74, point 6): the batch's ``[confirm]`` table
runs the points either side of each thin-film transition on a 3D rung, from the thin-film
states, and the regime analysis says where the rungs agree."""

from __future__ import annotations

import json

import pytest

from ehlfoam.batch.folder import CASES
from ehlfoam.batch.launch import BatchOptions, run_batch
from ehlfoam.batch.results import read_results
from ehlfoam.errors import SpecError
from ehlfoam.metrics.record import read_metrics

#: a thin-film map on the tiny contact (0.45 um layers: state I at 4 and 8 mm/s, II at 17
#: and 30 mm/s on the coarse grid) and its confirmations on the tiny 3D mesh, 1 ms each
MAP = """
name = "confirm"
[base]
contact = { grid = 129, tol_residual = 1e-4 }
supply = { mode = "layers", disc_layer = 0.45e-6, ball_layer = 0.45e-6, track_half_width = 3e-4 }
physics = { cavitation_pressure = 9e4 }
run = { transits_max = 60.0 }

[[sweep]]
rung = ["thin-film-coarse"]
contact.speed = [0.004, 0.008, 0.017, 0.03]
"""
CONFIRM = """
[confirm]
rung = "coarse"
scene = "gas-release"
set = { "run.end_time" = 1e-3, "mesh.size_rim" = 0.25, "mesh.size_far" = 1.2, \
"mesh.n_layers" = 3, "mesh.wall_grading" = 3.0, "domain.upstream" = 5.0, \
"domain.downstream" = 7.0, "domain.side" = 5.0 }
"""


@pytest.mark.openfoam
def test_the_points_either_side_of_a_thin_film_transition_are_run_in_3d(tmp_path):
    spec = tmp_path / "confirm.toml"
    spec.write_text(MAP + CONFIRM)
    opts = BatchOptions(out=tmp_path / "confirm", jobs=2, quiet=True, report=False)
    outcome = run_batch(spec, opts)
    assert outcome.exit_code == 0
    rows = {r["case_id"]: r for r in read_results(outcome.batch_dir)}
    tf = {float(r["contact.speed"]): r["state"] for r in rows.values()
          if r["rung"] == "thin-film-coarse"}
    top_i = max(u for u, s in tf.items() if s == "I")
    low_ii = min(u for u, s in tf.items() if s == "II" and u > top_i)
    confirms = [r for r in rows.values() if r["case_id"].startswith("confirm_")]
    assert sorted(float(r["contact.speed"]) for r in confirms) == [top_i, low_ii]
    for r in confirms:
        assert r["rung"] == "coarse" and r["scene"] == "gas-release"
        assert rows[r["confirms"]]["contact.speed"] == r["contact.speed"]
        case = outcome.batch_dir / CASES / r["case_id"]
        assert read_metrics(case).ramp_start_method == "thin-film"   # from its own state
    regime = json.loads((outcome.batch_dir / "regime" / "regime.json").read_text())
    conf = {c["case_id"]: c for c in regime["confirmations"]}
    assert set(conf) == {r["case_id"] for r in confirms}
    for cid, c in conf.items():
        assert c["agree"] == (rows[cid]["state"] == tf[c["contact.speed"]])
        assert c["rung"] == "thin-film-coarse" and c["supply"] == "0.45um"
    again = run_batch(spec, opts)   # a resume finds the same confirmations, all finished
    assert again.ran == [] and again.exit_code == 0


def test_a_confirm_table_without_thin_film_cases_or_with_a_bad_key_is_refused(tmp_path):
    spec = tmp_path / "bad.toml"
    spec.write_text(MAP.replace('rung = ["thin-film-coarse"]', 'rung = ["coarse"]') + CONFIRM)
    with pytest.raises(SpecError, match="confirm: the batch has no thin-film sweep case"):
        run_batch(spec, BatchOptions(out=tmp_path / "bad", quiet=True, report=False))
    spec.write_text(MAP + '[confirm]\nset = { "run.transits_max" = -1.0 }\n')
    with pytest.raises(SpecError, match="confirm: the 3D case of u04.0.*run.transits_max"):
        run_batch(spec, BatchOptions(out=tmp_path / "bad", quiet=True, report=False))
    assert not (tmp_path / "bad").exists()


def test_the_confirmations_are_the_brackets_of_the_lines_confirm_only_names(tmp_path):
    """From a finished map's rows alone (no run): two cases a line with a transition, none
    for a line in one state, only the lines ``confirm.only`` names, each from its thin-film
    case's folder."""
    from ehlfoam.batch.confirm import confirm_plan
    from ehlfoam.batch.plan import expand
    from ehlfoam.batch.spec import parse_batch_spec
    import tomllib

    data = tomllib.loads(MAP.replace("disc_layer = 0.45e-6, ball_layer = 0.45e-6, ", "")
                         + "supply = [{disc_layer = 0.45e-6, ball_layer = 0.45e-6}, "
                           "{disc_layer = 1e-6, ball_layer = 1e-6}, "
                           "{disc_layer = 2e-6, ball_layer = 2e-6}]\n" + CONFIRM)
    batch = parse_batch_spec(data, "map")
    plan = expand(batch)
    states = {0.45e-6: "I I II II", 1e-6: "I I I II", 2e-6: "I I I I"}
    speeds = [0.004, 0.008, 0.017, 0.03]
    rows = [{**pc.params, "case_id": pc.id, "status": "finished",
             "state": states[pc.params["supply.disc_layer"]].split()[
                 speeds.index(pc.params["contact.speed"])]} for pc in plan]
    got = confirm_plan(batch, plan, rows, tmp_path)
    assert [(pc.params["supply.disc_layer"], pc.params["contact.speed"]) for pc in got] == [
        (0.45e-6, 0.008), (0.45e-6, 0.017), (1e-6, 0.017), (1e-6, 0.03)]
    for pc in got:
        assert pc.id.startswith("confirm_") and pc.spec.rung == "coarse"
        assert pc.ramp["start_from"] == str(tmp_path / "cases" / pc.ramp["confirms"])
    only = parse_batch_spec({**data, "confirm": {**data["confirm"],
                                                 "only": {"supply.disc_layer": 1e-6}}}, "map")
    assert [pc.params["contact.speed"] for pc in confirm_plan(only, plan, rows, tmp_path)] == \
        [0.017, 0.03]


def test_a_3d_confirmation_that_opens_a_closed_region_says_why():
    """The 3D levels drain a state I region (their films): a confirmation in state II
    against the thin-film's I says so and points at the docs; one in I against II, or one
    that agrees, does not."""
    from ehlfoam.report.regime import DRAINS, summary_lines

    def conf(state, thin_film_state):
        return {"confirm_rung": "coarse", "rung": "thin-film-coarse", "contact.speed": 0.008,
                "supply": "0.45 um", "contact.temperature": 40.0, "contact.load": 20.0,
                "state": state, "thin_film_state": thin_film_state,
                "agree": state == thin_film_state}

    lines = summary_lines({"confirmations": [conf("II", "I"), conf("I", "II"), conf("I", "I")]})
    assert DRAINS in lines[0] and "disagrees" in lines[0]
    assert "disagrees" in lines[1] and DRAINS not in lines[1]
    assert "agrees" in lines[2] and DRAINS not in lines[2]
    assert lines[-1].startswith("3D confirmations: 1 of 3 agree")
