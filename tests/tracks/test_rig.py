"""The rig's tracks (ehlfoam.tracks.rig) and the thin-film model's two ends of a pass: its
supply as lateral profiles (the scalar supply's march when the profiles are its own), the
oil it carries out row by row closing on what it took in, the layers a balanced state
leaves behind, the passes' timing and the tracks' oil kept through a pass."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ehlfoam.thinfilm import ThinFilmProblem, solve_thin_film
from ehlfoam.thinfilm.march import Marcher
from ehlfoam.tracks.rig import Rig, Tracks, outlet_layers

A, U = 1.37e-4, 0.008


def gap(x, y):
    """A rigid ball on a flat: 1 um at the contact, R = 9.525 mm."""
    return 1e-6 + (np.asarray(x) ** 2 + np.asarray(y) ** 2) / (2 * 9.525e-3)


def problem(**kw) -> ThinFilmProblem:
    """A small region round an island on 0.6 a cells, 8 um layers on each wall, gas below
    10 kPa under ambient."""
    base = dict(gap=gap, speed=U, viscosity=0.0216, surface_tension=0.03, contact_angle=15.0,
                supply=16e-6, track_half_width=3e-4, x_range=(-7.2 * A, 10.8 * A),
                y_max=6 * A, island_radius=1.5 * A, cell=0.6 * A, initial_radius=5 * A,
                cavitation_pressure=-1e4)
    return ThinFilmProblem(**(base | kw))


def test_its_own_profiles_march_as_the_scalar_supply():
    """Profiles (disc, ball) that are the scalar supply's halves on the track's rows give the
    same march: the same oil in every cell after 200 steps (to 1e-9 of the gap)."""
    scalar = problem()
    d = scalar.cell
    y = d * (np.arange(scalar.rows) + 0.5)
    on = np.clip((scalar.track_half_width - (y - d / 2)) / d, 0.0, 1.0)
    layers = (8e-6 * on, 8e-6 * on)
    runs = [Marcher(p) for p in (scalar, problem(supply_layers=layers))]
    for m in runs:
        for _ in range(200):
            m.step()
    assert runs[0].q_in == pytest.approx(runs[1].q_in, rel=1e-14)
    assert np.abs(runs[0].c - runs[1].c).max() <= 1e-9 * 1e-6
    assert (runs[0].flooded == runs[1].flooded).all()


def test_profiles_of_the_wrong_shape_or_sign_are_refused_by_name():
    ny = problem().rows
    with pytest.raises(ValueError, match=r"supply_layers \(disc\) has shape \(3,\)"):
        problem(supply_layers=(np.zeros(3), np.zeros(ny)))
    with pytest.raises(ValueError, match=r"supply_layers \(ball\) = -1e-06 m on row 0 is out "
                                         r"of range: must be finite and >= 0"):
        problem(supply_layers=(np.zeros(ny), np.full(ny, -1e-6)))


def test_the_outlet_rows_close_the_balance_on_the_inflow():
    """What left through the outlet row by row, plus the side, plus the oil gained, is what
    the supply brought in, to round-off, while the region fills and empties."""
    m = Marcher(problem(supply_layers=(np.linspace(1e-6, 0, 10), np.linspace(2e-6, 0, 10))))
    start = m.oil()
    for _ in range(400):
        m.step()
    assert m.oil_out_rows.sum() == pytest.approx(m.oil_out_outlet, rel=1e-12)
    closing = m.oil_in - m.oil_out_rows.sum() - m.oil_out_side - (m.oil() - start)
    assert abs(closing) <= 1e-12 * m.oil_in
    assert (m.oil_out_rows > 0).sum() >= 3                 # a profile, not a point


def test_a_balanced_state_leaves_its_supply_behind_split_between_the_walls():
    """At the balance the layers the state carries out of its last column (films and
    layers behind a region that closes before the outlet), u times their sum over the rows,
    are the supply within 1 %; half on each wall. A state whose region floods the outlet is
    refused: its outflow is not in its cells."""
    sol = solve_thin_film(problem(supply=4e-6), transits_max=80, tolerance=0.01,
                          transit_length=10 * A)
    assert sol.steady and not sol.flooded[:, -1].any()
    disc, ball = outlet_layers(sol)
    assert np.array_equal(disc, ball)
    carried = U * float((disc + ball).sum()) * sol.grid.cell
    assert carried == pytest.approx(sol.flux_in, rel=0.01)
    flooded = solve_thin_film(problem(), transits_max=10, tolerance=0.0, transit_length=10 * A)
    with pytest.raises(ValueError, match="the flooded region reaches the outlet on 10 rows"):
        outlet_layers(flooded)


def rig(**kw) -> Rig:
    base = dict(track_radius=0.039, ball_radius=9.525e-3, speed=0.008, surface_tension=0.03,
                viscosity=0.0216, row=0.4 * A, rows=25, width_rows=75, step=0.25 * 0.4 * A / U)
    return Rig(**(base | kw))


def test_a_pass_is_a_ball_revolution_and_a_kth_of_the_disc_s():
    """r / R = 4.09: K = 4 arcs; a pass a whole number of steps within a step of 2 pi r /
    (K u); the ball levels for 2 pi R / u, the disc's arcs for K passes."""
    r = rig()
    assert r.arcs == 4
    assert abs(r.pass_time - 2 * math.pi * 0.039 / (4 * U)) <= r.step
    assert r.pass_time == pytest.approx(r.pass_steps * r.step, rel=1e-15)
    assert r.arc_length * r.arcs == pytest.approx(2 * math.pi * 0.039, rel=1e-3)
    assert r.disc_revolution == pytest.approx(4 * r.pass_time)
    assert r.ball_revolution == pytest.approx(2 * math.pi * 9.525e-3 / U)
    assert rig(track_radius=3e-3).arcs == 1


def test_a_pass_keeps_the_tracks_oil_and_moves_to_the_next_arc():
    """The tracks lose the layers on the contact's rows of the arc met and of the ball and
    gain what was laid (a row drawing oil in takes it from the others): their oil changes by
    laid less taken, to round-off; the arc met next is the next one."""
    r = rig()
    tracks = Tracks.uniform(r, 2e-6, 1e-6, 3e-4)
    before = sum(tracks.oil(r))
    disc, ball = tracks.inlet(r)
    taken = float((disc + ball).sum()) * r.arc_length * r.row
    laid = np.linspace(3e-12, 0.0, r.rows)
    laid[-3] = -1e-14
    tracks.lay(r, laid, side=1e-13)
    after = sum(tracks.oil(r))
    assert after - before == pytest.approx(laid.sum() + 1e-13 - taken, rel=1e-12)
    assert tracks.next_arc == 1 and tracks.passes == 1
    assert (tracks.disc >= 0).all() and (tracks.ball >= 0).all()
    assert np.array_equal(tracks.disc[2], tracks.disc[3])       # untouched arcs


def test_bad_rig_parameters_are_refused_by_name():
    with pytest.raises(ValueError, match=r"width_rows = 10 is out of range: must be >= 25"):
        rig(width_rows=10)
    with pytest.raises(ValueError, match=r"disc_share = 1.5 is out of range"):
        rig(disc_share=1.5)
