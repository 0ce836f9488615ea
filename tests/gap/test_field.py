"""The exported gap h(x, y) [m] (ehlfoam.gap.field.GapField) of a solved contact.

References: the solver's own film on its grid with the paraboloid swapped for the exact
sphere; the deformation of a point load, w = 2 F / (pi E' r); a direct sum of the exported
pressure over every grid cell; continuity under refinement of the sampling step.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ehlfoam.gap.field import GapField
from ehlfoam.contact.outputs import write_all
from ehlfoam.contact.solver import solve
from ehlfoam.contact.spec import make_spec


@pytest.fixture(scope="module")
def solved():
    r = solve(make_spec(load=20, speed=1.0, temperature=40, grid=129))
    assert r.converged
    return r


@pytest.fixture(scope="module")
def gap(solved):
    return GapField.from_result(solved)


@pytest.fixture(scope="module")
def consts(solved):
    c, s = solved.contact, solved.spec
    return dict(a=c.a, R=c.radius, E=s.modulus, F=s.load, scale=c.a**2 / c.radius,
                h0=solved.mg.H0 * c.a**2 / c.radius)


def sphere(r, R):
    return R - np.sqrt(R * R - r * r)


def test_gap_on_grid_equals_solver_film(solved, gap, consts):
    mg = solved.mg
    a, R = consts["a"], consts["R"]
    X, Y = np.meshgrid(mg.x, mg.y)
    # grid points at least 0.3 a inside the domain edge (outside the blend band)
    d = np.minimum.reduce([X - mg.x[0], mg.x[-1] - X, Y - mg.y[0], mg.y[-1] - Y])
    sel = d >= 0.3
    xm, ym = X[sel] * a, Y[sel] * a
    r = np.hypot(xm, ym)
    expected = mg.H[sel] * consts["scale"] + sphere(r, R) - r**2 / (2 * R)
    got = gap(xm, ym)
    assert got.shape == expected.shape
    assert np.max(np.abs(got / expected - 1)) < 1e-3
    assert np.max(np.abs(got - expected)) < 1e-12  # interpolation at nodes is exact


def test_gap_broadcasts(gap, consts):
    a = consts["a"]
    xs = np.linspace(-3, 3, 7) * a
    ys = np.linspace(-2, 2, 5) * a
    h = gap(xs[None, :], ys[:, None])
    assert h.shape == (5, 7)
    assert gap(xs[2], ys[1]) == pytest.approx(h[1, 2], rel=1e-14)


def _max_jump(gap, a, line, step):
    t = np.arange(line[0], line[1], step)
    x, y = line[2](t), line[3](t)
    return np.abs(np.diff(gap(x * a, y * a))).max()


LINES = {
    # crossing the outlet edge x = 1.5 a (and its blend band) at y = 0.3 a
    "outlet": (1.1, 1.9, lambda t: t, lambda t: 0.3 + 0 * t),
    # crossing the side edge y = 3 a at x = 0.2 a
    "side": (2.6, 3.4, lambda t: 0.2 + 0 * t, lambda t: t),
    # crossing the inlet edge x = -4.5 a on the centreline
    "inlet": (-4.9, -4.1, lambda t: t, lambda t: 0 * t),
    # diagonal through the corner (1.5, 3) a
    "corner": (2.6, 3.4, lambda t: t - 1.5, lambda t: t),
}


@pytest.mark.parametrize("name", sorted(LINES))
def test_gap_continuous_across_edge_and_blend(gap, consts, name):
    a = consts["a"]
    jumps = [_max_jump(gap, a, LINES[name], s) for s in (1e-2, 1e-3, 1e-4, 1e-5)]
    # a discontinuity would leave max|dh| at the jump size whatever the step
    for coarse, fine in zip(jumps, jumps[1:]):
        assert fine < 0.2 * coarse
    assert jumps[-1] < 1e-4 * consts["scale"]  # < 0.2 pm for 1.4 nm steps


def test_far_field_is_point_load(gap, consts):
    a, R, E, F, h0 = (consts[k] for k in ("a", "R", "E", "F", "h0"))
    errs = {}
    for rr in (5.0, 10.0):
        e = []
        for th in np.linspace(0, 2 * np.pi, 8, endpoint=False):
            x, y = rr * a * math.cos(th), rr * a * math.sin(th)
            w_point = 2 * F / (math.pi * E * rr * a)
            w = gap(x, y) - h0 - sphere(rr * a, R)
            e.append(abs(w / w_point - 1))
        errs[rr] = max(e)
    assert errs[5.0] < 0.02
    assert errs[10.0] < 0.01
    assert errs[10.0] < errs[5.0]


def test_far_field_equals_direct_sum_of_pressure(solved, gap, consts):
    """Outside the domain h - h0 - sphere is the deformation of the exported pressure."""
    mg, c = solved.mg, solved.contact
    a, R, E, h0 = consts["a"], consts["R"], consts["E"], consts["h0"]
    X, Y = np.meshgrid(mg.x * a, mg.y * a)
    p = mg.P * c.p_hertz
    dA = ((mg.x[1] - mg.x[0]) * a) ** 2
    keep = p > 0
    pts = [(1.5, 0.0), (1.5, 1.0), (-4.5, 0.0), (0.0, 3.0), (2.0, 2.0), (-5.0, 0.0),
           (0.0, -5.0), (-3.0, -3.1), (10.0, 3.0)]
    for xa, ya in pts:
        xq, yq = xa * a, ya * a
        w_ref = 2 / (math.pi * E) * np.sum(p[keep] * dA / np.hypot(xq - X[keep], yq - Y[keep]))
        w = gap(xq, yq) - h0 - sphere(math.hypot(xq, yq), R)
        assert w == pytest.approx(w_ref, rel=1e-3), (xa, ya)


def test_gap_positive_out_to_1mm(gap):
    s = np.linspace(-1e-3, 1e-3, 161)
    X, Y = np.meshgrid(s, s)
    h = gap(X, Y)
    assert np.all(np.isfinite(h))
    assert h.min() > 0
    # far from the contact the gap is dominated by the sphere: 1 mm off-centre ~ 52 um
    assert gap(1e-3, 0.0) == pytest.approx(sphere(1e-3, 9.525e-3), rel=0.05)


def test_gap_outside_ball_refused(gap):
    with pytest.raises(ValueError):
        gap(0.0, 9.6e-3)


def test_load_from_output_dir_matches(solved, gap, consts, tmp_path_factory):
    out = tmp_path_factory.mktemp("gapout")
    write_all(solved, out)
    g2 = GapField.load(out)
    a = consts["a"]
    rng = np.random.default_rng(3)
    pts = np.concatenate([rng.uniform(-4.4, 1.4, (200, 2)), rng.uniform(-12, 12, (200, 2))])
    pts[:200, 1] *= 2.9 / 4.4
    h1 = gap(pts[:, 0] * a, pts[:, 1] * a)
    h2 = g2(pts[:, 0] * a, pts[:, 1] * a)
    assert np.allclose(h2, h1, rtol=1e-9, atol=0)


def test_a_linked_precalc_is_read_once_and_a_new_one_again(solved, tmp_path_factory):
    """A case's precalc is a hard link to the cache's: the same file, read once in a
    process; a precalc written anew (a new file) is read again."""
    from ehlfoam._io import link_tree

    cache = tmp_path_factory.mktemp("cache")
    write_all(solved, cache)
    case = tmp_path_factory.mktemp("case") / "precalc"
    link_tree(cache, case)
    assert (case / "solution.npz").stat().st_ino == (cache / "solution.npz").stat().st_ino
    assert GapField.load(case) is GapField.load(cache)
    other = tmp_path_factory.mktemp("other")
    write_all(solved, other)
    assert GapField.load(other) is not GapField.load(cache)
