"""The bridge's theory (ehlfoam.thinfilm.bridge): where a meniscus rests for an angle and back,
a slip's share of the drag, Cox-Voinov, and where the gap is h."""

from __future__ import annotations

import numpy as np
import pytest

from ehlfoam.spec.case import make_case_spec
from ehlfoam.thinfilm.bridge import (angle_at_meniscus, bridge_balance, cox_voinov,
                                     meniscus_for_angle, x_at_gap)
from tests.tiny import SMALL, small_contact


@pytest.fixture(scope="module")
def small():
    return small_contact()


def test_the_meniscus_position_and_its_apparent_angle_invert_each_other(small):
    spec, gap, a = small
    balance = bridge_balance(spec, gap, 4 * a, 10 * a)
    x = [meniscus_for_angle(spec, balance, t) for t in (15.0, 30.0, 47.0, 70.0)]
    assert all(4 * a < xi < 10 * a for xi in x)
    assert x == sorted(x, reverse=True)         # less suction: nearer the reservoir
    for theta, xi in zip((15.0, 30.0, 47.0, 70.0), x):
        assert angle_at_meniscus(spec, balance, xi) == pytest.approx(theta, abs=0.5)
    # at the reservoir no drag has built up: no angle below a right one balances there
    assert np.isnan(angle_at_meniscus(spec, balance, 4 * a))


def test_a_slip_takes_its_share_of_the_drag_off_the_balance(small):
    """On a gap of uniform height h, walls slipping by lambda let the pressure drive
    (1 + 6 lambda / h) times the flux, so the drag's pressure drop is that much smaller; a
    precursor layer p on each wall takes (h - 2 p) / h of it."""
    spec, _, a = small
    h, lam = 30e-6, 1e-6
    slipping = make_case_spec({**SMALL, "physics": {"wall_slip_length": lam}})
    flat = lambda x, y: np.full_like(np.asarray(x, float), h)  # noqa: E731
    drop = bridge_balance(spec, flat, 4 * a, 10 * a).drop[-1]
    assert drop == pytest.approx(12 * spec.oil_viscosity * spec.speed * 6 * a / h**2, rel=1e-9)
    assert bridge_balance(slipping, flat, 4 * a, 10 * a).drop[-1] == pytest.approx(
        drop / (1 + 6 * lam / h), rel=1e-9)
    assert bridge_balance(spec, flat, 4 * a, 10 * a, precursor=3e-6).drop[-1] == pytest.approx(
        drop * (h - 6e-6) / h, rel=1e-9)


def test_cox_voinov_grows_the_static_angle_with_the_log_of_the_length_ratio():
    assert cox_voinov(15.0, 0.006, 1.0) == pytest.approx(15.0)
    theta = np.radians(cox_voinov(15.0, 0.006, 100.0))
    assert theta**3 == pytest.approx(np.radians(15.0) ** 3 + 9 * 0.006 * np.log(100.0))
    assert cox_voinov(15.0, 0.006, 1e3) > cox_voinov(15.0, 0.006, 1e2)


def test_where_the_gap_is_h_and_where_no_film_was_measured(small):
    _, gap, a = small
    h8 = float(gap(np.array([8 * a]), np.array([0.0]))[0])
    assert x_at_gap(gap, h8, 3 * a, 10 * a) == pytest.approx(8 * a, rel=1e-6)
    # no film measured (a failed run): NaN, not a root finder's error
    assert np.isnan(x_at_gap(gap, float("nan"), 3 * a, 10 * a))
    # a gap outside the range
    assert np.isnan(x_at_gap(gap, 10 * h8, 3 * a, 10 * a))
