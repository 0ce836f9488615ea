"""The batch spec: validation messages, ranges, ids and the expanded plan (no OpenFOAM)."""

from __future__ import annotations

from pathlib import Path

import pytest

from ehlfoam.errors import SpecError
from ehlfoam.batch.spec import expand, load_plan, parse_batch_spec

ROOT = Path(__file__).resolve().parents[2]


def _plan(data: dict):
    return expand(parse_batch_spec(data))


@pytest.mark.parametrize("data, expected", [
    ({"sweep": {"speed_mm_s": [5], "sped": [1]}},
     ["sweep.sped: unknown key", "valid here: speed_mm_s, temperature_C"]),
    ({"sweeps": {"speed_mm_s": [5]}}, ["sweeps: unknown key", "sweep, ramp"]),
    ({"sweep": {"speed_mm_s": []}}, ["sweep.speed_mm_s = []: empty sweep"]),
    ({"sweep": {}}, ["empty sweep (sweep[0] has no values)"]),
    ({}, ["the batch has no cases"]),
    ({"sweep": {"speed_mm_s": {"start": 5, "stop": 25, "num": 0}}}, ["empty sweep"]),
    ({"sweep": {"speed_mm_s": [-5, 8]}},
     ["sweep.speed_mm_s = -5 mm/s", "contact.speed = -0.005",
      "valid range 0 < contact.speed <= 100"]),
    ({"ramp": [{"name": "A"}]}, ["ramp[0].speed_mm_s: missing: a ramp needs its speeds"]),
    ({"base": {"mesh": {"follow": {}}}, "sweep": {"speed_mm_s": [5]}},
     ["case u05.0_flooded", "has mesh.follow but no state to start from", "only a ramp's steps"]),
    ({"base": {"mesh": {"follow": {}}}, "ramp": [{"name": "A", "speed_mm_s": [5, 8]}]},
     ["case rampA_up01_u05.0", "has mesh.follow but no state to start from"]),
    ({"ramp": [{"name": "A", "speed_mm_s": []}]}, ["a ramp without speeds"]),
    ({"ramp": [{"name": "A", "speed_mm_s": [8, 5]}]}, ["strictly increasing"]),
    ({"ramp": [{"name": "A", "speed_mm_s": [5, 8]}, {"name": "A", "speed_mm_s": [5, 8]}]},
     ["ramp name = 'A' is used twice"]),
    ({"sweep": {"temperature_C": [99]}},
     ["sweep.temperature_C = 99 C", "valid range 25 to 60 C"]),
    ({"sweep": {"supply": ["dry"]}}, ["supply item 'dry'", "flooded"]),
    ({"sweep": {"supply": [-1]}}, ["supply.disc_layer = -1e-06", "valid range 0 <= "]),
    ({"sweep": {"resolution": ["ultra"]}}, ["mesh.resolution = 'ultra'", "'coarse'"]),
    ({"base": {"mesh": {"levels": 3}}, "sweep": {"speed_mm_s": [5]}},
     ["base: invalid case spec: mesh.levels: unknown key"]),
    ({"sweep": {"speed_mm_s": {"start": 5, "stop": 25}}}, ["a range needs start, stop"]),
])
def test_bad_specs_name_key_value_and_range(data, expected):
    with pytest.raises(SpecError) as err:
        _plan(data)
    for text in expected:
        assert text in str(err.value), str(err.value)


def test_ranges_lists_and_scalars():
    plan = _plan({"sweep": {"speed_mm_s": {"start": 5, "stop": 25, "step": 5},
                            "load_N": {"start": 5, "stop": 20, "num": 3, "spacing": "log"},
                            "temperature_C": 40}})
    speeds = sorted({pc.params["speed_mm_s"] for pc in plan})
    loads = sorted({pc.params["load_N"] for pc in plan})
    assert speeds == [5, 10, 15, 20, 25]
    assert loads == pytest.approx([5, 10, 20])
    assert len(plan) == 15 and {pc.params["temperature_C"] for pc in plan} == {40.0}


