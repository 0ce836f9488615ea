"""bench/film_deposition.py's strip: its columns follow the gap, and a bridge fed on it runs
in the real OpenFOAM, keeps its rear meniscus where it was put and lays films behind it."""

from __future__ import annotations

import numpy as np
import pytest
from foamlib import FoamFile

from bench.film_deposition import columns, measure, strip_mesh, write_strip_case, x_at_gap
from generator.case_spec import make_case_spec
from generator.gap_source import load_gap
from runs.foam_runtime import FoamRuntime
from tiny import SMALL


@pytest.fixture(scope="module")
def strip():
    spec = make_case_spec(SMALL)
    gap, _ = load_gap(spec.contact)
    a = spec.a
    return spec, gap, a, strip_mesh(spec, gap, 3 * a, 10 * a, 0.5 * a)


def test_the_strip_columns_hold_the_gap_and_the_oil(strip):
    spec, gap, a, mesh = strip
    x, h, oil = columns(mesh, np.ones(mesh.n_cells))
    assert len(x) == 14 and mesh.n_cells == 14 * SMALL["mesh"]["n_layers"]
    assert np.allclose(x / a, np.arange(3.25, 10, 0.5))
    # the gap of each column, but the last, whose nodes lean one-sidedly
    assert np.allclose(h[:-1], gap(x, np.zeros_like(x))[:-1], rtol=0.01)
    assert np.allclose(oil, h)
    half = np.where(mesh.cell_centres[:, 0] < 6 * a, 1.0, 0.0)
    assert np.allclose(columns(mesh, half)[2], np.where(x < 6 * a, h, 0.0))
    assert {p.name: p.type for p in mesh.patches}["side"] == "empty"
    assert mesh.patch("supply").size == SMALL["mesh"]["n_layers"]


def test_where_the_gap_is_h_and_where_no_film_was_measured(strip):
    spec, gap, a, mesh = strip
    h8 = float(gap(np.array([8 * a]), np.array([0.0]))[0])
    assert x_at_gap(gap, h8, 3 * a, 10 * a) == pytest.approx(8 * a, rel=1e-6)
    # no film measured (a failed run): NaN, not a root finder's error
    assert np.isnan(x_at_gap(gap, float("nan"), 3 * a, 10 * a))
    # a gap outside the range
    assert np.isnan(x_at_gap(gap, 10 * h8, 3 * a, 10 * a))


def test_a_fed_bridge_runs_and_lays_films_behind_its_rear_meniscus(strip, tmp_path):
    spec, gap, a, mesh = strip
    case = tmp_path / "strip"
    dt = write_strip_case(spec, case, mesh, x_bridge=7 * a, film=2e-6, dx=0.5 * a,
                          end_time=0.02, write_interval=0.01)
    assert 0 < dt < 0.01
    assert FoamFile(case / "system" / "controlDict")["maxDeltaT"] == pytest.approx(dt)
    FoamRuntime.from_environment().run("interFoam", cwd=case, log_path=case / "log.interFoam")
    rows = measure(case, mesh, a, 10 * a)
    assert [r["t_s"] for r in rows] == pytest.approx([0.01, 0.02])
    last = rows[-1]
    assert 6.5 < last["x_rear_over_a"] < 7.5            # a bridge, not drained nor spilled
    assert 0 < last["film_m"] < 0.3 * last["gap_rear_m"]   # the walls carry films out
    assert last["oil_per_width_m2"] > 0
