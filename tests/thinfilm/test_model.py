"""The thin-film model of the flooded region (ehlfoam.thinfilm): a strip against
its 1D theory, a region round an island, films, metrics and bad input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from ehlfoam.thinfilm import (Grid, ThinFilmProblem, ThinFilmSolution, landau_levich,
                              region_metrics, solve_thin_film)

ETA, U, SIGMA, THETA = 0.02, 0.01, 0.03, 15.0


def strip_gap(x, y):
    """A gap that does not vary along y: 20 um at x = 0, a 10 mm radius."""
    return 20e-6 + np.asarray(x) ** 2 / (2 * 0.01) + 0 * np.asarray(y)


def strip_problem(supply: float, cell: float, **kw) -> ThinFilmProblem:
    """The strip: 5 mm along x, two cells across with both sides closed, fed ``supply``."""
    return ThinFilmProblem(gap=strip_gap, speed=U, viscosity=ETA, surface_tension=SIGMA,
                           contact_angle=THETA, supply=supply, track_half_width=1.0,
                           x_range=(-2e-3, 3e-3), y_max=2 * cell, island_radius=0.0,
                           cell=cell, initial_radius=0.8e-3, closed_side=True, **kw)


@pytest.mark.parametrize("receding", ["static", "bretherton"])
def test_strip_menisci_sit_where_the_1d_theory_puts_them(receding):
    """In a strip the steady region passes the supply s as Landau-Levich films: its rear
    meniscus sits where f h = s, and its inlet meniscus where the Reynolds pressure rise
    from it to the rear, int 12 eta u (h - s) / h^3 dx, equals the difference of the two
    menisci's capillary pressures: 2 sigma cos(theta) / h_in less 2 sigma cos(theta) /
    h_rear (static) or (2 sigma / h_rear) (1 + 3.8 Ca^(2/3)) (Bretherton's receding
    meniscus)."""
    s, cell = 4e-6, 2.5e-5
    prob = strip_problem(s, cell, receding_meniscus=receding)
    sol = solve_thin_film(prob, transits_max=10, tolerance=0.0, transit_length=5e-3)
    h_rear = s / landau_levich(ETA, U, SIGMA)
    x_rear = np.sqrt(2 * 0.01 * (h_rear - 20e-6))
    cos_t = np.cos(np.radians(THETA))
    suction_rear = (2 * SIGMA / h_rear * (1 + 3.8 * (ETA * U / SIGMA) ** (2 / 3))
                    if receding == "bretherton" else 2 * SIGMA * cos_t / h_rear)

    def mismatch(x_in):
        rise = quad(lambda x: 12 * ETA * U * (strip_gap(x, 0) - s) / strip_gap(x, 0) ** 3,
                    x_in, x_rear)[0]
        return rise - (2 * SIGMA * cos_t / strip_gap(x_in, 0) - suction_rear)

    xs = np.linspace(-1.9e-3, 0.99 * x_rear, 40)     # the first crossing from upstream
    k = np.nonzero(np.diff(np.sign([mismatch(x) for x in xs])))[0][0]
    x_in = brentq(mismatch, xs[k], xs[k + 1])
    row = sol.flooded[0]
    assert (sol.flooded == row).all()                  # no variation along y
    xs = sol.grid.x[row]
    assert abs(xs[-1] + cell / 2 - x_rear) <= cell
    assert abs(xs[0] - cell / 2 - x_in) <= cell
    # read inside their open cells (sub-cell menisci), within a quarter and a half cell
    first, last = np.nonzero(row)[0][[0, -1]]
    assert abs(xs[0] - cell / 2 - cell * sol.fill[0, first - 1] - x_in) <= 0.25 * cell
    assert abs(xs[-1] + cell / 2 + cell * sol.fill[0, last + 1] - x_rear) <= 0.5 * cell
    assert abs(sol.flux_out / sol.flux_in - 1.0) < 0.02
    assert sol.mass_balance_error < 1e-9


def test_a_march_stops_at_a_balance_read_over_a_window_of_transits():
    """With a tolerance the march stops once the mean outflow over the last ``window``
    transits meets the supply and the oil has stood over them, and says so."""
    s, cell = 4e-6, 5e-5
    prob = strip_problem(s, cell)
    sol = solve_thin_film(prob, transits_max=40, tolerance=0.01, transit_length=5e-3,
                          window=3)
    assert sol.steady
    assert 3 < len(sol.history) < 40
    last = sol.history[-4:]
    assert np.mean([r["outflow_over_supply"] for r in last[1:]]) == pytest.approx(1, abs=0.01)
    assert last[-1]["oil_m3"] == pytest.approx(last[0]["oil_m3"], rel=0.01)


def ball_gap(x, y):
    """A rigid ball on a flat: 1 um at the contact, R = 9.525 mm."""
    return 1e-6 + (np.asarray(x) ** 2 + np.asarray(y) ** 2) / (2 * 9.525e-3)


A = 1.37e-4


def ball_problem(**kw) -> ThinFilmProblem:
    base = dict(gap=ball_gap, speed=0.008, viscosity=0.0216, surface_tension=SIGMA,
                contact_angle=THETA, supply=16e-6, track_half_width=3e-4,
                x_range=(-11 * A, 19 * A), y_max=11 * A, island_radius=1.5 * A,
                cell=0.4 * A, initial_radius=7 * A)
    return ThinFilmProblem(**(base | kw))


def test_region_closes_round_the_island_and_keeps_its_oil():
    sol = solve_thin_film(ball_problem(), transits_max=6, tolerance=0.0,
                          transit_length=10 * A)
    m = sol.metrics(A)
    assert m["state"] == "I"
    assert not m["touches_boundary"]
    assert m["inlet_meniscus_distance_over_a"] > 1.0
    assert m["rear_meniscus_x_over_a"] > 3.0
    assert m["flooded_width_over_a"] > 6.0
    assert sol.mass_balance_error < 1e-9
    assert len(sol.history) == 6


def test_thicker_films_hold_less_oil_in_a_narrower_region():
    thin, thick = (solve_thin_film(ball_problem(film_factor=f), transits_max=6,
                                   tolerance=0.0, transit_length=10 * A).metrics(A)
                   for f in (1.0, 3.0))
    assert thick["oil_volume_m3"] < 0.9 * thin["oil_volume_m3"]
    assert thick["flooded_width_over_a"] < thin["flooded_width_over_a"]
    assert thick["outflow_over_supply"] > thin["outflow_over_supply"]


@pytest.mark.parametrize("receding, pull", [(1.1, 1.1), ("bretherton", None)])
def test_the_receding_pull_acts_where_the_walls_leave_the_meniscus(receding, pull):
    """On a round region the open cells get the full pull straight behind it, none ahead
    of it or beside it, and n^(2/3) of it in between."""
    from ehlfoam.thinfilm.operators import Operators, touches

    prob = ball_problem(receding_meniscus=receding, cell=0.2 * A)
    grid = Grid.build(prob)
    ops = Operators(prob, grid)
    X, Y = np.meshgrid(grid.x, grid.y)
    flooded = (np.hypot(X, Y) < 6 * A) & ~grid.island
    factor = ops.pull_factor(flooded)
    if pull is None:
        cos_t = np.cos(np.radians(THETA))
        pull = (1 + 3.8 * (0.0216 * 0.008 / SIGMA) ** (2 / 3)) / cos_t
    edge = touches(flooded) & ~grid.island
    rear = edge[0] & (grid.x > 0)
    front = edge[0] & (grid.x < 0)
    assert factor[0, rear] == pytest.approx(pull, rel=1e-3)
    assert factor[0, front] == pytest.approx(1.0)
    side = edge & (np.abs(X) < 0.3 * A)
    assert factor[side] == pytest.approx(1.0, abs=0.03 * (pull - 1))
    at45 = edge & (np.abs(np.arctan2(Y, X) - np.pi / 4) < 0.05)
    assert factor[at45] == pytest.approx(1 + (pull - 1) * np.cos(np.pi / 4) ** (2 / 3),
                                         rel=0.02)
    assert (factor[~edge & ~flooded & ~grid.island] >= 1.0).all()
    static = Operators(ball_problem(receding_meniscus=1.0), grid)
    assert np.all(static.pull_factor(flooded) == 1.0)


def test_the_advancing_angle_acts_where_dry_walls_run_into_the_meniscus():
    """Off the track the walls come in dry: straight ahead of a round region its menisci
    take cos(theta_a) / cos(theta_s) of the static suction, beside it none of the change,
    and in between Cox-Voinov's theta^3 at the share of the walls' speed into it; on the
    track, where the supply's layers meet it, the static suction stays."""
    from ehlfoam.thinfilm.operators import Operators, touches

    prob = ball_problem(advancing_angle=47.0, cell=0.2 * A, track_half_width=2 * A)
    grid = Grid.build(prob)
    ops = Operators(prob, grid)
    X, Y = np.meshgrid(grid.x, grid.y)
    flooded = (np.hypot(X, Y) < 6 * A) & ~grid.island
    factor = ops.pull_factor(flooded)
    edge = touches(flooded) & ~grid.island
    ts, ta = np.radians(THETA), np.radians(47.0)
    assert factor[0, edge[0] & (grid.x < 0)] == pytest.approx(1.0)       # on the track
    assert factor[0, edge[0] & (grid.x > 0)] == pytest.approx(1.0)       # the rear
    side = edge & (np.abs(X) < 0.3 * A)
    assert factor[side] == pytest.approx(1.0, abs=0.03)
    dry = grid.y[:, None] > 2 * A + 0.2 * A
    at135 = edge & dry & (np.abs(np.arctan2(Y, X) - 3 * np.pi / 4) < 0.05)
    m = np.cos(np.pi / 4)
    expected = np.cos(np.cbrt(ts**3 + m * (ta**3 - ts**3))) / np.cos(ts)
    assert factor[at135] == pytest.approx(expected, rel=0.03)
    assert expected < 0.85                    # a weaker suction than the static one
    static = Operators(ball_problem(cell=0.2 * A), grid)
    assert np.all(static.pull_factor(flooded) == 1.0)


