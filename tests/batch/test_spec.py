"""The batch spec: validation messages, ranges, ids and the expanded plan (no OpenFOAM)."""

from __future__ import annotations

from pathlib import Path

import pytest

from ehlfoam.errors import SpecError
from ehlfoam.batch.plan import expand, load_plan
from ehlfoam.batch.spec import parse_batch_spec

ROOT = Path(__file__).resolve().parents[2]


def _plan(data: dict):
    return expand(parse_batch_spec(data))


@pytest.mark.parametrize("data, expected", [
    ({"sweep": {"contact": {"speed": [0.005], "sped": [1]}}},
     ["sweep: contact.sped: unknown key", "valid here: ", "speed"]),
    ({"sweep": {"speeds": [0.005]}}, ["sweep: speeds: unknown key", "contact, supply"]),
    ({"sweeps": {"contact.speed": [0.005]}}, ["sweeps: unknown key", "sweep, ramp"]),
    ({"sweep": {"contact.speed": []}}, ["sweep.contact.speed = []: empty sweep"]),
    ({"sweep": {"contact": {"speed": []}}}, ["sweep.contact.speed = []: empty sweep"]),
    ({"sweep": {"contact.speed": [0.005], "contact": {"speed": [0.008]}}},
     ["contact.speed is given twice"]),
    ({"sweep": {}}, ["empty sweep (sweep[0] has no values)"]),
    ({"sweep": {"name": ["a", "b"]}}, ["the case name is the case id"]),
    ({}, ["the batch has no cases"]),
    ({"sweep": {"contact.speed": {"start": 0.005, "stop": 0.025, "num": 0}}}, ["empty sweep"]),
    ({"sweep": {"contact.speed": [-0.005, 0.008]}},
     ["sweep: contact.speed = -0.005", "valid range 0 < contact.speed <= 100"]),
    ({"sweep": [{"contact.speed": [0.005]}, {"contact.load": [0.0]}]},
     ["sweep[1]: contact.load = 0.0", "valid range 0 < contact.load"]),
    ({"ramp": [{"name": "A"}]}, ["ramp[0].contact.speed: missing: a ramp needs its speeds"]),
    ({"base": {"mesh": {"follow": {}}}, "sweep": {"contact.speed": [0.005]}},
     ["case u05.0_flooded", "has mesh.follow but no state to start from", "or set run.start = \"thin-film\""]),
    ({"base": {"mesh": {"follow": {}}}, "ramp": [{"name": "A", "contact.speed": [0.005, 0.008]}]},
     ["case rampA_up01_u05.0", "has mesh.follow but no state to start from"]),
    ({"ramp": [{"name": "A", "contact.speed": []}]}, ["a ramp without speeds"]),
    ({"ramp": [{"name": "A", "contact.speed": [0.008, 0.005]}]}, ["strictly increasing"]),
    ({"ramp": [{"name": "A", "contact.speed": [0.008]}]},
     ["ramp[0]", "a ramp needs at least two speeds", "or a start_from"]),
    ({"ramp": [{"name": "A", "contact": {"speed": [0.005, 0.008], "temperature": 99}}]},
     ["ramp 'A': contact: temperature = 99 C", "valid range 25 to 60 C"]),
    ({"ramp": [{"name": "A", "contact.speed": [0.005, 0.008]},
               {"name": "A", "contact.speed": [0.005, 0.008]}]},
     ["ramp name = 'A' is used twice"]),
    ({"sweep": {"contact.temperature": [99]}},
     ["sweep: contact: temperature = 99 C", "valid range 25 to 60 C"]),
    ({"sweep": {"supply": [{"mode": "dry"}]}}, ["sweep.supply[0]: supply.mode = 'dry'",
                                                "'flooded'"]),
    ({"sweep": {"supply": [{"disc_layer": -1e-6}]}},
     ["sweep.supply[0]: supply.disc_layer = -1e-06", "valid range 0 <= "]),
    ({"sweep": {"mesh.resolution": ["ultra"]}}, ["mesh.resolution = 'ultra'", "'coarse'"]),
    ({"base": {"mesh": {"levels": 3}}, "sweep": {"contact.speed": [0.005]}},
     ["base: invalid case spec: mesh.levels: unknown key"]),
    ({"sweep": {"contact.speed": {"start": 0.005, "stop": 0.025}}},
     ["a range needs start, stop"]),
    ({"sweep": {"speed_mm_s": [5, 8]}},
     ["speed_mm_s = [5, 8]: the batch spec takes the case spec's keys in SI: give "
      "contact.speed in m/s"]),
    ({"sweep": {"supply": [1, "flooded"]}}, ["supply = [1, 'flooded']: supply takes supply "
                                             "tables"]),
    ({"ramp": [{"name": "A", "speed_mm_s": [5, 8]}]}, ["give contact.speed in m/s"]),
])
def test_bad_specs_name_key_value_and_range(data, expected):
    with pytest.raises(SpecError) as err:
        _plan(data)
    for text in expected:
        assert text in str(err.value), str(err.value)


