"""bench/film_deposition.py's strip: its columns follow the gap, and a bridge fed on it runs
in the real OpenFOAM, keeps its rear meniscus where it was put and lays films behind it."""

from __future__ import annotations

import numpy as np
import pytest
from foamlib import FoamFieldFile, FoamFile

from bench.film_deposition import (columns, lateral_speed, measure, slab_mesh, strip_mesh,
                                   supply_cell_size, write_strip_case, x_at_gap)
from ehlfoam.spec.case import make_case_spec
from ehlfoam.gap.source import load_gap
from ehlfoam.foam.runtime import FoamRuntime
from tests.tiny import SMALL


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


def test_cells_finer_than_the_columns_lean_at_the_supply_stay_right_side_out():
    """The normal columns lean upstream by h h' / 2 at the ball, 0.037 a at 9 a on the nominal
    gap: uniform cells of 0.035 a from there turned the first ones inside out (the strip then
    diverged within 2 ms); the strip and the slab now grow their cells near the supply."""
    spec = make_case_spec({"mesh": {"resolution": "fine"}})
    gap, _ = load_gap(spec.contact)
    a = spec.a
    assert 0.035 * a < supply_cell_size(gap, 9 * a) < 0.1 * a
    strip = strip_mesh(spec, gap, 9 * a, 12 * a, 0.035 * a)
    assert strip.cell_volumes.min() > 0
    x, h, _ = columns(strip, np.zeros(strip.n_cells))
    assert np.isclose(x[-1] - x[-2], 0.035 * a, rtol=0.05)          # dx where it is read
    assert x[1] - x[0] > 1.5 * 0.035 * a                              # coarser at the supply
    with pytest.raises(ValueError, match="aligned slab cells"):
        slab_mesh(spec, gap, 9 * a, 12 * a, 0.035 * a, 0.2 * a, free=False)


@pytest.mark.parametrize("free", [True, False])
def test_a_slab_holds_the_gap_between_two_planar_symmetry_planes(strip, free):
    spec, gap, a, _ = strip
    mesh = slab_mesh(spec, gap, 3 * a, 10 * a, 0.5 * a, 2 * a, free=free)
    patches = {p.name: p.type for p in mesh.patches}
    assert patches["side"] == patches["symmetry"] == "symmetryPlane"
    for name, sign in (("side", 1.0), ("symmetry", -1.0)):
        normals = mesh.face_areas[mesh.patch_slice(name)]
        assert np.all(sign * normals[:, 1] > 0) and np.allclose(normals[:, [0, 2]], 0.0)
    assert mesh.cell_volumes.min() > 0
    edges = np.linspace(3 * a, 10 * a, 15)
    x, h, oil = columns(mesh, np.ones(mesh.n_cells), edges)
    assert np.allclose(h[1:-1], gap(x, np.zeros_like(x))[1:-1], rtol=0.02)
    assert np.allclose(oil, h)
    # the footprint covers the slab once: the oil of a full gap is the slab's volume
    assert np.sum(oil * np.diff(edges)) * 2 * a == pytest.approx(mesh.cell_volumes.sum())
    if not free:     # rows of square cells: every edge on the disc along x or along y
        disc = mesh.points[mesh.faces[mesh.patch_slice("disc")]][..., :2]
        edges = np.roll(disc, -1, axis=1) - disc
        assert np.allclose(np.min(np.abs(edges), axis=2), 0.0, atol=1e-9 * a)
        assert mesh.n_cells == 14 * 4 * SMALL["mesh"]["n_layers"]


def test_the_lateral_current_is_the_rms_speed_across_y_within_a_of_the_rear_meniscus(strip,
                                                                                      tmp_path):
    """A slab's flow should not vary in y: its speed across y around the rear meniscus is a
    spurious current (0.46 u rms at the default step on the fine walls, 0.002 u at half
    of it, docs/cases.md). Read on a field written by hand: 0.3 u across y within a of x_r,
    u elsewhere (which must not count), and a wall speed along x that must not count either."""
    spec, gap, a, _ = strip
    mesh = slab_mesh(spec, gap, 3 * a, 10 * a, 0.5 * a, 2 * a, free=True)
    u, x_r = 0.008, 6.2 * a
    near = np.abs(mesh.cell_centres[:, 0] - x_r) < a
    velocity = np.zeros((mesh.n_cells, 3))
    velocity[:, 0] = u
    velocity[:, 1] = np.where(near, np.where(mesh.cell_centres[:, 1] > 0, 0.3, -0.3) * u, u)
    field = FoamFieldFile(tmp_path / "U")
    field["dimensions"] = FoamFieldFile.DimensionSet(length=1, time=-1)
    field.internal_field = velocity
    field.boundary_field = {}
    assert near.sum() > 20 and (~near).sum() > 20
    assert lateral_speed(tmp_path, mesh, x_r, a, u) == pytest.approx(0.3, rel=1e-9)
    velocity[near, 1] *= np.linspace(0.0, 2.0, near.sum())     # no longer uniform: by volume
    field.internal_field = velocity
    w = mesh.cell_volumes[near]
    expected = np.sqrt(np.sum(w * velocity[near, 1] ** 2) / w.sum()) / u
    assert lateral_speed(tmp_path, mesh, x_r, a, u) == pytest.approx(expected, rel=1e-9)


def test_strip_options_edit_the_written_case_and_name_it(strip, tmp_path):
    """The strip benches' --edit changes the written case's system/ files before it runs (here
    the interface normal's gradient), --set and --edit name the case's folder, and --reuse
    takes a finished run instead of running it again."""
    import argparse

    from bench.film_deposition import add_strip_options, options_suffix, run_or_reuse

    spec, gap, a, mesh = strip
    ap = argparse.ArgumentParser()
    add_strip_options(ap, [0.5], "coarse", 0.01, 1, tmp_path)
    args = ap.parse_args(["--set", "run.capillary_safety=0.5",
                          "--edit", "fvSchemes:gradSchemes/nHat=pointCellsLeastSquares",
                          "--edit", "fvSchemes:divSchemes/div(phirb,alpha)=Gauss "
                                    "interfaceCompression"])
    args.film = 2e-6
    assert options_suffix(args) == ("_capillary_safety0.5_nHatpointCellsLeastSquares"
                                    "_div(phirb,alpha)GaussinterfaceCompression")
    case = tmp_path / "strip"
    runtime = FoamRuntime.from_environment()
    run = run_or_reuse(runtime, spec, case, mesh, 7 * a, args, 0.5 * a)
    assert run["status"] == "ok" and run["steps"] > 0
    schemes = FoamFile(case / "system" / "fvSchemes")
    assert schemes["gradSchemes"]["nHat"] == "pointCellsLeastSquares"
    assert tuple(schemes["divSchemes"]["div(phirb,alpha)"]) == ("Gauss", "interfaceCompression")
    (case / "log.interFoam").unlink()
    args.reuse = True
    assert run_or_reuse(runtime, spec, case, mesh, 7 * a, args, 0.5 * a) == run
    assert not (case / "log.interFoam").exists()         # taken, not run again
