"""The contact angle a meniscus's pressure jump implies (bench/meniscus_pressure.py):
Young-Laplace across the gap and along the outline, inverted."""

from __future__ import annotations

import math

import pytest

from bench.meniscus_pressure import apparent_angle

SIGMA, GAP = 0.030, 70e-6   # N/m, m: the nominal oil, the gap beside the region's widest point


@pytest.mark.parametrize("theta, radius", [(15.0, math.inf), (25.0, 7 * 137e-6), (60.0, 1e-3)])
def test_the_angle_of_a_young_laplace_jump_is_recovered(theta, radius):
    kappa = 0.0 if math.isinf(radius) else 1.0 / radius
    p_air = 3.0
    p_oil = p_air - 2.0 * SIGMA * math.cos(math.radians(theta)) / GAP + SIGMA * kappa
    assert apparent_angle(p_oil, p_air, GAP, SIGMA, kappa) == pytest.approx(theta, abs=1e-9)


def test_the_outline_curvature_counts_and_a_jump_beyond_any_angle_is_nan():
    p_oil = -2.0 * SIGMA / GAP          # a fully wetting meniscus, straight in the plane
    assert apparent_angle(p_oil, 0.0, GAP, SIGMA) == pytest.approx(0.0, abs=1e-6)
    # the same jump on an outline bulging out needs more suction than any angle gives
    assert math.isnan(apparent_angle(p_oil, 0.0, GAP, SIGMA, 1.0 / (7 * 137e-6)))
    assert math.isnan(apparent_angle(+2.5 * SIGMA / GAP, 0.0, GAP, SIGMA))


def test_the_angles_chart_draws_every_ray_asked_for(tmp_path):
    from bench.meniscus_pressure import plot_angles

    def ray(deg, cell, angle):
        return {"angle_deg": deg, "meniscus_over_a": 7.0, "cell_over_a": cell,
                "apparent_angle_deg": angle}

    results = [{"case": "runs/x/coarse", "time_s": 0.1, "wall_angle_deg": 15.0,
                "rays": [ray(60, 0.24, 18.0), ray(90, 0.24, float("nan"))]},
               {"case": "runs/x/fine", "time_s": 0.1, "wall_angle_deg": 15.0,
                "rays": [ray(60, 0.06, 30.0), ray(90, 0.03, 35.0), ray(0, 0.06, 36.0)]}]
    out = tmp_path / "angles.png"
    plot_angles(results, out, rays=(60, 90))
    import matplotlib.image

    image = matplotlib.image.imread(out)
    assert image.shape[0] > 300 and image.shape[1] > 500
    # no run has a meniscus on the 45 deg ray: nothing to draw is an error, not an empty chart
    with pytest.raises(ValueError, match="no ray"):
        plot_angles(results, tmp_path / "none.png", rays=(45,))


def test_series_group_runs_by_their_case_path_and_a_missing_run_is_an_error(tmp_path):
    from bench.meniscus_pressure import group_series, plot_angles

    def run(case, cell, angle):
        return {"case": case, "time_s": 0.1, "wall_angle_deg": 43.0,
                "rays": [{"angle_deg": 60, "meniscus_over_a": 8.0, "cell_over_a": cell,
                          "apparent_angle_deg": angle}]}

    results = [run("runs/slip/coarse", 0.12, 38.0), run("runs/noslip/coarse", 0.12, 18.0),
               run("runs/slip/fine", 0.03, 42.0), run("runs/other/medium", 0.06, 30.0)]
    groups = group_series(results, ["slip, 43 deg=slip/fine,slip/coarse", "no slip=noslip/coarse"])
    assert [(label, [r["case"] for r in runs]) for label, runs in groups] == [
        ("slip, 43 deg", ["runs/slip/fine", "runs/slip/coarse"]),
        ("no slip", ["runs/noslip/coarse"])]
    with pytest.raises(ValueError, match="no run ends with 'slip/medium'"):
        group_series(results, ["slip=slip/coarse,slip/medium"])
    with pytest.raises(ValueError, match="LABEL=SUFFIX"):
        group_series(results, ["slip/coarse"])
    out = tmp_path / "series.png"
    plot_angles(results, out, rays=(60,), series=["slip=slip/coarse,slip/fine"])
    assert out.stat().st_size > 10_000