def test_ranges_lists_and_scalars():
    plan = _plan({"sweep": {"contact": {
        "speed": {"start": 0.005, "stop": 0.025, "step": 0.005},
        "load": {"start": 5, "stop": 20, "num": 3, "spacing": "log"}, "temperature": 40}}})
    speeds = sorted({pc.params["contact.speed"] for pc in plan})
    loads = sorted({pc.params["contact.load"] for pc in plan})
    assert speeds == [0.005, 0.01, 0.015, 0.02, 0.025]
    assert loads == pytest.approx([5, 10, 20])
    assert len(plan) == 15 and {pc.params["contact.temperature"] for pc in plan} == {40.0}
    assert [pc.id for pc in plan[:2]] == ["u05.0_flooded_T40_F5_medium",
                                          "u05.0_flooded_T40_F10_medium"]


def test_ids_params_and_si_specs():
    plan = _plan({"base": {"mesh": {"resolution": "coarse"}},
                  "sweep": {"contact.speed": [0.008, 0.00825],
                            "supply": [{"disc_layer": 2e-6, "ball_layer": 2e-6},
                                       {"mode": "flooded"},
                                       {"disc_layer": 1e-6, "ball_layer": 3e-6},
                                       {"mode": "submerged"}]}})
    ids = [pc.id for pc in plan]
    assert ids[:4] == ["u08.0_s2um_T40_F20_coarse", "u08.0_flooded_T40_F20_coarse",
                       "u08.0_s1+3um_T40_F20_coarse", "u08.0_submerged_T40_F20_coarse"]
    assert "u08.25_s2um_T40_F20_coarse" in ids and len(set(ids)) == len(ids) == 8
    pc = plan[0]
    assert pc.params == {"contact.speed": 0.008, "contact.temperature": 40.0,
                         "contact.load": 20.0, "supply.mode": "layers",
                         "supply.disc_layer": 2e-6, "supply.ball_layer": 2e-6,
                         "mesh.resolution": "coarse", "scene": "interface", "rung": "coarse"}
    assert pc.spec.speed == 0.008 and pc.spec.supply.mode == "layers"    # layers: mode layers
    assert pc.spec.supply.disc_layer == 2e-6
    assert pc.spec.name == pc.id and pc.ramp is None
    flooded = plan[1]
    assert flooded.spec.supply.mode == "flooded" and flooded.params["supply.disc_layer"] is None
    assert plan[3].spec.supply.mode == "submerged" and plan[3].spec.fills_domain
    assert pc.to_json() == {"id": pc.id, "params": pc.params, "ramp": None}


def test_supply_tables_keep_the_base_supply_keys():
    plan = _plan({"base": {"supply": {"mode": "layers", "track_half_width": 2e-4}},
                  "sweep": {"supply": [{"disc_layer": 1e-6, "ball_layer": 1e-6}]}})
    assert plan[0].spec.supply.track_half_width == 2e-4 and plan[0].id.startswith("u08.0_s1um")


