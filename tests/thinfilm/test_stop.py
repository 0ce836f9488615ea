"""The sudden stop's wall velocity (ehlfoam.spec.stop, issue 76 part 5): the one function
that gives the walls' speed over time, the [stop] table's checks, and a march that follows it:
a march whose walls run at half its speed is the march of the problem at half the speed, step
for step; one whose walls stop takes in no oil and lets none out at rest, keeps its oil, and
its region draws round."""

from __future__ import annotations

import numpy as np
import pytest

from ehlfoam.errors import SpecError
from ehlfoam.spec import make_case_spec
from ehlfoam.spec.stop import Stop, stop_end_time, wall_speed_at
from ehlfoam.thinfilm.gas import GasBalance
from ehlfoam.thinfilm.march import Marcher
from ehlfoam.thinfilm.solution import connected_region
from tests.thinfilm.test_model import A, ball_problem

U = 0.008


def test_the_walls_roll_then_slow_linearly_to_rest_and_stay_there():
    stop = Stop(at=0.01, duration=0.004)
    t = np.array([0.0, 0.0099, 0.01, 0.011, 0.012, 0.0139, 0.014, 0.02, 5.0])
    u = wall_speed_at(stop, U, t)
    assert u == pytest.approx([U, U, U, 0.75 * U, 0.5 * U, 0.025 * U, 0.0, 0.0, 0.0],
                              abs=1e-15)
    assert isinstance(wall_speed_at(stop, U, 0.012), float)
    assert np.all(np.diff(u) <= 0)                      # never speeds up again
    sudden = Stop(at=0.01, duration=0.0)                # at once
    assert wall_speed_at(sudden, U, [0.00999, 0.01, 0.02]) == pytest.approx([U, 0, 0])
    assert wall_speed_at(Stop(), U, [0.0, 1.0, 100.0]) == pytest.approx([U] * 3)
    assert stop_end_time(stop) == pytest.approx(0.01 + 0.004 + 0.1)
    assert stop_end_time(Stop()) is None


def test_the_stop_table_is_checked_and_sets_the_run_s_end():
    tf = {"scene": "thin-film", "stop": {"at": 0.02, "duration": 0.01, "after": 0.05}}
    spec = make_case_spec(tf)
    assert spec.end_time == pytest.approx(0.08)
    assert make_case_spec({"scene": "thin-film"}).end_time == pytest.approx(
        4.0 * make_case_spec({"scene": "thin-film"}).transit_time)
    with pytest.raises(SpecError, match=r"stop\.duration = -0\.001.*0 <= stop\.duration <= 10 s"):
        make_case_spec({**tf, "stop": {"at": 0.0, "duration": -0.001}})
    with pytest.raises(SpecError, match=r"stop\.after = 0.*0 < stop\.after <= 100 s"):
        make_case_spec({**tf, "stop": {"at": 0.0, "after": 0.0}})
    assert make_case_spec({"stop": {"at": 0.02}}).end_time == pytest.approx(0.125)   # 3D
    with pytest.raises(SpecError, match=r"stop\.at = 0\.02 s does not apply to supply\.mode "
                                        r"= \"rig\""):
        make_case_spec({**tf, "stop": {"at": 0.02}, "supply": {"mode": "rig"}})
    with pytest.raises(SpecError, match=r"run\.end_time = 1 s does not apply with stop\.at"):
        make_case_spec({**tf, "run": {"end_time": 1.0}})


def _gas() -> GasBalance:
    return GasBalance(solubility=0.09, diffusivity=1e-9, temperature=313.15, ambient=1.013e5,
                      release=9e4)


def test_a_march_at_half_its_speed_is_the_march_of_the_problem_at_half_the_speed():
    """Every flux the walls drive follows u(t): Couette, supply, films, the gas's exchange.
    The same step (a quarter cell's transit at u) on both sides, to round-off."""
    prob = ball_problem(cavitation_pressure=-11300.0, gas=_gas(), speed=2 * U)
    slowed = Marcher(prob, courant=0.25, speed_at=lambda t: U)
    half = Marcher(ball_problem(cavitation_pressure=-11300.0, gas=_gas()), courant=0.125)
    assert slowed.dt == pytest.approx(half.dt, rel=1e-12)
    for _ in range(150):
        slowed.step()
        half.step()
    assert slowed.speed == U
    assert half.cavity().any() and half.gas.held() > 0  # a bubble, with its gas
    assert np.allclose(slowed.c, half.c, rtol=0, atol=1e-12 * prob.supply)
    assert np.array_equal(slowed.flooded, half.flooded)
    assert slowed.gas.held() == pytest.approx(half.gas.held(), rel=1e-9)
    assert half.gas.budget["released_by_diffusion_mol"] > 0
    for key, value in half.gas.budget.items():
        assert slowed.gas.budget[key] == pytest.approx(value, rel=1e-9, abs=1e-30), key
    assert slowed.oil_in == pytest.approx(half.oil_in, rel=1e-12)


def _aspect(m: Marcher) -> float:
    region = connected_region(m.flooded, m.grid.island)
    cols, rows = np.nonzero(region.any(axis=0))[0], np.nonzero(region.any(axis=1))[0]
    return (cols[-1] - cols[0] + 1) / (2.0 * (rows[-1] + 1))


def test_walls_that_stop_take_in_and_carry_out_nothing_and_the_region_draws_round():
    """From a region made at u (longer than wide), the walls slow to rest over 5 ms: the
    march's speed is u(t) at each step's middle, the step stays u's, no oil comes in or
    leaves once at rest, the oil is kept, and the region, held only by its menisci, draws
    toward a circle about the contact."""
    prob = ball_problem()
    m = Marcher(prob, courant=0.25, transit_length=10 * A)
    while m.steps < 6 * m.steps_per_transit:           # the region at u
        m.step()
    stop = Stop(at=m.time, duration=0.005)
    t_stop, dt = m.time, m.dt
    moving = Marcher(prob, start=m.solution(), courant=0.25, transit_length=10 * A,
                     speed_at=lambda t: wall_speed_at(stop, U, t_stop + t))
    before = _aspect(moving)
    assert before > 1.15
    speeds = []
    while moving.time < 0.005:
        t_mid = moving.time + 0.5 * moving.dt
        moving.step()
        speeds.append((moving.speed, wall_speed_at(stop, U, t_stop + t_mid)))
    assert moving.dt == dt
    assert [s for s, _ in speeds] == pytest.approx([w for _, w in speeds], abs=1e-15)
    assert speeds[0][0] > speeds[-1][0] >= 0.0
    oil_in, out = moving.oil_in, moving.oil_out_outlet + moving.oil_out_side
    while moving.time < 0.005 + 0.06:
        moving.step()
    assert moving.speed == 0.0
    assert moving.oil_in == oil_in                      # no supply at rest
    assert moving.oil_out_outlet + moving.oil_out_side == pytest.approx(out, abs=1e-25)
    assert moving.mass_balance_error() < 1e-9
    assert np.isfinite(moving.c).all()
    after = _aspect(moving)
    assert abs(after - 1.0) < 0.5 * abs(before - 1.0)