def test_a_normal_length_in_metres_gives_every_grid_the_same_pull():
    """With the region smoothed over a fixed length for the meniscus's normal, the pull on
    the open cells round a tilted ellipse agrees between 0.2 a and 0.1 a cells (the coarse
    cells against the mean of the fine cells in them): 90 % of them within 2.5 % of the
    pull's excess at 0.6 a; at 1.5 cells each (the default) the two grids' staircases give
    different normals, twice that apart."""
    from ehlfoam.thinfilm.operators import Operators, touches

    def pull_field(cell, normal_length):
        prob = ball_problem(receding_meniscus="bretherton", cell=cell * A,
                            normal_length=normal_length)
        grid = Grid.build(prob)
        ops = Operators(prob, grid)
        X, Y = np.meshgrid(grid.x, grid.y)
        xr, yr = (X - Y) / np.sqrt(2), (X + Y) / np.sqrt(2)
        flooded = ((xr / (7 * A)) ** 2 + (yr / (4 * A)) ** 2 < 1) & ~grid.island
        return ops.pull_factor(flooded), flooded, grid

    apart = {}
    for normal_length in (0.6 * A, None):
        coarse, fl_c, grid_c = pull_field(0.2, normal_length)
        fine, fl_f, _ = pull_field(0.1, normal_length)
        fine_mean = 0.25 * (fine[0::2, 0::2] + fine[1::2, 0::2] + fine[0::2, 1::2]
                            + fine[1::2, 1::2])
        edge = touches(fl_c) & ~grid_c.island & (fl_c == fl_f[0::2, 0::2])
        excess = coarse[~grid_c.island].max() - 1.0
        apart[normal_length] = np.percentile(np.abs(coarse - fine_mean)[edge] / excess, 90)
    assert apart[0.6 * A] < 0.025
    assert apart[None] > 2 * apart[0.6 * A]