def test_any_case_spec_key_can_be_swept_and_names_its_cases():
    plan = _plan({"base": {"mesh": {"resolution": "coarse"}},
                  "sweep": {"contact.speed": [0.008],
                            "physics": {"contact_angle": [15.0, 43.0]}}})
    assert [pc.id for pc in plan] == ["u08.0_flooded_T40_F20_coarse_contact_angle15",
                                      "u08.0_flooded_T40_F20_coarse_contact_angle43"]
    assert [pc.spec.physics.contact_angle for pc in plan] == [15.0, 43.0]
    assert plan[1].params["physics.contact_angle"] == 43.0
    with pytest.raises(SpecError, match="physics.contact_angle = 200.0"):
        _plan({"sweep": {"physics.contact_angle": [200.0]}})


def test_sweeps_union_and_unswept_values_from_the_base():
    plan = _plan({"base": {"contact": {"temperature": 25.0, "speed": 0.012}},
                  "sweep": [{"contact.speed": [0.008, 0.012]},
                            {"contact": {"speed": [0.012], "load": [30]}},
                            {"contact.speed": [0.008]}]})
    # the case spec's default supply is flooded, its default level medium
    assert [pc.id for pc in plan] == ["u08.0_flooded_T25_F20_medium",
                                      "u12.0_flooded_T25_F20_medium",
                                      "u12.0_flooded_T25_F30_medium"]


def test_ramp_steps_up_then_down():
    plan = _plan({"base": {"mesh": {"resolution": "coarse"}},
                  "ramp": [{"name": "A", "contact.speed": [0.005, 0.008, 0.012],
                            "supply": {"disc_layer": 1.5e-6, "ball_layer": 1.5e-6}},
                           {"name": "B", "contact": {"speed": [0.005, 0.008]},
                            "branches": "down-up"}]})
    a = [pc for pc in plan if pc.ramp["name"] == "A"]
    assert [pc.id for pc in a] == [
        "rampA_up01_u05.0_s1.5um_T40_F20_coarse", "rampA_up02_u08.0_s1.5um_T40_F20_coarse",
        "rampA_up03_u12.0_s1.5um_T40_F20_coarse", "rampA_down04_u08.0_s1.5um_T40_F20_coarse",
        "rampA_down05_u05.0_s1.5um_T40_F20_coarse"]
    assert a[0].ramp == {"name": "A", "step": 1, "direction": "up", "previous": None}
    assert all(pc.ramp["previous"] == prev.id for prev, pc in zip(a, a[1:]))
    b = [pc for pc in plan if pc.ramp["name"] == "B"]
    assert [(pc.params["contact.speed"], pc.ramp["direction"]) for pc in b] == [
        (0.008, "down"), (0.005, "down"), (0.008, "up")]


@pytest.mark.parametrize("name, n_cases", [("default", 21), ("regime", 34)])
def test_shipped_batch_specs_expand(name, n_cases):
    batch, plan = load_plan(ROOT / "examples" / "batches" / f"{name}.toml")
    assert batch.name == name and len(plan) == n_cases
    at_ref = [pc for pc in plan
              if pc.params["contact.temperature"] == 40 and pc.params["contact.load"] == 20]
    assert len(at_ref) >= 5
    if name == "default":      # the thin-film map at medium, its 3D checks on the coarse mesh
        assert {pc.spec.rung for pc in plan} == {"thin-film-medium"}
        assert {pc.params["contact.speed"] for pc in plan} >= {0.008, 0.017}
        assert all(pc.ramp is None for pc in plan)
        assert (batch.confirm.rung, batch.confirm.scene) == ("coarse", "gas-release")
    else:
        assert all(pc.spec.mesh.resolution == "coarse" for pc in plan)
        sweep = [pc for pc in at_ref if pc.ramp is None]
        assert len({pc.params["contact.speed"] for pc in sweep}) >= 5
        assert len({pc.params["supply.disc_layer"] for pc in sweep}) >= 3
        directions = {pc.ramp["direction"] for pc in plan if pc.ramp}
        assert directions == {"up", "down"}


