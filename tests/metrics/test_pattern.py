"""Flow-pattern metrics (ehlfoam.metrics.pattern) on synthetic alpha fields with known answers.

The fields are smooth steps (tanh, width 0.2 a) of analytic signed distances,
sampled at scattered "cell centres" (a jittered grid, or uniform random
points) of a half domain a = 1.371e-4 m, island 1.5 a, x in [-6a, 12a],
y in [0, 6a], with a slight over/undershoot of [0, 1] and a little noise.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ehlfoam.metrics.pattern import (Geometry, Raster, flooded_widths_at, flow_pattern, meniscus_contours, raster)

A = 1.371e-4
GEOM = Geometry(a=A, island_radius=1.5 * A, x_min=-6 * A, x_max=12 * A, y_max=6 * A)
FULL = Geometry(a=A, island_radius=1.5 * A, x_min=-6 * A, x_max=12 * A, y_max=6 * A, symmetric=False)
WIDTH = 0.2 * A  # transition width of the synthetic alpha steps
TOL = 0.06  # lengths over a: about a pixel (a/20) plus the sampling error


def centres(geom: Geometry = GEOM, h: float = A / 6, seed: int = 0, kind: str = "jitter"):
    """Scattered cell centres (x, y) in the domain, none inside the island."""
    rng = np.random.default_rng(seed)
    if kind == "jitter":
        xs = np.arange(geom.x_min + h / 2, geom.x_max, h)
        ys = np.arange(geom.y_min + h / 2, geom.y_max, h)
        x, y = (g.ravel() for g in np.meshgrid(xs, ys))
        x = x + rng.uniform(-0.35, 0.35, x.size) * h
        y = y + rng.uniform(-0.35, 0.35, y.size) * h
    else:
        n = int((geom.x_max - geom.x_min) * (geom.y_max - geom.y_min) / h**2)
        x = rng.uniform(geom.x_min, geom.x_max, n)
        y = rng.uniform(geom.y_min, geom.y_max, n)
    keep = x**2 + y**2 > geom.island_radius**2 * 1.0001
    return x[keep], y[keep]


def alpha_of(oil_distance: np.ndarray, seed: int = 1) -> np.ndarray:
    """alpha from a signed distance to the oil region (negative inside the oil)."""
    rng = np.random.default_rng(seed)
    alpha = 0.5 * (1.0 - np.tanh(oil_distance / WIDTH))
    return 1.02 * alpha - 0.01 + rng.uniform(-0.005, 0.005, alpha.size)


# Signed distances (negative inside), combined with max (intersection) / min (union).
def ring(x, y, radius=4 * A):
    return np.hypot(x, y) - radius


def box(x, y, x0, x1, half_width):
    return np.maximum.reduce([x0 - x, x - x1, np.abs(y) - half_width])


def open_wake(x, y):
    return np.maximum(ring(x, y), -box(x, y, 0.0, 20 * A, A))


def enclosed_bubble(x, y):
    return np.maximum(ring(x, y, 5 * A), -box(x, y, 0.0, 4 * A, 0.8 * A))


def butterfly(x, y):  # meniscus x_m(y) = -3a + a (1 - (y/2a)^2): nearer the contact on the axis
    return np.maximum(ring(x, y, 5 * A), (-3 * A + A * (1 - (y / (2 * A)) ** 2)) - x)


def bulging(x, y):  # meniscus x_m(y) = -3a - a (1 - (y/2a)^2): upstream on the axis
    return np.maximum(ring(x, y, 5 * A), (-3 * A - A * (1 - (y / (2 * A)) ** 2)) - x)


def starved(x, y):  # butterfly plus an upstream air channel reaching the contact
    return np.maximum(butterfly(x, y), -box(x, y, -20 * A, 0.0, 0.5 * A))


def pattern(field, geom=GEOM, **kw):
    x, y = centres(geom, **kw)
    return flow_pattern(x, y, alpha_of(field(x, y)), geom)


@pytest.fixture(scope="module")
def ring_result():
    return pattern(ring)


def test_closed_ring_is_state_one(ring_result):
    m = ring_result
    assert m["state"] == "I"
    assert m["inlet_meniscus_distance_over_a"] == pytest.approx(3.0, abs=TOL)
    assert m["inlet_meniscus_at_rim"] is False
    assert m["flooded_length_over_a"] == pytest.approx(8.0, abs=2 * TOL)
    assert m["flooded_width_over_a"] == pytest.approx(8.0, abs=2 * TOL)
    assert m["flooded_x_min_over_a"] == pytest.approx(-4.0, abs=TOL)
    assert m["inlet_meniscus_shape"] == "convex"
    assert m["wake_gas_length_over_a"] == 0.0
    assert m["wake_open"] is False and m["inlet_starved"] is False
    assert m["enclosed_bubbles"] == 0
    free_area = 18 * 12 - math.pi * 1.5**2
    expected = (math.pi * (16 - 1.5**2)) / free_area
    assert m["oil_area_fraction"] == pytest.approx(expected, abs=0.01)


def test_output_types_plain_python(ring_result):
    for key, value in ring_result.items():
        assert value is None or type(value) in (float, int, str, bool), key
        if isinstance(value, float):
            assert math.isfinite(value), key


def test_unstructured_centres_same_answers(ring_result):
    m = pattern(ring, kind="random", h=A / 7, seed=5)
    assert m["state"] == "I"
    for key in ("inlet_meniscus_distance_over_a", "flooded_length_over_a", "flooded_width_over_a"):
        assert m[key] == pytest.approx(ring_result[key], abs=2 * TOL), key
    assert m["inlet_meniscus_shape"] == "convex"


def test_open_wake_is_state_two():
    m = pattern(open_wake)
    assert m["state"] == "II"
    assert m["wake_open"] is True and m["inlet_starved"] is False
    assert m["wake_gas_length_over_a"] == pytest.approx(11.0, abs=TOL)
    assert m["inlet_meniscus_distance_over_a"] == pytest.approx(3.0, abs=TOL)
    assert m["inlet_meniscus_shape"] == "convex"
    # the flooded ring ends downstream where the channel edge |y| = a cuts r = 4a
    assert m["flooded_length_over_a"] == pytest.approx(4 + math.sqrt(15), abs=2 * TOL)
    assert m["flooded_width_over_a"] == pytest.approx(8.0, abs=2 * TOL)
    assert m["enclosed_bubbles"] == 0


def test_clearance_to_the_nearest_open_boundary():
    # the ring of radius 4 a in x in [-6, 12] a, |y| <= 6 a: 2 a from the upstream edge
    # and from the sides, a tie named "side"
    m = pattern(ring)
    assert m["flooded_clearance_over_a"] == pytest.approx(2.0, abs=TOL)
    assert m["flooded_nearest_boundary"] == "side"
    # shifted 1 a upstream: 1 a from the upstream edge
    m = pattern(lambda x, y: ring(x + A, y))
    assert m["flooded_clearance_over_a"] == pytest.approx(1.0, abs=TOL)
    assert m["flooded_nearest_boundary"] == "upstream"
    # a region reaching back to 11.5 a: half an a from the outlet
    m = pattern(lambda x, y: np.minimum(ring(x, y), box(x, y, 0.0, 11.5 * A, 2 * A)))
    assert m["flooded_clearance_over_a"] == pytest.approx(0.5, abs=TOL)
    assert m["flooded_nearest_boundary"] == "outlet"
    # one 5.5 a wide each side: half an a from the side, also in the full domain
    wide = lambda x, y: np.minimum(ring(x, y), box(x, y, -2 * A, 2 * A, 5.5 * A))  # noqa: E731
    for geom in (GEOM, FULL):
        m = pattern(wide, geom)
        assert m["flooded_clearance_over_a"] == pytest.approx(0.5, abs=TOL)
        assert m["flooded_nearest_boundary"] == "side"


def test_enclosed_bubble_behind_contact_is_state_one():
    m = pattern(enclosed_bubble)
    assert m["state"] == "I"
    assert m["enclosed_bubbles"] == 1
    assert m["wake_open"] is False
    assert m["wake_gas_length_over_a"] == pytest.approx(3.0, abs=TOL)
    assert m["flooded_length_over_a"] == pytest.approx(10.0, abs=2 * TOL)


def test_detached_bubble_not_wake_gas():
    def field(x, y):
        return np.maximum(ring(x, y, 5 * A), -box(x, y, 2.5 * A, 4 * A, 0.5 * A))

    m = pattern(field)
    assert m["state"] == "I"
    assert m["enclosed_bubbles"] == 1
    assert m["wake_gas_length_over_a"] == 0.0


def test_air_bubbles_ahead_of_the_contact_are_not_the_inlet_meniscus():
    # bubbles the oil carries toward the contact: one on the axis 1.5 a ahead of the island
    # and one against its inlet rim; the meniscus that bounds the outer air stays at 4 a
    def field(x, y):
        return np.maximum.reduce([bulging(x, y), -box(x, y, -3.3 * A, -2.7 * A, 0.3 * A),
                                  -box(x, y, -1.8 * A, -1.2 * A, 0.3 * A)])

    m = pattern(field)
    assert m["state"] == "I" and m["enclosed_bubbles"] == 2
    assert m["inlet_meniscus_at_rim"] is False
    assert m["inlet_meniscus_distance_over_a"] == pytest.approx(3.0, abs=TOL)
    assert m["inlet_meniscus_shape"] == "convex"
    assert m["inlet_meniscus_c2"] == pytest.approx(pattern(bulging)["inlet_meniscus_c2"])


def test_off_axis_bubble_counts_twice_in_full_picture():
    def field(x, y):
        return np.maximum(ring(x, y, 5 * A), -box(x, y - 3 * A, -1 * A, 1 * A, 0.5 * A))

    assert pattern(field)["enclosed_bubbles"] == 2


def test_concave_butterfly_meniscus():
    m = pattern(butterfly)
    assert m["inlet_meniscus_shape"] == "concave"
    assert m["inlet_meniscus_c2"] == pytest.approx(-0.25, abs=0.05)
    assert m["inlet_meniscus_distance_over_a"] == pytest.approx(1.0, abs=TOL)


def test_convex_counterpart():
    m = pattern(bulging)
    assert m["inlet_meniscus_shape"] == "convex"
    assert m["inlet_meniscus_c2"] == pytest.approx(0.25, abs=0.05)
    assert m["inlet_meniscus_distance_over_a"] == pytest.approx(3.0, abs=TOL)


def test_starved_inlet_is_state_two_concave():
    m = pattern(starved)
    assert m["state"] == "II"
    assert m["inlet_starved"] is True and m["wake_open"] is False
    assert m["inlet_meniscus_at_rim"] is True
    assert m["inlet_meniscus_distance_over_a"] == pytest.approx(0.5)
    assert m["inlet_meniscus_shape"] == "concave"


def test_full_domain_matches_mirrored_half():
    x, y = centres(GEOM)
    alpha = alpha_of(open_wake(x, y))
    half = flow_pattern(x, y, alpha, GEOM)
    upper = y > 0
    full = flow_pattern(np.r_[x, x[upper]], np.r_[y, -y[upper]], np.r_[alpha, alpha[upper]], FULL)
    assert full == half


@pytest.mark.parametrize("field", [ring, enclosed_bubble, starved])
def test_full_domain_independent_centres(field):
    half = pattern(field)
    full = pattern(field, geom=FULL, seed=3)
    for key, value in half.items():
        if isinstance(value, float) and key != "inlet_meniscus_c2":
            assert full[key] == pytest.approx(value, abs=2 * TOL), key
        elif key != "inlet_meniscus_c2":
            assert full[key] == value, key


def test_all_oil_and_all_gas_do_not_crash():
    x, y = centres()
    oil = flow_pattern(x, y, np.ones_like(x), GEOM)
    assert oil["state"] == "I"
    assert oil["inlet_meniscus_distance_over_a"] is None
    assert oil["inlet_meniscus_shape"] is None
    assert oil["wake_gas_length_over_a"] == 0.0
    assert oil["flooded_length_over_a"] == pytest.approx(18.0)
    assert oil["flooded_width_over_a"] == pytest.approx(12.0)
    assert oil["oil_area_fraction"] == 1.0 and oil["enclosed_bubbles"] == 0

    gas = flow_pattern(x, y, np.zeros_like(x), GEOM)
    assert gas["state"] == "II"
    assert gas["inlet_starved"] and gas["wake_open"]
    assert gas["inlet_meniscus_distance_over_a"] == pytest.approx(0.5)
    assert gas["inlet_meniscus_shape"] is None
    assert gas["flooded_length_over_a"] is None and gas["flooded_width_over_a"] is None
    assert gas["wake_gas_length_over_a"] == pytest.approx(11.0)
    assert gas["oil_area_fraction"] == 0.0


def test_raster_grid_and_island():
    x, y = centres()
    r = raster(x, y, alpha_of(ring(x, y)), GEOM)
    assert isinstance(r, Raster)
    assert r.x[0] == GEOM.x_min and r.x[-1] == pytest.approx(GEOM.x_max)
    assert r.y[0] == -GEOM.y_max and r.y[-1] == GEOM.y_max and r.y[r.axis_row] == 0.0
    assert r.dx == pytest.approx(A / 20, rel=0.01)
    assert np.isnan(r.alpha[r.island]).all()
    assert np.nanmin(r.alpha) >= 0.0 and np.nanmax(r.alpha) <= 1.0
    np.testing.assert_allclose(r.alpha, r.alpha[::-1], atol=0.05)  # mirrored
    coarse = raster(x, y, alpha_of(ring(x, y)), GEOM, cell=A / 10)
    assert coarse.alpha.shape[1] == 181


def test_meniscus_contours_ring():
    x, y = centres()
    lines = meniscus_contours(raster(x, y, alpha_of(ring(x, y)), GEOM))
    assert len(lines) == 1
    line = lines[0]
    assert line.ndim == 2 and line.shape[1] == 2
    np.testing.assert_allclose(np.hypot(line[:, 0], line[:, 1]), 4 * A, atol=0.05 * A)
    assert meniscus_contours(raster(x, y, np.ones_like(x), GEOM)) == []


def test_bad_inputs_raise():
    x, y = centres()
    alpha = alpha_of(ring(x, y))
    with pytest.raises(ValueError, match="alpha"):
        flow_pattern(x, y, alpha[:-1], GEOM)
    with pytest.raises(ValueError, match="^y"):
        flow_pattern(x, y[:-1], alpha, GEOM)
    bad = alpha.copy()
    bad[3] = np.nan
    with pytest.raises(ValueError, match="alpha"):
        flow_pattern(x, y, bad, GEOM)
    bad = x.copy()
    bad[0] = np.inf
    with pytest.raises(ValueError, match="^x"):
        flow_pattern(bad, y, alpha, GEOM)
    with pytest.raises(ValueError, match="alpha"):
        flow_pattern(x, y, 3.0 * alpha, GEOM)
    with pytest.raises(ValueError, match="^x"):
        flow_pattern(x.reshape(-1, 1), y, alpha, GEOM)
    with pytest.raises(ValueError, match="^y"):  # a full-domain mesh passed as a half one
        flow_pattern(np.r_[x, x], np.r_[y, -y], np.r_[alpha, alpha], GEOM)
    with pytest.raises(ValueError, match="^x"):  # millimetres, not metres
        flow_pattern(x * 1e3, y * 1e3, alpha, GEOM)
    with pytest.raises(ValueError, match="threshold"):
        flow_pattern(x, y, alpha, GEOM, threshold=1.5)
    with pytest.raises(ValueError, match="cell"):
        raster(x, y, alpha, GEOM, cell=-1.0)
    with pytest.raises(ValueError, match="^x"):
        flow_pattern(x[:2], y[:2], alpha[:2], GEOM)
    with pytest.raises(ValueError, match="island_radius"):
        Geometry(a=A, island_radius=0.5 * A, x_min=-6 * A, x_max=12 * A, y_max=6 * A)
    with pytest.raises(ValueError, match="^a"):
        Geometry(a=float("nan"), island_radius=A, x_min=-6 * A, x_max=12 * A, y_max=6 * A)
    with pytest.raises(ValueError, match="x_min"):
        Geometry(a=A, island_radius=1.5 * A, x_min=-A, x_max=12 * A, y_max=6 * A)


# ------------------------------------------------------------ the cavitation bubble
def detached_bubble(x, y):  # gas enclosed in the oil but not touching the contact
    return np.maximum(ring(x, y, 5 * A), -box(x, y, 2.5 * A, 4 * A, 0.8 * A))


@pytest.mark.parametrize("field, length, width, enclosed", [
    (enclosed_bubble, 3.0, 1.6, True),      # tip at x = 4a: l = (4a - a)/a; |y| < 0.8 a
    (open_wake, 11.0, None, False),         # runs out at x = 12a and joins the outer air
    (detached_bubble, 0.0, 0.0, False),     # gas, but not attached to the contact exit
    (ring, 0.0, 0.0, False),                # oil all around
])
def test_bubble_metrics_on_known_shapes(field, length, width, enclosed):
    p = pattern(field)
    assert p["bubble_length_over_a"] == pytest.approx(length, abs=TOL)
    assert p["bubble_enclosed"] is enclosed
    if width is not None:
        assert p["bubble_width_over_a"] == pytest.approx(width, abs=TOL)


def test_the_advancing_front_is_the_upstream_edge_off_the_track():
    """On a round region of 4 a, with a track of 2 a: the edge the walls (rolling along +x) run
    into from dry ground is the upstream half of the circle with |y| > 2 a; none of it
    downstream, on the track or inside; a track wider than the region leaves none."""
    from ehlfoam.metrics.pattern import advancing_front

    x, y = centres()
    r = raster(x, y, alpha_of(ring(x, y)), GEOM)
    pts = advancing_front(r, 2 * A)
    assert len(pts) > 20
    radius = np.hypot(pts[:, 0], pts[:, 1])
    assert np.all(np.abs(radius - 4 * A) < 0.15 * A)        # on the meniscus
    assert np.all(pts[:, 0] < 0.3 * A)                      # where the walls come in
    assert np.all(np.abs(pts[:, 1]) > 2 * A)                # off the track
    assert (pts[:, 1] > 0).any() and (pts[:, 1] < 0).any()  # both halves of the picture
    assert len(advancing_front(r, 5 * A)) == 0
    with pytest.raises(ValueError, match="track_half_width"):
        advancing_front(r, -1.0)


def test_flooded_widths_at_follow_a_known_outline():
    """A ring of radius 4 a: the width at x is 2 sqrt(16 a^2 - x^2) (at x = 0 the region's
    width); none beyond it; an oil patch detached from the region does not count."""
    x, y = centres()
    detached = box(x, y, 7 * A, 9 * A, 1.5 * A)
    r = raster(x, y, alpha_of(np.minimum(ring(x, y), detached)), GEOM)
    stations = np.array([-3.0, 0.0, 2.0, 3.5, 8.0]) * A
    widths = flooded_widths_at(r, stations)
    assert widths[-1] is None                              # the patch at 7-9 a is not flooded
    expected = 2.0 * np.sqrt(16.0 - (stations[:-1] / A) ** 2)
    # the nearest raster column is up to half a pixel off the station: where the outline is
    # steep (3.5 a) that moves the width by its slope times half a pixel
    slope = 2.0 * np.abs(stations[:-1] / A) / np.sqrt(16.0 - (stations[:-1] / A) ** 2)
    error = np.abs(np.array(widths[:-1]) / A - expected)
    assert np.all(error <= 2 * TOL + slope * r.dx / A / 2), error
    assert widths[1] / A == pytest.approx(pattern(ring)["flooded_width_over_a"], abs=TOL)


def test_the_extents_across_the_rows_are_those_of_the_transposed_picture():
    """The extents along the rows (axis 0, read row by row) are bitwise those read along
    the columns of the transposed picture, crossings and signed coordinates included; the
    mean leaving NaN out is numpy's nanmean bitwise, with and without NaN."""
    from ehlfoam.metrics.pattern import _extent, _mean
    rng = np.random.default_rng(5)
    for _ in range(100):
        ny, nx = rng.integers(2, 30, size=2)
        alpha = rng.uniform(0.0, 1.0, (ny, nx))
        region = alpha >= 0.5
        region[rng.integers(ny), rng.integers(nx)] = True
        gas = ~region & (rng.uniform(size=(ny, nx)) < 0.8)
        y = np.sort(rng.normal(0.0, 1e-3, ny))
        assert _extent(region, alpha, gas, y, 0.5, axis=0) == _extent(region.T, alpha.T,
                                                                     gas.T, y, 0.5)
        values = alpha.ravel()
        assert _mean(values) == np.nanmean(values)
        values[rng.integers(values.size)] = np.nan
        assert _mean(values) == np.nanmean(values)
