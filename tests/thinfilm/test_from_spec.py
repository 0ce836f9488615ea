"""A case spec's region in the thin-film model (ehlfoam.thinfilm.from_spec): the spec read
into the model's problem, its grid refused in the units it is given in, and a march written
as a state that reads back and a summary."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ehlfoam.spec.case import make_case_spec
from ehlfoam.thinfilm.from_spec import RegionOptions, march, problem_from_spec, write_region
from ehlfoam.thinfilm.problem import landau_levich
from ehlfoam.thinfilm.state import load_state


def ball_gap(x, y):
    """A rigid ball on a flat: 1 um at the contact, R = 9.525 mm."""
    return 1e-6 + (np.asarray(x) ** 2 + np.asarray(y) ** 2) / (2 * 9.525e-3)


def test_a_case_spec_becomes_the_same_problem():
    """The spec's contact, oil, wetting and supply, and the options' grid in units of a."""
    spec = make_case_spec({"supply": {"mode": "layers", "disc_layer": 5e-6, "ball_layer": 3e-6,
                                      "track_half_width": 2e-4, "initial_puddle": 6.0},
                           "physics": {"contact_angle": 20.0}})
    a = spec.a
    options = RegionOptions(cell=0.25, domain=(-10.0, 18.0, 9.0), film_factor=2.0,
                            receding="bretherton", normal_length=0.3)
    prob = problem_from_spec(spec, ball_gap, options)
    assert prob.supply == pytest.approx(8e-6)
    assert prob.track_half_width == pytest.approx(2e-4)
    assert prob.initial_radius == pytest.approx(6 * a)
    assert prob.island_radius == pytest.approx(spec.domain.island_radius * a)
    assert prob.x_range == pytest.approx((-10 * a, 18 * a)) and prob.y_max == pytest.approx(9 * a)
    assert prob.cell == pytest.approx(0.25 * a)
    assert (prob.speed, prob.viscosity) == (spec.speed, spec.oil_viscosity)
    assert (prob.contact_angle, prob.receding_meniscus) == (20.0, "bretherton")
    assert prob.normal_length == pytest.approx(0.3 * a)
    assert prob.film == pytest.approx(2 * landau_levich(spec.oil_viscosity, spec.speed,
                                                        spec.physics.surface_tension))
    flooded = make_case_spec({"supply": {"mode": "flooded"}})
    prob = problem_from_spec(flooded, ball_gap, options)
    assert prob.supply == pytest.approx(ball_gap(-10 * flooded.a, 0.0))   # the whole inlet gap
    with pytest.raises(ValueError, match="supply.mode = 'submerged'"):
        problem_from_spec(make_case_spec({"supply": {"mode": "submerged"}}), ball_gap, options)


@pytest.mark.parametrize("options, words", [
    (RegionOptions(cell=5.0), r"cell = 5.0 a is out of range: must be in \(0, 3.75\] a"),
    (RegionOptions(cell=0.0), r"cell = 0.0 a is out of range"),
    (RegionOptions(domain=(0.0, 19.0, 11.0)), r"domain = \(0.0, 19.0, 11.0\) a is out of range"),
    (RegionOptions(cell=0.2, normal_length=0.05),
     r"normal_length = 0.05 a is out of range: must be None or in \[0.1, 3.75\] a"),
    (RegionOptions(advancing_angle=10.0), r"advancing_angle = 10.0 is out of range"),
])
def test_a_grid_out_of_range_is_refused_in_units_of_a(options, words):
    with pytest.raises(ValueError, match=words):
        problem_from_spec(make_case_spec({}), ball_gap, options)


def test_a_march_is_written_as_a_state_and_a_summary(tmp_path):
    """Two transits of the spec (run.transit_length a at u) from its puddle: the state reads
    back cell for cell, the summary holds its metrics, one record a transit and the record
    it was given."""
    spec = make_case_spec({"supply": {"initial_puddle": 5.0}})
    a = spec.a
    prob = problem_from_spec(spec, ball_gap, RegionOptions(cell=0.5))
    sol = march(spec, prob, transits=2)
    assert sol.time == pytest.approx(2 * spec.transit_time, rel=0.01)
    summary = write_region(sol, spec, tmp_path / "tf", {"made_by": "test"})
    back = load_state(tmp_path / "tf" / "state.npz")
    np.testing.assert_array_equal(back.flooded, sol.flooded)
    np.testing.assert_array_equal(back.content, sol.content)
    on_disc = json.loads((tmp_path / "tf" / "summary.json").read_text())
    assert on_disc == json.loads(json.dumps(summary))
    assert on_disc["made_by"] == "test" and len(on_disc["history"]) == 2
    assert on_disc["transits"] == pytest.approx(2.0, rel=0.01)
    m = on_disc["metrics"]
    assert m["state"] == "I" and m["cell_over_a"] == pytest.approx(0.5)
    assert m["oil_volume_m3"] == pytest.approx(sol.metrics(a)["oil_volume_m3"])
    assert not list((tmp_path / "tf").glob(".*.tmp"))          # atomic: no leftovers


def test_balance_stops_a_march_when_the_outflow_meets_the_supply():
    """With balance the march stops at the window's balance before the cap; without, it
    runs to the cap."""
    spec = make_case_spec({"supply": {"initial_puddle": 8.0}})
    prob = problem_from_spec(spec, ball_gap, RegionOptions(cell=0.5))
    capped = march(spec, prob, transits=12)
    balanced = march(spec, prob, transits=60, balance=True, tolerance=0.05, window=3)
    assert not capped.steady and capped.time == pytest.approx(12 * spec.transit_time, rel=0.01)
    assert balanced.steady and balanced.time < 60 * spec.transit_time
    assert balanced.flux_out / balanced.flux_in == pytest.approx(1.0, abs=0.1)


def test_the_gas_balance_of_a_spec_scales_its_diffusivity_with_temperature_and_viscosity():
    """The balance's constants from the spec: the Ostwald solubility, the ambient and
    release pressures, and the diffusivity taken from 40 C / 21.6 mPa s to the case's as
    T / eta^(2/3); none in the release pressure's scene."""
    from ehlfoam.thinfilm.from_spec import DIFFUSIVITY_REFERENCE, gas_balance, scene_options
    spec = make_case_spec({"scene": "thin-film"}, **{
        "thin_film.bubble_gas": "balance", "contact.temperature": 25.0,
        "physics.cavitation_pressure": 9.5e4})
    k = gas_balance(spec)
    eta_ref, t_ref = DIFFUSIVITY_REFERENCE
    assert k.diffusivity == pytest.approx(1e-9 * (298.15 / t_ref)
                                          * (eta_ref / spec.oil_viscosity) ** (2 / 3))
    assert k.diffusivity < 1e-9            # HVI60 is thicker at 25 C
    assert (k.solubility, k.ambient, k.release) == (0.09, 1.013e5, 9.5e4)
    assert scene_options(spec).gas
    assert not scene_options(make_case_spec({"scene": "thin-film"})).gas