def test_shipped_batch_specs_keep_their_case_ids():
    """The case ids name the cases' folders: the batch spec's keys in SI give the ids the
    display-unit keys gave."""
    _, plan = load_plan(ROOT / "examples" / "batches" / "default.toml")
    ids = [pc.id for pc in plan]
    assert ids[:2] == ["u05.0_s0.45um_T40_F20_tf-medium", "u05.0_s1um_T40_F20_tf-medium"]
    assert len(ids) == 21 and ids[-1] == "u60.0_s2um_T40_F20_tf-medium"
    _, plan = load_plan(ROOT / "examples" / "batches" / "breakthrough_release_low.toml")
    assert [pc.id for pc in plan] == [f"rampR_up0{k}_u{u}_s8um_T40_F20_coarse"
                                      for k, u in enumerate(("05.0", "06.5", "08.0", "09.5"),
                                                            start=1)]
    _, plan = load_plan(ROOT / "examples" / "batches" / "regime.toml")
    assert plan[3].id == "u08.0_s1um_T40_F20_coarse" and plan[25].id == \
        "rampA_up01_u05.0_s1.5um_T40_F20_coarse"


@pytest.mark.parametrize("path", sorted((Path(__file__).resolve().parents[2] / "examples")
                                        .glob("*/*.toml")), ids=lambda p: p.name)
def test_tracked_specs_are_valid(path):
    """Every spec under examples/ that the docs tell users to run is a valid case spec, or a batch
    spec that expands into valid case specs: a renamed or retired key fails here, not in a
    user's hands."""
    from ehlfoam._io import read_toml
    from ehlfoam.spec.case import load_case_spec

    data = read_toml(path)
    if {"sweep", "ramp", "base"} & set(data):
        assert expand(parse_batch_spec(data, str(path)))
    else:
        assert load_case_spec(path).name


def test_a_batch_sweeps_the_rung_thin_film_beside_3d():
    """One point on two rungs (the thin-film scene and a 3D level) in one batch: distinct ids,
    the scene in the params, and the regime analysis keeps their lines apart."""
    from ehlfoam.batch.regime import analyse

    plan = _plan({"base": {"mesh": {"resolution": "medium"}},
                  "sweep": [{"contact.speed": [0.008, 0.017], "scene": ["thin-film"]},
                            {"contact.speed": [0.008, 0.017], "scene": ["interface"]}]})
    ids = [pc.id for pc in plan]
    assert ids == ["u08.0_flooded_T40_F20_tf-medium", "u17.0_flooded_T40_F20_tf-medium",
                   "u08.0_flooded_T40_F20_medium", "u17.0_flooded_T40_F20_medium"], ids
    assert [pc.params["scene"] for pc in plan] == ["thin-film"] * 2 + ["interface"] * 2
    rows = [{**pc.params, "case_id": pc.id, "status": "finished",
             "state": "I" if pc.params["scene"] == "interface" or k == 0 else "II"}
            for k, pc in enumerate(plan)]
    lines = analyse(rows)["lines"]
    assert sorted(ln["rung"] for ln in lines) == ["medium", "thin-film-medium"]
    by = {ln["rung"]: ln for ln in lines}
    assert by["thin-film-medium"]["transition_m_s"] is not None
    assert by["medium"]["transition_m_s"] is None


def test_a_log_ranges_ids_keep_four_significant_digits():
    plan = _plan({"sweep": {"contact.speed": {"start": 0.002, "stop": 0.1, "num": 12,
                                              "spacing": "log"}}})
    ids = [pc.id.split("_")[0] for pc in plan]
    assert ids[:3] == ["u02.0", "u02.854", "u04.073"] and ids[-1] == "u100.0", ids
    assert plan[1].params["contact.speed"] == pytest.approx(0.0028541829945)   # the value
    assert len(set(ids)) == 12