def test_a_pull_on_a_normal_of_metres_opens_no_cell_dry_where_one_of_cells_does():
    """On 0.1 a cells, Bretherton's pull on a normal smoothed over 1.5 cells swings with
    every cell that flips and drains hundreds of flooded cells within a step over half a
    transit (341 measured); smoothed over 0.3 a it drains none."""
    def dry(normal_length):
        sol = solve_thin_film(ball_problem(cell=0.1 * A, receding_meniscus="bretherton",
                                           normal_length=normal_length),
                              transits_max=1, tolerance=0.0, transit_length=5 * A)
        return sol.history[-1]["cells_opened_dry"]

    assert dry(0.3 * A) == 0
    assert dry(None) > 100


def _ring_grid(n=40):
    d = 1.0 / n * 20 * A
    x = -10 * A + d * (np.arange(n) + 0.5)
    y = d * (np.arange(n // 2) + 0.5)
    X, Y = np.meshgrid(x, y)
    island = np.hypot(X, Y) < 1.5 * A
    h = np.where(island, np.nan, 1e-5)
    return Grid(x=x, y=y, h=h, hx=h[:, 1:], hy=h[1:], h_side=h[-1], island=island), X, Y


def test_metrics_read_a_closed_ring_as_state_I_and_an_open_wake_as_state_II():
    grid, X, Y = _ring_grid()
    r = np.hypot(X, Y)
    ring = (r < 6 * A) & ~grid.island
    closed = region_metrics(ring, grid, A, 1.5 * A)
    assert closed["state"] == "I"
    assert closed["flooded_width_over_a"] == pytest.approx(12.0, abs=0.5)
    assert closed["inlet_meniscus_distance_over_a"] == pytest.approx(5.0, abs=0.5)
    pocket = ring & ~((r < 3 * A) & (X > 0))           # enclosed air behind the island
    assert region_metrics(pocket, grid, A, 1.5 * A)["state"] == "I"
    wake = ring & ~((X > 0) & (Y < 2 * A))             # the air behind reaches the outside
    assert region_metrics(wake, grid, A, 1.5 * A)["state"] == "II"


def test_sub_cell_menisci_are_read_where_they_sit_in_their_open_cells():
    """A fill of 0.4 in every open cell puts each meniscus 0.4 cells beyond the flooded
    cells' faces: the width grows by 0.8 cells, the length by 0.8, the inlet meniscus's
    distance and the rear meniscus by 0.4; the oil is the flooded cells'."""
    grid, X, Y = _ring_grid()
    d = grid.cell
    ring = (np.hypot(X, Y) < 6 * A) & ~grid.island
    faces = region_metrics(ring, grid, A, 1.5 * A)
    sub = region_metrics(ring, grid, A, 1.5 * A, fill=np.full(ring.shape, 0.4))
    for key, cells in (("flooded_width_over_a", 0.8), ("flooded_length_over_a", 0.8),
                       ("inlet_meniscus_distance_over_a", 0.4),
                       ("rear_meniscus_x_over_a", 0.4)):
        assert sub[key] - faces[key] == pytest.approx(cells * d / A), key
    assert sub["oil_volume_m3"] == faces["oil_volume_m3"]


@pytest.mark.parametrize("key, value, words", [
    ("cell", -1.0, "cell = -1.0 is out of range"),
    ("contact_angle", 95.0, "contact_angle = 95.0 is out of range: must be in [0, 90) deg"),
    ("supply", -1e-6, "supply = -1e-06 is out of range: must be >= 0 m"),
    ("x_range", (0.0, 19 * A), "x_range"),
    ("receding_meniscus", 3.0, "receding_meniscus = 3.0 is out of range: must be 'static', "
                               "'bretherton' or a factor in [0.5, 2]"),
    ("normal_length", 1e-9, "normal_length = 1e-09 is out of range: must be None or in"),
    ("advancing_angle", 10.0, "advancing_angle = 10.0 is out of range: must be None or in "
                              "[15, 90) deg"),
])
def test_bad_parameters_are_refused_by_name_and_range(key, value, words):
    with pytest.raises(ValueError, match=words.replace("(", r"\(").replace(")", r"\)")
                       .replace("[", r"\[")):
        ball_problem(**{key: value})


def test_a_saved_state_starts_a_run_where_it_left_off(tmp_path):
    """`ehlfoam thin-film --start`: a state written by a run, read back, starts the
    next one with the same oil in the same cells, on its grid or a finer one."""
    from ehlfoam.thinfilm.state import load_state, save_state

    sol = solve_thin_film(ball_problem(), transits_max=2, tolerance=0.0, transit_length=10 * A)
    save_state(sol, tmp_path / "state.npz")
    start = load_state(tmp_path / "state.npz")
    again = solve_thin_film(ball_problem(), transits_max=0, start=start)
    np.testing.assert_array_equal(again.flooded, sol.flooded)
    np.testing.assert_allclose(again.content, sol.content, rtol=1e-12, atol=0)
    finer = solve_thin_film(ball_problem(cell=0.2 * A), transits_max=0, start=start)
    assert finer.metrics(A)["oil_volume_m3"] == pytest.approx(sol.metrics(A)["oil_volume_m3"],
                                                              rel=0.05)


def test_oil_fraction_at_reads_the_cell_holding_a_point_on_either_side_of_the_axis():
    """ThinFilmSolution.oil_fraction_at, what a 3D case starts from: 1 in flooded cells,
    c / h behind, the same at -y as at y (the model's half domain), the nearest open cell's
    inside the island, NaN beyond the grid's edges."""
    d = 1.0
    x, y = d * (np.arange(6) + 0.5), d * (np.arange(3) + 0.5)
    X, Y = np.meshgrid(x, y)
    island = (X < 1) & (Y < 1)
    h = np.where(island, np.nan, 2.0)
    flooded = (X < 3) & ~island
    sol = ThinFilmSolution(
        grid=Grid(x=x, y=y, h=h, hx=h[:, 1:], hy=h[1:], h_side=h[-1], island=island),
        p=np.zeros(h.shape), content=np.where(flooded, 2.0, 0.5), flooded=flooded, time=0.0,
        steps=0, flux_in=0.0, flux_out=0.0, steady=False, island_radius=1.0)
    got = sol.oil_fraction_at(np.array([2.2, 4.6, 4.6, 0.3, 6.4, 2.0]),
                              np.array([0.4, 1.2, -1.2, 0.2, 1.0, 3.4]))
    np.testing.assert_allclose(got[:4], [1.0, 0.25, 0.25, 1.0])
    assert np.isnan(got[4]) and np.isnan(got[5])