def test_ids_params_and_si_specs():
    plan = _plan({"base": {"mesh": {"resolution": "coarse"}},
                  "sweep": {"speed_mm_s": [8, 8.25], "supply": [2, "flooded",
                                                                {"disc_um": 1, "ball_um": 3},
                                                                "submerged"]}})
    ids = [pc.id for pc in plan]
    assert ids[:4] == ["u08.0_s2um_T40_F20_coarse", "u08.0_flooded_T40_F20_coarse",
                       "u08.0_s1+3um_T40_F20_coarse", "u08.0_submerged_T40_F20_coarse"]
    assert "u08.25_s2um_T40_F20_coarse" in ids and len(set(ids)) == len(ids) == 8
    pc = plan[0]
    assert pc.params == {"speed_mm_s": 8.0, "temperature_C": 40.0, "load_N": 20.0,
                         "supply": "layers", "disc_layer_um": 2.0, "ball_layer_um": 2.0,
                         "resolution": "coarse"}
    assert pc.spec.speed == pytest.approx(0.008)
    assert pc.spec.supply.disc_layer == pytest.approx(2e-6)
    assert pc.spec.name == pc.id and pc.ramp is None
    flooded = plan[1]
    assert flooded.spec.supply.mode == "flooded" and flooded.params["disc_layer_um"] is None
    assert plan[3].spec.supply.mode == "submerged" and plan[3].spec.fills_domain
    assert pc.to_json() == {"id": pc.id, "params": pc.params, "ramp": None}


def test_sweeps_union_and_unswept_values_from_the_base():
    plan = _plan({"base": {"contact": {"temperature": 25.0, "speed": 0.012}},
                  "sweep": [{"speed_mm_s": [8, 12]}, {"speed_mm_s": [12], "load_N": [30]},
                            {"speed_mm_s": [8]}]})
    # the case spec's default supply is flooded, its default level medium
    assert [pc.id for pc in plan] == ["u08.0_flooded_T25_F20_medium",
                                      "u12.0_flooded_T25_F20_medium",
                                      "u12.0_flooded_T25_F30_medium"]


def test_ramp_steps_up_then_down():
    plan = _plan({"base": {"mesh": {"resolution": "coarse"}},
                  "ramp": [{"name": "A", "speed_mm_s": [5, 8, 12], "supply": 1.5},
                           {"name": "B", "speed_mm_s": [5, 8], "branches": "down-up"}]})
    a = [pc for pc in plan if pc.ramp["name"] == "A"]
    assert [pc.id for pc in a] == [
        "rampA_up01_u05.0_s1.5um_T40_F20_coarse", "rampA_up02_u08.0_s1.5um_T40_F20_coarse",
        "rampA_up03_u12.0_s1.5um_T40_F20_coarse", "rampA_down04_u08.0_s1.5um_T40_F20_coarse",
        "rampA_down05_u05.0_s1.5um_T40_F20_coarse"]
    assert a[0].ramp == {"name": "A", "step": 1, "direction": "up", "previous": None}
    assert all(pc.ramp["previous"] == prev.id for prev, pc in zip(a, a[1:]))
    b = [pc for pc in plan if pc.ramp["name"] == "B"]
    assert [(pc.params["speed_mm_s"], pc.ramp["direction"]) for pc in b] == [
        (8.0, "down"), (5.0, "down"), (8.0, "up")]


@pytest.mark.parametrize("name, n_cases", [("default", 5), ("regime", 34)])
def test_shipped_batch_specs_expand(name, n_cases):
    batch, plan = load_plan(ROOT / "examples" / "batches" / f"{name}.toml")
    assert batch.name == name and len(plan) == n_cases
    at_ref = [pc for pc in plan if pc.params["temperature_C"] == 40 and pc.params["load_N"] == 20]
    assert len(at_ref) >= 5 and all(pc.spec.mesh.resolution == "coarse" for pc in plan)
    if name == "default":
        assert {pc.params["speed_mm_s"] for pc in plan} >= {8.0, 17.0}
        assert all(pc.ramp is None for pc in plan)
    else:
        sweep = [pc for pc in at_ref if pc.ramp is None]
        assert len({pc.params["speed_mm_s"] for pc in sweep}) >= 5
        assert len({pc.params["disc_layer_um"] for pc in sweep}) >= 3
        directions = {pc.ramp["direction"] for pc in plan if pc.ramp}
        assert directions == {"up", "down"}


@pytest.mark.parametrize("path", sorted((Path(__file__).resolve().parents[2] / "examples")
                                        .glob("*/*.toml")), ids=lambda p: p.name)
def test_tracked_specs_are_valid(path):
    """Every spec under runs/ that the docs tell users to run is a valid case spec, or a batch
    spec that expands into valid case specs: a renamed or retired key fails here, not in a
    user's hands."""
    from ehlfoam._io import read_toml
    from ehlfoam.spec.case import load_case_spec

    data = read_toml(path)
    if {"sweep", "ramp", "base"} & set(data):
        assert expand(parse_batch_spec(data, str(path)))
    else:
        assert load_case_spec(path).name
