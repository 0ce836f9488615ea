"""The walls' contact-angle condition (ehlfoam.case.wall_angle): static unless the advancing
and receding angles differ, then v1912's dynamicAlphaContactAngle with its limits where the
spec puts them. The sign on a real run: tests/case/test_strip.py."""

from __future__ import annotations

import math

import pytest

from ehlfoam.case.wall_angle import ANGLE_SPEED_SHARE, wall_angle_entry
from ehlfoam.errors import SpecError
from ehlfoam.spec.case import make_case_spec


def v1912_theta(entry: dict, u_w: float) -> float:
    """dynamicAlphaContactAngleFvPatchScalarField::theta of v1912 for a wall cell moving at
    ``u_w`` relative to the wall along the interface's normal (into the oil)."""
    return entry["theta0"] + (entry["thetaA"] - entry["thetaR"]) * math.tanh(
        u_w / entry["uTheta"])


def test_the_static_angle_is_a_constant_condition():
    entry = wall_angle_entry(make_case_spec({"physics": {"contact_angle": 25.0}}))
    assert entry["type"] == "constantAlphaContactAngle" and entry["theta0"] == 25.0
    both = make_case_spec({"physics": {"advancing_angle": 30.0, "receding_angle": 30.0}})
    assert wall_angle_entry(both) == {**entry, "theta0": 30.0}


def test_apart_the_advancing_line_takes_the_advancing_angle_and_oil_at_rest_their_mean():
    spec = make_case_spec({"contact": {"speed": 0.017},
                           "physics": {"advancing_angle": 52.7, "receding_angle": 0.0}})
    entry = wall_angle_entry(spec)
    assert entry["type"] == "dynamicAlphaContactAngle"
    assert entry["uTheta"] == pytest.approx(ANGLE_SPEED_SHARE * 0.017)
    # an oil front advancing over the wall moves against the normal into the oil: u_w < 0
    assert v1912_theta(entry, -0.017) == pytest.approx(52.7, abs=1e-6)
    assert v1912_theta(entry, 0.017) == pytest.approx(0.0, abs=1e-6)
    assert v1912_theta(entry, 0.0) == pytest.approx(26.35)
    # an unset receding angle is the static one
    half = wall_angle_entry(make_case_spec({"physics": {"advancing_angle": 41.0}}))
    assert v1912_theta(half, -1.0) == pytest.approx(41.0)
    assert v1912_theta(half, 1.0) == pytest.approx(15.0)


@pytest.mark.parametrize("physics, words", [
    ({"receding_angle": 30.0}, "receding_angle = 30 deg must not exceed advancing_angle = 15"),
    ({"advancing_angle": 10.0, "receding_angle": 5.0, "contact_angle": 20.0}, None),
    ({"advancing_angle": 200.0}, "physics.advancing_angle = 200"),
])
def test_angles_out_of_order_or_range_are_refused(physics, words):
    if words is None:          # in order, whatever the static angle: taken
        assert make_case_spec({"physics": physics}).physics.wall_angles == (10.0, 5.0)
        return
    with pytest.raises(SpecError, match=words):
        make_case_spec({"physics": physics})
