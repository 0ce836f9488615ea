"""The case machinery with the real OpenFOAM: spec -> case -> checkMesh -> run -> metrics.

One small case (coarse mesh, a cheap precalc) is built once per session; each test that runs
the solver works on its own copy.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from foamlib import FoamFieldFile, FoamFile

from ehlfoam.errors import SpecError
from ehlfoam.spec.case import make_case_spec
from ehlfoam.case.geometry import BALL_WALL_STEPS_LIMIT, load_geometry, mesh_warnings
from ehlfoam.case.timestep import capillary_time_step
from ehlfoam.case.writer import CaseExists, write_case
from ehlfoam.mesh import refinement_size
from ehlfoam.run import fields as case_fields
from ehlfoam.cli.case import parse_value
from ehlfoam.foam.runtime import FoamRuntime
from ehlfoam.report.case_data import read_history
from ehlfoam.run.monitor import (FRONT_CELL_WARNING, OIL_FLUX_APPROXIMATE, OIL_FLUX_EXACT, front_cell_warnings, rear_cell_warnings, run_case)
from ehlfoam.run.watch import HANG_POLLS, POLL_S
from ehlfoam.notices import to_text
from tests.hostile import procs
from tests.tiny import SMALL

ROOT = Path(__file__).resolve().parents[2]
EHLFOAM = [str(Path(sys.executable).parent / "ehlfoam")]


@pytest.fixture(scope="session")
def small_case(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("cases") / "small"
    write_case(make_case_spec(SMALL), out)
    return out


def _copy(case: Path, tmp_path: Path) -> Path:
    dst = tmp_path / case.name
    shutil.copytree(case, dst)
    return dst


# ------------------------------------------------------------ bad input
@pytest.mark.parametrize("table, text, expected", [
    ("[contact]\nspeed = -0.01\n", "contact.speed = -0.01", "valid range 0 < contact.speed"),
    ("[supply]\nlayer = 1e-6\n", "supply.layer: unknown key", "disc_layer"),
    ("[mesh]\nresolution = \"ultra\"\n", "mesh.resolution = 'ultra'", "'coarse', 'medium' or 'fine'"),
    ("[domain]\nisland_radius = 9.0\n", "island_radius = 9 a", "nearest boundary"),
    ("[mesh]\npolar_radius = 7.9\n", "mesh.polar_radius = 7.9 a", "(1.5, 7.6] a"),
    ("[mesh]\npolar_radius = \"ring\"\n", "mesh.polar_radius = 'ring'", '"auto"'),
    ("[mesh]\ncolumns = \"slanted\"\n", "mesh.columns = 'slanted'", "'normal' or 'vertical'"),
    ("[contact]\ntemperature = 99.0\n", "temperature = 99 C", "valid range 25 to 60 C"),
    ("[run]\nsteady_tolerance = 2.0\n", "run.steady_tolerance = 2.0", "steady_tolerance < 1"),
    ("[run]\nalpha_subcycles = 0\n", "run.alpha_subcycles = 0", "1 <= run.alpha_subcycles"),
    ("scene = \"gas-release\"\n[physics]\ngas_release_rate = 0.0\n",
     "physics.gas_release_rate = 0.0", "0 < physics.gas_release_rate"),
    ("scene = \"gas-release\"\n[run]\nair_viscosity_factor = 20.0\n",
     "run.air_viscosity_factor = 20", "leave it at 100"),
    ("scene = \"gas-release\"\n[physics]\nisotropic_compression = 1.0\n",
     "physics.isotropic_compression = 1 does not apply", "valid range: 0"),
    ("scene = \"gas-release\"\n[physics]\ngas_dissolution_rate = 100.0\n",
     "physics.gas_dissolution_rate = 100 1/s", 'supply.mode = "submerged"'),
    ("[supply]\nmode = \"bath\"\n", "supply.mode = 'bath'", "'submerged'"),
    ("[mesh]\nwall_cell = 1e-3\n", "mesh.wall_cell = 0.001",
     "valid range 1e-08 <= mesh.wall_cell <= 0.0001"),
    ("[mesh]\nwall_cell = 1e-6\nwall_grading = 20.0\n", "wall_grading (20) and wall_cell (1e-06 m)",
     "set one of"),
])
def test_bad_spec_fails_before_anything_is_written(tmp_path, table, text, expected):
    spec = tmp_path / "bad.toml"
    spec.write_text(table)
    out = tmp_path / "case"
    proc = subprocess.run([*EHLFOAM, "case", str(spec), "--out", str(out)],
                          capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 2, proc.stderr
    assert text in proc.stderr and expected in proc.stderr, proc.stderr
    assert not out.exists()


def test_set_none_clears_an_optional_key_and_is_refused_for_a_required_one(tmp_path):
    """`--set KEY=none`: an optional key goes back to "not set" (the spec file's polar ring
    off); a required key is refused by name before anything is written."""
    spec = make_case_spec({"mesh": {"resolution": "coarse", "polar_radius": 6.8}},
                          **{"mesh.polar_radius": parse_value("none")})
    assert spec.mesh.polar_radius is None
    path = tmp_path / "ring.toml"
    path.write_text("[mesh]\npolar_radius = 6.8\n")
    out = tmp_path / "case"
    proc = subprocess.run([*EHLFOAM, "case", str(path), "--out", str(out),
                           "--set", "contact.speed=none"], capture_output=True, text=True)
    assert proc.returncode == 2 and "contact.speed" in proc.stderr, proc.stderr
    assert not out.exists()


def test_polar_ring_is_the_default_and_auto_follows_the_domain():
    """mesh.polar_radius = "auto" (the default) is 0.85 x the nearest boundary: 6.8 a in the
    default domain, 0.85 x 5 a when the side comes in to 5 a; none gives free quads."""
    assert make_case_spec().mesh.polar_radius == "auto"
    assert make_case_spec().polar_radius == pytest.approx(6.8)
    assert make_case_spec(**{"domain.side": 5.0}).polar_radius == pytest.approx(4.25)
    assert make_case_spec(**{"mesh.polar_radius": 5.5}).polar_radius == 5.5
    assert make_case_spec(**{"mesh.polar_radius": parse_value("none")}).polar_radius is None


def test_the_level_reports_the_wall_rule_the_mesh_is_built_with():
    """Under mesh.wall_cell the level's wall grading does not apply, and level() says so
    (it used to report the level's grading beside a mesh graded for the wall cell)."""
    graded = make_case_spec().mesh.level()
    assert graded["wall_cell"] is None and graded["wall_grading"] == 10.0
    one_cell = make_case_spec(**{"mesh.wall_cell": 8e-7}).mesh.level()
    assert one_cell["wall_cell"] == 8e-7 and one_cell["wall_grading"] is None
    assert one_cell["n_layers"] == graded["n_layers"]


def test_spec_defaults_are_the_reference_case():
    spec = make_case_spec()
    assert spec.contact.load == 20.0 and spec.contact.temperature == 40.0
    assert spec.speed == 0.008
    # the reference's Hertzian radius (docs/reference.md#conditions-thesis-table-21)
    assert spec.a == pytest.approx(0.137e-3, rel=0.01)
    assert spec.physics.surface_tension == 0.030 and spec.physics.contact_angle == 15.0
    assert spec.oil_viscosity == pytest.approx(21.6e-3)
    with pytest.raises(SpecError, match="track_half_width"):
        make_case_spec({"supply": {"track_half_width": 0.01}})
    with pytest.raises(SpecError, match=r"supply.track_inner_half_width = 0.0003 m must be in "
                                        r"\[0, 0.0003\) m"):
        make_case_spec({"supply": {"track_half_width": 3e-4, "track_inner_half_width": 3e-4}})


def test_existing_case_is_not_overwritten(small_case):
    with pytest.raises(CaseExists):
        write_case(make_case_spec(SMALL), small_case)


# ------------------------------------------------------------ the case
def test_case_is_complete_and_runs_by_hand_layout(small_case):
    for rel in ("Allrun", "Allclean", "0.orig/U", "0.orig/p_rgh", "0.orig/alpha.oil",
                "constant/polyMesh/faces", "constant/transportProperties", "system/controlDict",
                "system/fvSolution", "precalc/summary.json", "ehlfoam/spec.json"):
        assert (small_case / rel).is_file(), rel
    allrun = (small_case / "Allrun").read_text()
    assert "bin/tools/RunFunctions" not in allrun
    assert not re.search(r"@[A-Z_]+@", allrun)      # every marker filled
    fv = FoamFile(small_case / "system" / "fvSolution")
    assert fv["PIMPLE"]["momentumPredictor"] is False
    geom = load_geometry(small_case)
    assert geom.gap_mismatch < 0.05      # a deliberately coarse mesh; the levels: below
    assert 0 < geom.max_delta_t < 1e-3


def test_time_step_options_reach_the_dictionaries(tmp_path):
    """run.max_courant, max_alpha_courant, pressure_correctors, alpha_subcycles,
    capillary_safety and the interface compression (physics.interface_compression,
    isotropic_compression) are what controlDict and fvSolution say; the capillary limit
    scales with its safety factor."""
    spec = make_case_spec({**SMALL, "run": {**SMALL["run"], "max_courant": 0.7,
                                            "max_alpha_courant": 0.6, "pressure_correctors": 2,
                                            "alpha_subcycles": 4, "capillary_safety": 1.5},
                           "physics": {"interface_compression": 0.25,
                                       "isotropic_compression": 1.0}})
    geom = write_case(spec, tmp_path / "opts")
    with FoamFile(tmp_path / "opts" / "system" / "controlDict") as f:
        assert (f["maxCo"], f["maxAlphaCo"]) == (0.7, 0.6)
        assert f["maxDeltaT"] == pytest.approx(geom.max_delta_t)
    fv_solution = FoamFile(tmp_path / "opts" / "system" / "fvSolution")
    assert fv_solution["PIMPLE"]["nCorrectors"] == 2
    alpha = fv_solution["solvers"]['"alpha.oil.*"']
    assert (alpha["cAlpha"], alpha["icAlpha"], alpha["nAlphaSubCycles"]) == (0.25, 1.0, 4)
    dx = geom.min_cell_size
    assert geom.max_delta_t == pytest.approx(min(capillary_time_step(spec, dx),
                                                 geom.write_interval))
    default = make_case_spec(SMALL)           # capillary_safety 2 (the default)
    assert capillary_time_step(spec, dx) == pytest.approx(
        capillary_time_step(default, dx) * 1.5 / default.run.capillary_safety, rel=1e-12)


@pytest.mark.parametrize("level, ring", [("coarse", False), ("medium", False), ("medium", True)])
def test_meshed_gap_matches_the_gap_export(level, ring):
    """At the resolution levels the meshed gap is the precalc's gap within 1 %, with or
    without the polar ring."""
    from ehlfoam.gap.source import load_gap
    from ehlfoam.mesh import MeshParams, build_base_mesh, extrude, gap_mismatch, size_function

    spec = make_case_spec({**SMALL, "mesh": {"resolution": level}})
    gap, _ = load_gap(spec.contact)
    a, d = spec.a, spec.domain
    params = MeshParams(**spec.domain.box(a).fields(), n_layers=2,
                        polar_radius=0.8 * min(d.upstream, d.downstream, d.side) * a
                        if ring else None)
    mesh = extrude(build_base_mesh(params, size_function(spec)), gap, 2)
    assert gap_mismatch(mesh, gap) < 0.01


def test_a_refinement_box_refines_the_free_quads_inside_it():
    """mesh.refine: quads of about the box's size inside it, the level's outside, the cells
    growing back at REFINE_GROWTH in between; a box that is not a box is refused naming it."""
    from ehlfoam.mesh import REFINE_GROWTH, MeshParams, build_base_mesh, size_function

    def base(spec):
        a = spec.a
        params = MeshParams(**spec.domain.box(a).fields(), n_layers=2,
                            polar_radius=spec.polar_radius * a)
        mesh = build_base_mesh(params, size_function(spec))
        centre = mesh.points[mesh.quads].mean(axis=1) / a
        return centre, np.sqrt(mesh.quad_areas()) / a

    box = {"x_min": 4.0, "x_max": 6.5, "y_min": 0.0, "y_max": 4.5, "size": 0.2}
    plain = make_case_spec(SMALL)
    boxed = make_case_spec({**SMALL, "mesh": {**SMALL["mesh"], "refine": [box]}})
    size = size_function(boxed)
    a = boxed.a
    assert size(5.0 * a, 2.0 * a) == pytest.approx(0.2 * a)
    assert size(5.0 * a, -2.0 * a) == pytest.approx(0.2 * a)          # |y|: the full domain
    assert size(5.0 * a, 5.0 * a) == pytest.approx((0.2 + REFINE_GROWTH * 0.5) * a)
    assert size(-4.0 * a, 0.0) == pytest.approx(size_function(plain)(-4.0 * a, 0.0))
    (c0, s0), (c1, s1) = base(plain), base(boxed)
    inside = lambda c: (c[:, 0] > 4.3) & (c[:, 0] < 6.2) & (c[:, 1] < 4.2)  # noqa: E731
    upstream = lambda c: c[:, 0] < -3.0  # noqa: E731
    assert np.median(s1[inside(c1)]) == pytest.approx(0.2, rel=0.2)
    assert np.median(s0[inside(c0)]) > 2.5 * 0.2
    assert np.median(s1[upstream(c1)]) == pytest.approx(np.median(s0[upstream(c0)]), rel=0.05)
    with pytest.raises(SpecError, match=r"mesh.refine\[0\]: y_min = 5 a must be below y_max = 4.5"):
        make_case_spec({**SMALL, "mesh": {**SMALL["mesh"], "refine": [{**box, "y_min": 5.0}]}})


def test_the_capillary_step_is_set_for_the_finest_refinement(tmp_path):
    """A refinement finer than the level's rim sets the case's capillary step (until
    2026-11-27 the rim alone did, and a fine band ran at 1.6 times its own limit); a coarser
    one leaves the rim's."""
    from ehlfoam.mesh import smallest_cell_size

    box = {"x_min": 4.0, "x_max": 6.5, "y_min": 0.0, "y_max": 4.5, "size": 0.1}
    plain = make_case_spec(SMALL)
    boxed = make_case_spec({**SMALL, "mesh": {**SMALL["mesh"], "refine": [box]},
                            "run": {**SMALL["run"], "writes_per_transit": 10}})
    coarse_box = make_case_spec({**SMALL, "mesh": {**SMALL["mesh"],
                                                   "refine": [{**box, "size": 0.5}]}})
    a = plain.a
    assert smallest_cell_size(plain) == pytest.approx(SMALL["mesh"]["size_rim"] * a)
    assert smallest_cell_size(boxed) == pytest.approx(0.1 * a)
    assert smallest_cell_size(coarse_box) == pytest.approx(smallest_cell_size(plain))
    geom = write_case(boxed, tmp_path / "boxed")
    assert geom.min_cell_size == pytest.approx(0.1 * a)
    with FoamFile(tmp_path / "boxed" / "system" / "controlDict") as f:
        assert f["maxDeltaT"] == pytest.approx(capillary_time_step(boxed, 0.1 * a))
    assert capillary_time_step(boxed, 0.1 * a) < 0.5 * capillary_time_step(plain, 0.25 * a)


def test_a_band_refines_the_free_quads_along_its_line():
    """mesh.refine with points: quads of the band's size within half_width of its line, the
    level's far from it; the line is read as (x, |y|); a band with one point or below y = 0
    is refused, naming it."""
    from ehlfoam.mesh import REFINE_GROWTH, MeshParams, build_base_mesh, size_function

    # a quarter circle of r = 3 a from the upstream axis round to x = 0 (points every 0.3 a)
    phi = np.linspace(np.pi, np.pi / 2, 17)
    band = {"points": [[3 * np.cos(f), 3 * np.sin(f)] for f in phi], "half_width": 0.6,
            "size": 0.2}
    free = {**SMALL["mesh"], "polar_radius": None}            # free quads: the band's cells
    spec = make_case_spec({**SMALL, "mesh": {**free, "refine": [band]}})
    size, a = size_function(spec), spec.a
    assert size(-3.0 * a, 0.0) == pytest.approx(0.2 * a)
    assert size(-2.1 * a, -2.1 * a) == pytest.approx(0.2 * a)       # r = 2.97 a, below y = 0
    beyond = np.hypot(4.0, 0.5) - 3.0 - 0.6                         # from the band's edge
    assert size(-4.0 * a, 0.5 * a) == pytest.approx((0.2 + REFINE_GROWTH * beyond) * a, rel=0.01)
    plain = make_case_spec({**SMALL, "mesh": free})
    assert size(3.0 * a, 0.0) == pytest.approx(size_function(plain)(3.0 * a, 0.0))
    params = MeshParams(**spec.domain.box(a).fields(), n_layers=2, polar_radius=None)
    mesh = build_base_mesh(params, size)
    c = mesh.points[mesh.quads].mean(axis=1) / a
    cell = np.sqrt(mesh.quad_areas()) / a
    r = np.hypot(c[:, 0], c[:, 1])
    on_band = (np.abs(r - 3.0) < 0.4) & (c[:, 0] < -0.5)
    assert on_band.sum() > 20
    assert np.median(cell[on_band]) == pytest.approx(0.2, rel=0.25)
    assert np.median(cell[c[:, 0] > 4.0]) > 3 * 0.2
    for bad, text in (({**band, "points": [[1.0, 2.0]]}, r"mesh.refine\[0\].points = \[\[1.0, 2.0\]\]"),
                      ({**band, "points": [[1.0, -2.0], [3.0, 4.0]]}, r"point \(1, -2\) a"),
                      ({**band, "half_width": 0.0}, r"mesh.refine\[0\].half_width = 0.0.*valid range")):
        with pytest.raises(SpecError, match=text):
            make_case_spec({**SMALL, "mesh": {**SMALL["mesh"], "refine": [bad]}})


def test_ehlfoam_band_follows_a_written_meniscus(small_case, tmp_path):
    """`ehlfoam band` on a write with oil inside r = 2.5 a at mid-gap: one band whose points
    lie on r = 2.5 a within a mesh cell, from y = 0 upstream round to y = 0 downstream; its
    TOML is a valid mesh.refine."""
    case = _copy(small_case, tmp_path)
    geom = load_geometry(case)
    st = case_fields.Structure.load(case)
    r = np.hypot(st.base_x, st.base_y)[st.base_cell] / geom.a
    folder = case / "0.001"
    folder.mkdir()
    shutil.copy(case / "0.orig" / "alpha.oil", folder / "alpha.oil")
    FoamFieldFile(folder / "alpha.oil").internal_field = (r < 2.5).astype(float)
    out = subprocess.run(EHLFOAM + ["band", str(case), "--size", "0.1", "--half-width", "0.5"],
                         capture_output=True, text=True, check=True)
    refine = parse_value(out.stdout)
    assert len(refine) == 1
    pts = np.array(refine[0]["points"])
    assert (refine[0]["size"], refine[0]["half_width"]) == (0.1, 0.5)
    assert np.all(pts[:, 1] >= 0.0)
    cell = np.sqrt(st.footprint.max()) / geom.a
    assert np.abs(np.hypot(pts[:, 0], pts[:, 1]) - 2.5).max() < cell
    assert np.hypot(*np.diff(pts, axis=0).T).max() < 0.5 / 4 + 1e-6   # every half_width / 4
    assert sorted([pts[0, 0], pts[-1, 0]]) == pytest.approx([-2.5, 2.5], abs=cell)
    spec = make_case_spec({**SMALL, "mesh": {**SMALL["mesh"], "refine": refine}})
    size = refinement_size(spec.mesh.refine[0])
    assert size(np.array([0.0]), np.array([2.5])) == pytest.approx(0.1)
    bad = subprocess.run(EHLFOAM + ["band", str(case), "--size", "0.1", "--half-width", "-1"],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "--half-width = -1 a is out of range" in bad.stderr


@pytest.mark.openfoam
def test_allrun_runs_by_hand(small_case, tmp_path):
    case = _copy(small_case, tmp_path)
    with FoamFile(case / "system" / "controlDict") as f:
        f["endTime"] = 2e-4
        f["writeInterval"] = 1e-4
    proc = subprocess.run(["./Allrun"], cwd=case, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert (case / "log.interFoam").read_text().rstrip().endswith("End")
    assert (case / "0.0002" / "alpha.oil").is_file()
    subprocess.run(["./Allclean"], cwd=case, check=True)
    assert not (case / "0.0002").exists() and (case / "0.orig").is_dir()


@pytest.mark.openfoam
def test_checkmesh_passes(small_case):
    log = FoamRuntime.from_environment().run("checkMesh", [], cwd=small_case).stdout
    assert "Mesh OK." in log, log[-2000:]
    assert f"cells:            {load_geometry(small_case).cells}" in log


def test_gap_mean_weights_each_column_by_volume(small_case):
    from ehlfoam.run import fields as case_fields

    st = case_fields.Structure.load(small_case)
    assert np.allclose(st.gap_mean(np.ones_like(st.cell_volumes)), 1.0)
    # the layer index, averaged by hand over one column
    col = st.base_cell == st.base_cell[0]
    by_hand = (st.layer[col] * st.cell_volumes[col]).sum() / st.cell_volumes[col].sum()
    assert st.gap_mean(st.layer)[st.base_cell[0]] == pytest.approx(by_hand, rel=1e-12)
    vec = st.gap_mean(np.stack([st.layer, 2.0 * st.layer], axis=1))
    assert vec.shape == (len(st.base_x), 2)
    assert np.allclose(vec[:, 1], 2.0 * st.gap_mean(st.layer))


def test_supply_enters_only_on_the_track(small_case):
    from foamlib import FoamFieldFile

    bf = FoamFieldFile(small_case / "0.orig" / "alpha.oil").boundary_field
    frac = np.asarray(bf["supply"]["value"])
    d = np.load(small_case / "ehlfoam" / "mesh.npz")
    names = list(d["patch_names"])
    k = names.index("supply")
    start, size = d["patch_starts"][k], d["patch_sizes"][k]
    y = d["face_centres_boundary"][start:start + size, 1]
    assert len(frac) == size and np.all(frac > 0) and np.all(frac <= 1)
    assert np.all(np.abs(y) < 2.5e-4 + 0.5 * 1.2 * 1.4e-4)  # on the track (+ half a face)
    assert "inlet" in names                               # the rest of the inlet is open
    u = FoamFieldFile(small_case / "0.orig" / "U").boundary_field["supply"]["value"]
    assert np.allclose(np.asarray(u, float), [0.02, 0.0, 0.0])


@pytest.mark.openfoam
def test_supply_carries_the_layers_in(small_case, tmp_path):
    """The oil entering per second is u x (disc + ball layer) x track width."""
    from ehlfoam.run import fields as case_fields

    case = _copy(small_case, tmp_path)
    with FoamFile(case / "system" / "controlDict") as f:
        f["endTime"] = 2e-4
        f["writeInterval"] = 1e-4
    FoamRuntime.from_environment().run("interFoam", [], cwd=case) if (case / "0").exists() \
        else (shutil.copytree(case / "0.orig", case / "0"),
              FoamRuntime.from_environment().run("interFoam", [], cwd=case))
    geom = load_geometry(case)
    s = case_fields.sample(case / "0.0002", case_fields.Structure.load(case), geom)
    expected = 0.02 * (3e-6 + 3e-6) * 2 * 2.5e-4
    assert s.oil_in == pytest.approx(expected, rel=0.05)


def test_thin_wall_cells_under_a_sloping_ball_carry_the_whole_supply_in(tmp_path):
    """Wall cells of 0.3 um, thinner than the ball climbs across an inlet face: the supply
    faces' oil fractions times their areas across the flow, at u, are u x (disc + ball
    layer) x track width to 1e-6 (corners sorted by height had taken a share of the ball's
    layer off each face there)."""
    spec = make_case_spec({**SMALL, "mesh": {**SMALL["mesh"], "wall_grading": None,
                                             "wall_cell": 3e-7, "n_layers": 8}})
    case = tmp_path / "thin"
    write_case(spec, case)
    poly = case / "constant" / "polyMesh"
    points = np.asarray(FoamFile(poly / "points")[None], float)
    faces = FoamFile(poly / "faces")[None]
    patch = FoamFile(poly / "boundary")[None]
    supply = next(p[1] for p in patch if p[0] == "supply")
    start, size = int(supply["startFace"]), int(supply["nFaces"])
    quads = points[np.asarray([faces[i] for i in range(start, start + size)])]
    area_x = 0.5 * np.cross(quads[:, 2] - quads[:, 0], quads[:, 3] - quads[:, 1])[:, 0]
    alpha = np.asarray(FoamFieldFile(case / "0.orig" / "alpha.oil")
                       .boundary_field["supply"]["value"], float)
    # the ball climbs across some supply face by more than that face's height
    z = quads[:, :, 2]
    assert np.any(z.max(axis=1) - z.min(axis=1) > 2 * 3e-7)
    flux = 2 * spec.speed * float(np.sum(alpha * np.abs(area_x)))      # both halves
    assert flux == pytest.approx(spec.speed * (3e-6 + 3e-6) * 2 * 2.5e-4, rel=1e-6)


@pytest.mark.openfoam
def test_side_bands_carry_their_layers_in(tmp_path):
    """With a dry middle band the oil enters only on |y| in [inner, outer]: the flux is
    u x (disc + ball layer) x 2 (outer - inner), and no supply face lies inside the band."""
    from foamlib import FoamFieldFile

    from ehlfoam.run import fields as case_fields

    inner = 1.0e-4
    case = tmp_path / "bands"
    write_case(make_case_spec({**SMALL, "supply": {**SMALL["supply"],
                                                   "track_inner_half_width": inner}}), case)
    d = np.load(case / "ehlfoam" / "mesh.npz")
    k = list(d["patch_names"]).index("supply")
    start, size = d["patch_starts"][k], d["patch_sizes"][k]
    y = d["face_centres_boundary"][start:start + size, 1]
    assert np.all(np.abs(y) > inner - 0.5 * 1.2 * 1.4e-4)   # outside the band (- half a face)
    alpha0 = np.asarray(FoamFieldFile(case / "0.orig" / "alpha.oil").internal_field)
    yc, xc = d["cell_centres"][:, 1], d["cell_centres"][:, 0]
    a = load_geometry(case).a
    upstream = xc < -SMALL["supply"]["initial_puddle"] * a   # outside the initial puddle
    assert alpha0[upstream & (np.abs(yc) < 0.9 * inner)].max() == 0.0
    assert alpha0[upstream & (np.abs(yc) > 1.1 * inner) & (np.abs(yc) < 2.4e-4)].max() > 0
    with FoamFile(case / "system" / "controlDict") as f:
        f["endTime"] = 2e-4
        f["writeInterval"] = 1e-4
    shutil.copytree(case / "0.orig", case / "0")
    FoamRuntime.from_environment().run("interFoam", [], cwd=case)
    s = case_fields.sample(case / "0.0002", case_fields.Structure.load(case), load_geometry(case))
    assert s.oil_in == pytest.approx(0.02 * (3e-6 + 3e-6) * 2 * (2.5e-4 - inner), rel=0.05)


@pytest.mark.openfoam
def test_run_a_few_steps_writes_metrics(small_case, tmp_path):
    case = _copy(small_case, tmp_path)
    m = run_case(case, wall_limit=120)
    assert m["status"] == "finished" and m["end_reason"] == "end_time", m
    assert m["time_steps"] > 5
    assert m["simulated_time_s"] == pytest.approx(1e-3, rel=1e-6)
    assert m["state"] in ("I", "II")
    assert m["oil_volume_m3"] > 0
    # over 1 ms the outlet flux flickers between 15 writes (trapezoid error); runs to steady
    # state balance within 1 % (docs/validation.md#v-mass-balance). This catches a lost factor
    # or sign.
    assert m["oil_mass_balance_error"] is not None and m["oil_mass_balance_error"] < 0.1
    assert m["oil_flux_source"] == OIL_FLUX_EXACT
    assert m["oil_inflow_m3_s"] == pytest.approx(0.02 * 6e-6 * 5e-4, rel=1e-6)
    # the upstream boundary takes air in and lets no oil out (its alpha is fixed: with
    # inletOutlet the flickering face flux pumped oil out there,
    # docs/models/interface.md#physics)
    last = case_fields.time_folders(case)[-1][1]
    oil_up = FoamFieldFile(last / "alphaPhi0.oil").boundary_field["inlet"]["value"]
    assert np.all(np.asarray(oil_up) == 0.0)
    assert np.sum(FoamFieldFile(last / "phi").boundary_field["inlet"]["value"]) < 0
    rows = (case / "history.csv").read_text().splitlines()
    assert len(rows) >= 10 and rows[0].startswith("time_s,oil_volume_m3")
    assert "oil_out_outlet_m3_s" in rows[0] and "oil_out_side_m3_s" in rows[0]
    # the shape of the inlet meniscus at every write, as metrics.json has it at the last
    history = read_history(case / "history.csv")
    assert m["inlet_meniscus_shape"] == "convex"        # ample oil, state I
    assert history["inlet_meniscus_shape"][-1] == "convex"
    assert history["inlet_meniscus_c2"][-1] == pytest.approx(m["inlet_meniscus_c2"], rel=1e-9)
    assert set(history["wake_open"]) <= {True, False}
    # the share of the oil in smeared interface cells: in metrics.json and history's last row
    assert 0.0 < m["oil_smeared_fraction"] < 1.0
    assert history["oil_smeared_fraction"][-1] == pytest.approx(m["oil_smeared_fraction"])
    # where the oil leaves: split by boundary, adding up to the outflow, none upstream
    by_boundary = m["oil_outflow_by_boundary_m3_s"]
    assert set(by_boundary) == {"inlet", "outlet", "side"}
    assert sum(by_boundary.values()) == pytest.approx(m["oil_outflow_m3_s"], rel=1e-12)
    assert by_boundary["inlet"] == 0.0
    off = m["oil_outflow_off_outlet_fraction"]
    assert off is None or 0.0 <= off <= 1.0
    saved = json.loads((case / "metrics.json").read_text())
    assert saved["end_reason"] == "end_time" and saved["time_steps"] == m["time_steps"]


@pytest.mark.openfoam
def test_polar_ring_case_builds_and_runs(tmp_path):
    """mesh.polar_radius reaches the mesh (column centres on a few circles around the island),
    checkMesh passes and the solver runs on it."""
    spec = make_case_spec({**SMALL, "mesh": {**SMALL["mesh"], "polar_radius": 4.0}})
    case = tmp_path / "polar"
    write_case(spec, case)
    st = case_fields.Structure.load(case)
    r = np.hypot(st.base_x, st.base_y) / spec.a
    ring = r < 4.0
    assert 0.3 < ring.mean() < 0.9
    assert len(np.unique(np.round(r[ring], 4))) < 0.2 * ring.sum()   # free quads: all differ
    log = FoamRuntime.from_environment().run("checkMesh", [], cwd=case).stdout
    assert "Mesh OK." in log, log[-2000:]
    m = run_case(case, wall_limit=120)
    assert m["status"] == "finished" and m["end_reason"] == "end_time", m
    assert m["oil_mass_balance_error"] < 0.1


@pytest.mark.openfoam
@pytest.mark.parametrize("scene", ["interface", "cavitating", "gas-release"])
def test_balanced_interface_schemes_reach_every_solver(tmp_path, scene):
    """physics.interface_schemes = "balanced" writes uncorrected face gradients, the
    least-squares interface normal and the limited compression flux, and interFoam,
    compressibleInterFoam and interPhaseChangeFoam all run with them; "standard" keeps the
    templates' schemes."""
    spec = make_case_spec({**SMALL, "scene": scene,
                           "run": {**SMALL["run"], "end_time": 2e-4}},
                          **{"physics.interface_schemes": "balanced"})
    case = tmp_path / scene
    write_case(spec, case)
    with FoamFile(case / "system" / "fvSchemes") as f:
        assert f["snGradSchemes"]["default"] == "uncorrected"
        assert tuple(f["laplacianSchemes"]["default"]) == ("Gauss", "linear", "uncorrected")
        assert f["gradSchemes"]["nHat"] == "pointCellsLeastSquares"
        assert tuple(f["divSchemes"]["div(phirb,alpha)"]) == ("Gauss", "interfaceCompression")
    m = run_case(case, wall_limit=120)
    assert m["status"] == "finished" and m["end_reason"] == "end_time", m
    assert m["time_steps"] > 3
    standard = tmp_path / f"{scene}-standard"
    write_case(make_case_spec({**SMALL, "scene": scene}), standard)
    with FoamFile(standard / "system" / "fvSchemes") as f:
        assert tuple(f["snGradSchemes"]["default"].split()) == ("corrected",)
        assert "nHat" not in f["gradSchemes"]


@pytest.mark.openfoam
def test_cavitating_case_runs_a_few_steps(tmp_path):
    """The cavitating scene (compressibleInterFoam, air a perfect gas, absolute pressure):
    builds, runs, and reports the bubble and the lowest pressure."""
    spec = make_case_spec({**SMALL, "scene": "cavitating"})
    case = tmp_path / "cav"
    geom = write_case(spec, case)
    assert geom.solver == "compressibleInterFoam" and geom.absolute_pressure
    with FoamFile(case / "constant" / "thermophysicalProperties.oil") as f:
        assert f["thermoType"]["equationOfState"] == "rhoConst"     # incompressible oil
        assert f["mixture"]["equationOfState"]["rho"] == pytest.approx(spec.oil_density)
    m = run_case(case, wall_limit=120)
    assert m["status"] == "finished" and m["end_reason"] == "end_time", m
    assert (case / "log.compressibleInterFoam").read_text().rstrip().endswith("End")
    assert m["time_steps"] > 5
    # the rolling contact pumps: sub-ambient pressure behind it, above the pressure floor
    p_amb = spec.physics.ambient_pressure
    assert spec.physics.cavitation_pressure <= m["min_pressure_Pa"] < p_amb
    for key in ("bubble_length_over_a", "bubble_width_over_a", "bubble_volume_m3"):
        assert m[key] >= 0.0
    assert isinstance(m["bubble_enclosed"], bool)
    assert m["oil_mass_balance_error"] < 0.1
    assert m["oil_inflow_m3_s"] == pytest.approx(0.02 * 6e-6 * 5e-4, rel=1e-3)
    assert m["gas_mass_balance_error"] < 0.05       # the air: p/(R T) times the gas fluxes
    header = (case / "history.csv").read_text().splitlines()[0]
    assert "bubble_volume_m3" in header and "min_pressure_Pa" in header


@pytest.mark.openfoam
def test_cavitating_case_with_a_compressible_oil(tmp_path):
    """physics.oil_bulk_modulus makes the oil a perfect fluid, R = K/(rho0 T), which the
    solver reads and runs."""
    k = 1.5e9
    spec = make_case_spec({**SMALL, "scene": "cavitating", "physics": {"oil_bulk_modulus": k},
                           "run": {**SMALL["run"], "end_time": 2e-4}})
    case = tmp_path / "cav_k"
    write_case(spec, case)
    with FoamFile(case / "constant" / "thermophysicalProperties.oil") as f:
        assert f["thermoType"]["equationOfState"] == "perfectFluid"
        eos = f["mixture"]["equationOfState"]
        assert eos["rho0"] * eos["R"] * spec.temperature_k == pytest.approx(k)
    m = run_case(case, wall_limit=120)
    assert m["status"] == "finished" and m["end_reason"] == "end_time", m


@pytest.mark.openfoam
def test_gas_release_case_holds_the_pressure_at_the_release_pressure(tmp_path):
    """The gas-release scene (interPhaseChangeFoam, Kunz's vaporisation term only, no
    condensation): oil below the release pressure turns into gas, so the suction behind the
    contact, which reaches ~13 kPa absolute without it in this case, stays at the release
    pressure."""
    p_release = 9e4
    spec = make_case_spec({**SMALL, "scene": "gas-release",
                           "physics": {"cavitation_pressure": p_release,
                                       "gas_release_rate": 1.0}})
    case = tmp_path / "gr"
    geom = write_case(spec, case)
    assert geom.solver == "interPhaseChangeFoam" and not geom.absolute_pressure
    with FoamFile(case / "constant" / "transportProperties") as f:
        assert f["phaseChangeTwoPhaseMixture"] == "Kunz"
        assert f["pSat"] == pytest.approx(p_release - spec.physics.ambient_pressure)
        assert f["KunzCoeffs"]["Cc"] == 0.0
    with FoamFile(case / "system" / "controlDict") as f:
        assert f["application"] == "interPhaseChangeFoam"
    m = run_case(case, wall_limit=120)
    assert m["status"] == "finished" and m["end_reason"] == "end_time", m
    assert (case / "log.interPhaseChangeFoam").read_text().rstrip().endswith("End")
    assert 0.97 * p_release < m["min_pressure_Pa"] < spec.physics.ambient_pressure
    # holding the pressure there takes more gas than the supply brings in dissolved (5.7
    # times here): the release has no budget, and the run says so
    # (docs/models/gas-release.md#physics)
    assert 0.0 < m["gas_released_m3"] < m["dissolved_air_m3"]   # the puddle's air, in 1 ms
    assert m["gas_release_over_dissolved_inflow"] > 1.0, m["gas_release_over_dissolved_inflow"]
    # all-oil supply faces (ehlfoam.case.fields.supply_faces): 1.8 % here, 5.5 % with
    # part-oil faces, across which interPhaseChangeFoam compresses the interface. Over this
    # 1 ms the fluxes, sampled at 15 writes, fluctuate with the air (the oil's kinematic
    # viscosity, 60 times less than the other scenes'): interFoam with that air is off by
    # 3.1 % here even with its exact alphaPhi0.
    assert m["oil_mass_balance_error"] < 0.03
    assert m["oil_flux_source"] == OIL_FLUX_APPROXIMATE      # no alphaPhi0 written
    with FoamFieldFile(case / "0.orig" / "U") as f:
        u_supply = np.asarray(f.boundary_field["supply"]["value"])
    assert u_supply.ndim == 2 and np.all(u_supply[:, 0] < spec.wall_speed)


@pytest.mark.openfoam
def test_submerged_gas_release_dissolves_its_gas_back(tmp_path):
    """A submerged contact (supply.mode = "submerged": oil fills the domain and is what
    flows in everywhere) in the gas-release scene: the only gas is what the suction
    releases, and with physics.gas_dissolution_rate (Kunz's condensation term) it goes back
    into the oil where the pressure is above the release pressure. Same release, with and
    without dissolving back: less gas is left in the gap with it, the run reports the rate,
    and the oil balance, with the oil flowing in through the open boundaries, closes."""
    gas, rate = {}, 3e5
    for c in (0.0, rate):
        spec = make_case_spec({**SMALL, "scene": "gas-release",
                               "supply": {**SMALL["supply"], "mode": "submerged"},
                               "physics": {"cavitation_pressure": 9e4, "gas_release_rate": 1.0,
                                           "gas_dissolution_rate": c},
                               "run": {**SMALL["run"], "end_time": 2e-3}})
        case = tmp_path / f"submerged_C{c:g}"
        geom = write_case(spec, case)
        assert geom.open_inflow_oil == 1.0 and geom.gas_dissolution_rate == c
        with FoamFieldFile(case / "0.orig" / "alpha.oil") as f:
            assert np.all(np.asarray(f.internal_field) == 1.0)          # full of oil
            assert f.boundary_field['"(outlet|side)"']["inletValue"] == 1.0
        structure = case_fields.Structure.load(case)
        assert structure.patches.get("supply", (0, 0))[1] == 0          # no supply faces
        with FoamFile(case / "constant" / "transportProperties") as f:
            assert f["KunzCoeffs"]["Cc"] == c
        m = run_case(case, wall_limit=120)
        assert m["status"] == "finished" and m["end_reason"] == "end_time", m.get("log_tail")
        # without dissolving the balance closes to 1e-4; the gas dissolved back is integrated
        # from its rate sampled at the 29 writes, and that sampling moves the balance between
        # 0.9 and 1.3 % on this tiny mesh (vertical or leaning columns, 29 or 58 writes;
        # measured 2026-11-24)
        assert m["oil_mass_balance_error"] < (0.001 if c == 0 else 0.02), \
            m["oil_mass_balance_error"]
        _, last = case_fields.time_folders(case)[-1]
        alpha = np.clip(np.asarray(FoamFieldFile(last / "alpha.oil").internal_field), 0, 1)
        gas[c] = float(np.sum((1.0 - alpha) * structure.cell_volumes))
        # all that flows in is oil, and the monitor counts it so
        q_in, _ = case_fields.volume_flux(last, structure, geom)
        assert q_in > 0 and m["oil_inflow_m3_s"] == pytest.approx(q_in, rel=1e-9)
        if c > 0:
            assert m["gas_dissolution_m3_s"] > 0.0, m
        else:
            assert m["gas_dissolution_m3_s"] is None, m
    assert gas[0.0] > 0.0                                          # the suction released gas
    assert gas[rate] < 0.8 * gas[0.0], gas


def _last_velocity(case: Path) -> np.ndarray:
    _, last = case_fields.time_folders(case)[-1]
    return np.asarray(FoamFieldFile(last / "U").internal_field)


@pytest.mark.openfoam
def test_gas_release_flow_does_not_remember_the_initial_air(tmp_path):
    """interPhaseChangeFoam v1912 computes the mixture viscosity once, from the initial oil
    fraction, and never again. Here oil fills the gap and enters everywhere, so the flow must
    not depend on whether the outlet and side boundaries start as air (the template's value)
    or oil. With the air's kinematic viscosity 60 times the oil's (the other scenes' x100 air)
    the frozen air viscosity on those boundaries drove 1.3 m/s across the gap; the
    gas-release scene's air has the oil's kinematic viscosity (CaseSpec.air_viscosity), so
    nothing remembers."""
    spec = make_case_spec({**SMALL, "scene": "gas-release",
                           "supply": {**SMALL["supply"], "mode": "submerged"},
                           "run": {**SMALL["run"], "end_time": 2e-3}})
    velocities = {}
    for start in (0.0, 1.0):
        case = tmp_path / f"open_boundaries_start_{start:g}"
        write_case(spec, case)
        with FoamFile(case / "0.orig" / "alpha.oil") as f:
            open_patches = f["boundaryField"]['"(outlet|side)"']
            assert open_patches["value"] == 0.0 and open_patches["inletValue"] == 1.0
            open_patches["value"] = start
        with FoamFile(case / "constant" / "transportProperties") as f:
            assert f["air"]["nu"] == pytest.approx(f["oil"]["nu"])
        m = run_case(case, wall_limit=120)
        assert m["status"] == "finished", m.get("log_tail")
        velocities[start] = _last_velocity(case)
    assert np.abs(velocities[1.0]).max() > 0.5 * spec.wall_speed        # the flow is there
    assert np.abs(velocities[0.0] - velocities[1.0]).max() < 1e-3 * spec.wall_speed


@pytest.mark.openfoam
def test_cavitating_case_starts_from_another_cases_fields(tmp_path):
    """A ramp step of the cavitating scene: the previous case's final fields (lists, p and T
    included) as the start; the case must read them (no $internalField in list fields)."""
    from ehlfoam.seed.previous import seed_from_previous

    first, second = tmp_path / "first", tmp_path / "second"
    write_case(make_case_spec({**SMALL, "scene": "cavitating"}), first)
    assert run_case(first, wall_limit=120)["status"] == "finished"
    faster = make_case_spec({**SMALL, "scene": "cavitating",
                             "contact": {**SMALL["contact"], "speed": 0.025}})
    write_case(faster, second)
    info = seed_from_previous(second, first)
    assert info["method"] == "copy" and {"p", "p_rgh", "T", "alpha.oil", "U"} <= set(info["fields"])
    m = run_case(second, wall_limit=120)
    assert m["status"] == "finished", m.get("log_tail")
    assert m["oil_volume_initial_m3"] == pytest.approx(
        json.loads((first / "metrics.json").read_text())["oil_volume_m3"], rel=1e-6)


def _toml(spec: dict) -> str:
    """A spec dict (scalars and one level of tables) as TOML."""
    top = [f"{k} = {json.dumps(v)}" for k, v in spec.items() if not isinstance(v, dict)]
    tables = [f"[{k}]\n" + "\n".join(f"{kk} = {json.dumps(vv)}" for kk, vv in v.items())
              for k, v in spec.items() if isinstance(v, dict)]
    return "\n".join(top + tables) + "\n"


@pytest.mark.openfoam
def test_cli_case_starts_from_another_run_case(tmp_path):
    """`ehlfoam case --start-from CASE`: the new case's initial fields are CASE's final ones
    (a converged neighbour); a CASE with nothing written is refused before anything is."""
    spec = tmp_path / "small.toml"
    spec.write_text(_toml({**SMALL, "run": {**SMALL["run"], "end_time": 2e-4}}))
    first, second = tmp_path / "first", tmp_path / "second"
    assert subprocess.run([*EHLFOAM, "case", str(spec), "--out", str(first)],
                          capture_output=True).returncode == 0
    refused = subprocess.run([*EHLFOAM, "case", str(spec), "--out", str(second),
                              "--start-from", str(first)], capture_output=True, text=True)
    assert refused.returncode == 2 and "no written time" in refused.stderr
    assert not second.exists()
    assert run_case(first, wall_limit=120)["status"] == "finished"
    proc = subprocess.run([*EHLFOAM, "case", str(spec), "--out", str(second), "--start-from",
                           str(first), "--set", "contact.speed=0.025"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "starts from" in proc.stdout
    t, folder = case_fields.time_folders(first)[-1]
    info = json.loads((second / "ehlfoam" / "ramp.json").read_text())
    assert info["method"] == "copy" and info["previous_time_s"] == pytest.approx(t)
    structure = case_fields.Structure.load(second)
    final = case_fields._read_alpha(folder / "alpha.oil", structure)[0]
    start = case_fields._read_alpha(second / "0.orig" / "alpha.oil", structure)[0]
    assert np.allclose(start, final) and not np.allclose(
        start, case_fields._read_alpha(first / "0.orig" / "alpha.oil", structure)[0])


@pytest.mark.openfoam
def test_cli_snapshot_keeps_a_runs_state_and_starts_another_case_from_it(tmp_path):
    """`ehlfoam snapshot CASE OUT.npz`: a run's last write in one small file; `ehlfoam case
    --start-from OUT.npz` gives a case on the same mesh that write's oil and velocity back
    (to 16 bits and half precision), and the case runs. A case with nothing written, a file
    name that is no .npz and a snapshot of another contact are refused, naming the cause."""
    spec = tmp_path / "small.toml"
    spec.write_text(_toml({**SMALL, "run": {**SMALL["run"], "end_time": 2e-4}}))
    first, second, other = tmp_path / "first", tmp_path / "second", tmp_path / "other"
    snap = tmp_path / "first.npz"
    assert subprocess.run([*EHLFOAM, "case", str(spec), "--out", str(first)],
                          capture_output=True).returncode == 0
    refused = subprocess.run([*EHLFOAM, "snapshot", str(first), str(snap)],
                             capture_output=True, text=True)
    assert refused.returncode == 2 and "no written time" in refused.stderr
    assert run_case(first, wall_limit=120)["status"] == "finished"
    refused = subprocess.run([*EHLFOAM, "snapshot", str(first), str(tmp_path / "first.txt")],
                             capture_output=True, text=True)
    assert refused.returncode == 2 and "must end in .npz" in refused.stderr
    assert not (tmp_path / "first.txt").exists()
    proc = subprocess.run([*EHLFOAM, "snapshot", str(first), str(snap)],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "alpha.oil, U" in proc.stdout and snap.is_file()
    from ehlfoam.seed.snapshot import snapshot_history   # the run's history rides along
    kept, transit = snapshot_history(snap)
    own = read_history(first / "history.csv")
    assert transit == pytest.approx(load_geometry(first).transit_time)
    for key in ("time_s", "oil_volume_m3", "flooded_width_over_a"):
        assert len(own[key]) > 0
        np.testing.assert_allclose(kept[key], own[key])

    proc = subprocess.run([*EHLFOAM, "case", str(spec), "--out", str(second), "--start-from",
                           str(snap)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    t, folder = case_fields.time_folders(first)[-1]
    info = json.loads((second / "ehlfoam" / "ramp.json").read_text())
    assert info["method"] == "snapshot" and info["fields"] == ["U", "alpha.oil"]
    assert info["previous_time_s"] == pytest.approx(t)
    s = case_fields.Structure.load(second)
    final = case_fields._read_alpha(folder / "alpha.oil", s)[0]
    start = case_fields._read_alpha(second / "0.orig" / "alpha.oil", s)[0]
    assert final.min() < 0.5 < final.max()                    # an interface to carry
    assert np.abs(start - final).max() < 2e-5
    assert s.cell_volumes @ start == pytest.approx(s.cell_volumes @ final, rel=1e-9)
    assert info["oil"]["conserved"]
    # a snapshot written before it kept its oil: the oil from its run's history
    from ehlfoam.seed.snapshot import source_oil, load_snapshot
    record = {k: v for k, v in load_snapshot(snap)[3].items() if not k.startswith("mesh_")}
    oil, volume = source_oil(record, second, s)
    assert oil == pytest.approx(s.cell_volumes @ final, rel=1e-6)
    assert volume == pytest.approx(s.cell_volumes.sum(), rel=1e-12)
    # the kept state read on the new mesh gives the flow pattern the run read off its write
    from ehlfoam.metrics.pattern import flow_pattern_from_raster
    from ehlfoam.seed.snapshot import map_snapshot
    mapped, carried, _ = map_snapshot(second, s, snap, ["alpha.oil"])
    assert carried["conserved"]
    pattern = flow_pattern_from_raster(case_fields.mid_gap_raster(
        mapped["alpha.oil"], s, load_geometry(second)))
    measured = [k for k in ("flooded_width_over_a", "inlet_meniscus_distance_over_a",
                            "flooded_length_over_a") if np.isfinite(own[k][-1])]
    assert measured                                            # a pattern to compare
    for key in measured:
        assert pattern[key] == pytest.approx(own[key][-1], abs=1e-3), key
    u_final = np.asarray(FoamFieldFile(folder / "U").internal_field)
    u_start = np.asarray(FoamFieldFile(second / "0.orig" / "U").internal_field)
    assert np.abs(u_final).max() > 0.1 * SMALL["contact"]["speed"]
    assert np.abs(u_start - u_final).max() < 2e-3 * np.abs(u_final).max()
    assert run_case(second, wall_limit=120)["status"] == "finished"

    refused = subprocess.run([*EHLFOAM, "case", str(spec), "--out", str(other), "--start-from",
                              str(snap), "--set", "contact.load=60"],
                             capture_output=True, text=True)
    assert refused.returncode == 2 and "its gaps differ from the case's" in refused.stderr
    assert not other.exists()


def _thin_film_state(path: Path, a: float, films: float, gap_factor: float = 1.0) -> None:
    """A thin-film state written by hand on 0.25 a cells over x = -2..4 a, y = 0..2 a of the
    small case's gap (times ``gap_factor``): flooded ahead of x = a, films of ``films`` of the
    gap behind."""
    from ehlfoam.thinfilm import Grid, ThinFilmSolution
    from ehlfoam.thinfilm.state import save_state
    from ehlfoam.gap.source import load_gap

    d = 0.25 * a
    x, y = -2 * a + d * (np.arange(24) + 0.5), d * (np.arange(8) + 0.5)
    X, Y = np.meshgrid(x, y)
    gap, _ = load_gap(make_case_spec(SMALL).contact)
    h = gap_factor * gap(X.ravel(), Y.ravel()).reshape(X.shape)
    flooded = X < a
    grid = Grid(x=x, y=y, h=h, hx=h[:, 1:], hy=h[1:], h_side=h[-1], island=np.isnan(h))
    save_state(ThinFilmSolution(grid=grid, p=np.where(flooded, 0.0, np.nan),
                                content=np.where(flooded, h, films * h), flooded=flooded,
                                time=0.0, steps=0, flux_in=0.0, flux_out=0.0, steady=False,
                                island_radius=0.0), path)


def test_cli_case_starts_from_a_thin_film_state(small_case, tmp_path):
    """`ehlfoam case --start-from STATE.npz`: each column on the state's grid starts with the
    state's oil, whole where it is flooded, and behind as two films on the walls holding the
    state's share of the gap; columns off its grid keep the spec's own start, and `ehlfoam
    band --time start` finds the state's meniscus. A file that is no state, or a state of
    another contact (other gaps), is refused and leaves no case."""
    spec = tmp_path / "small.toml"
    spec.write_text(_toml(SMALL))
    a = load_geometry(small_case).a
    state, bad, other, case = (tmp_path / n for n in ("state.npz", "bad.npz", "other.npz",
                                                      "seeded"))
    _thin_film_state(state, a, films=0.2)
    _thin_film_state(other, a, films=0.2, gap_factor=1.5)   # another contact's
    bad.write_text("not a state")
    refused = subprocess.run([*EHLFOAM, "case", str(spec), "--out", str(case),
                              "--start-from", str(bad)], capture_output=True, text=True)
    assert refused.returncode == 2 and "not a thin-film state" in refused.stderr
    assert not case.exists()
    refused = subprocess.run([*EHLFOAM, "case", str(spec), "--out", str(case),
                              "--start-from", str(other)], capture_output=True, text=True)
    found = re.search(r"its gaps differ from the case's by ([\d.]+)%", refused.stderr)
    assert refused.returncode == 2 and found and 40 < float(found[1]) < 55   # 1.5 times
    assert not case.exists()
    proc = subprocess.run([*EHLFOAM, "case", str(spec), "--out", str(case), "--start-from",
                           str(state)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "starts from" in proc.stdout and "thin-film" in proc.stdout
    info = json.loads((case / "ehlfoam" / "ramp.json").read_text())
    assert info["method"] == "thin-film" and info["fields"] == ["alpha.oil"]
    s = case_fields.Structure.load(case)
    alpha = case_fields._read_alpha(case / "0.orig" / "alpha.oil", s)[0]
    own = case_fields._read_alpha(small_case / "0.orig" / "alpha.oil", s)[0]
    column_oil = s.gap_mean(alpha)
    x, y, m = s.base_x / a, s.base_y / a, 0.3          # m: clear of the state's cells' edges
    ahead = (x > -2 + m) & (x < 1 - m) & (y < 2 - m)
    behind = (x > 1 + m) & (x < 4 - m) & (y < 2 - m)
    off = (x > 4 + m) | (y > 2 + m)
    assert ahead.sum() > 5 and behind.sum() > 5 and off.sum() > 5
    assert np.all(alpha[np.isin(s.base_cell, np.nonzero(ahead)[0])] == 1.0)
    np.testing.assert_allclose(column_oil[behind], 0.2, rtol=1e-9)
    wall = np.isin(s.base_cell, np.nonzero(behind)[0]) & np.isin(s.layer, [0, s.layer.max()])
    middle = np.isin(s.base_cell, np.nonzero(behind)[0]) & ~np.isin(s.layer, [0, s.layer.max()])
    assert np.all(alpha[wall] > 0.0) and np.all(alpha[middle] == 0.0)
    cells_off = np.isin(s.base_cell, np.nonzero(off)[0])
    np.testing.assert_array_equal(alpha[cells_off], own[cells_off])
    assert not np.array_equal(alpha, own)
    band = subprocess.run(EHLFOAM + ["band", str(case), "--time", "start", "--size", "0.1",
                                     "--half-width", "0.5"], capture_output=True, text=True)
    assert band.returncode == 0, band.stderr
    pts = np.concatenate([np.array(b["points"]) for b in parse_value(band.stdout)])
    near_axis = pts[(pts[:, 1] < 1.5) & (pts[:, 0] > 0)]   # the state's rear, x = a to y = 2 a
    assert len(near_axis) >= 3 and np.abs(near_axis[:, 0] - 1.0).max() < 0.3


@pytest.mark.openfoam
def test_cli_case_warns_when_thin_wall_cells_stair_step_along_the_ball(tmp_path):
    """Thinner wall cells under the same in-plane cells make the ball stair-step over many
    wall-cell heights per cell, where a spurious film creeps along it: `ehlfoam case` says so
    (and records the median steps); the small case's own layers do not."""
    spec = tmp_path / "small.toml"
    spec.write_text(_toml(SMALL))
    runs = {}
    for name, extra in (("own", []), ("thin", ["--set", "mesh.n_layers=12",
                                               "--set", "mesh.wall_grading=40"])):
        runs[name] = subprocess.run([*EHLFOAM, "case", str(spec), "--out", str(tmp_path / name),
                                     *extra], capture_output=True, text=True)
        assert runs[name].returncode == 0, runs[name].stderr
    own, thin = (load_geometry(tmp_path / n).ball_wall_steps for n in ("own", "thin"))
    assert 0.0 < own < BALL_WALL_STEPS_LIMIT < thin
    assert "warning" not in runs["own"].stderr
    assert "wall cells step" in runs["thin"].stderr and "mesh.n_layers" in runs["thin"].stderr
    # every run records it in metrics.json, which a batch's log and results.csv show
    warnings = mesh_warnings(load_geometry(tmp_path / "thin"))
    assert [f"ehlfoam case: warning {w}" for w in warnings] == [
        ln for ln in runs["thin"].stderr.splitlines() if "warning" in ln]
    assert mesh_warnings(load_geometry(tmp_path / "own")) == []
    with FoamFile(tmp_path / "thin" / "system" / "controlDict") as f:
        f["endTime"] = 1e-4
    m = run_case(tmp_path / "thin", wall_limit=120)
    # after the mesh's warning, the coarse rear cells' of the same run, and its front's off
    # the track, where dry walls run into the puddle: the small case's cells there are tens
    # of its wall cells wide, past the contact-line strip's 15
    assert m["status"] == "finished" and m["warnings"] == to_text(
        warnings + rear_cell_warnings(m["rear_meniscus_cell_over_a"])
        + front_cell_warnings(m["front_contact_line_cells_over_wall_cell"])), m
    assert m["front_contact_line_cells_over_wall_cell"] > FRONT_CELL_WARNING
    assert "dry walls run into it" in m["warnings"]
    # with the compression from the local speed the advancing line holds on any cells
    assert front_cell_warnings(m["front_contact_line_cells_over_wall_cell"], 1.0) == []
    assert front_cell_warnings(m["front_contact_line_cells_over_wall_cell"], 0.5)


@pytest.mark.openfoam
def test_isoadvector_runs_the_interface_scene_on_interisofoam(tmp_path):
    """physics.interface_advection = "isoadvector": the case runs interIsoFoam with
    isoAdvector's controls, to its end, and keeps the oil the compression run of the same
    case keeps; a scene with phase change refuses it before anything is written."""
    ends = {}
    for advection in ("compression", "isoadvector"):
        spec = make_case_spec({**SMALL, "physics": {"interface_advection": advection},
                               "run": {**SMALL["run"], "end_time": 3e-4}})
        case = tmp_path / advection
        write_case(spec, case)
        ends[advection] = run_case(case, wall_limit=120)
        assert (ends[advection]["status"], ends[advection]["end_reason"]) == (
            "finished", "end_time"), ends[advection]
    case = tmp_path / "isoadvector"
    with FoamFile(case / "system" / "controlDict") as f:
        assert f["application"] == "interIsoFoam"
    with FoamFile(case / "system" / "fvSolution") as f:
        alpha = f["solvers"]['"alpha.oil.*"']
        assert (alpha["isoFaceTol"], alpha["nAlphaBounds"], alpha["clip"]) == (1e-6, 3, True)
    assert (case / "log.interIsoFoam").stat().st_size > 0
    iso, mules = ends["isoadvector"], ends["compression"]
    assert iso["oil_mass_balance_error"] < 1e-3
    assert iso["oil_volume_m3"] == pytest.approx(mules["oil_volume_m3"], rel=1e-3)
    with pytest.raises(SpecError, match='interface_advection = "isoadvector" needs scene'):
        make_case_spec({**SMALL, "scene": "gas-release",
                        "physics": {"interface_advection": "isoadvector"}})


@pytest.mark.openfoam
def test_diverging_run_keeps_logs_and_is_marked_failed(small_case, tmp_path):
    case = _copy(small_case, tmp_path)
    with FoamFile(case / "system" / "controlDict") as f:   # a fixed, absurd time step
        f["adjustTimeStep"] = False
        f["deltaT"] = 2e-2
        f["endTime"] = 2.0
    m = run_case(case, wall_limit=120)
    assert m["status"] == "failed" and m["end_reason"] == "diverged", m
    assert (case / "log.interFoam").stat().st_size > 0
    # the fixed step traps a floating-point exception in the numerics: the log's signal
    assert m["log_tail"] and m["reason"].startswith("interFoam failed after"), m["reason"]
    assert "signal 8 (Floating point exception), a floating-point trap" in m["reason"]
    saved = json.loads((case / "metrics.json").read_text())
    assert saved["status"] == "failed"


def _solver_of(run: subprocess.Popen, case: Path, timeout: float = 120.0) -> int:
    """The pid of the solver the ``ehlfoam run`` process ``run`` started, once ``case`` has a
    write past 0."""
    found: list[int] = []

    def writing() -> bool:
        found[:] = [p for p in procs.tree(run.pid) if "interFoam" in procs.command_line(p)]
        return bool(found) and len(case_fields.time_folders(case)) > 1

    procs.wait_for(writing, run, timeout, f"a solver writing in {case}", step=0.05)
    return found[0]


def _run_and_find_solver(tmp_path: Path) -> tuple[Path, subprocess.Popen, int]:
    """A tiny case run by ``ehlfoam run`` (wall limit 300 s) and the pid of its solver, once
    it has written past 0."""
    spec = make_case_spec({**SMALL, "run": {**SMALL["run"], "end_time": 5e-2}})
    case = tmp_path / "case"
    write_case(spec, case)
    proc = subprocess.Popen([*EHLFOAM, "run", str(case), "--quiet", "--wall-limit", "300"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        return case, proc, _solver_of(proc, case)
    except BaseException:
        proc.kill()
        raise


@pytest.mark.openfoam
def test_a_solver_killed_by_a_segfault_crashed(tmp_path):
    """A solver that dies on a segmentation fault after its first steps (a library, memory,
    two runs' MPI segments) crashed: the run fails, keeps its log, and ``reason`` names the
    signal (read from the log). (A floating-point trap is a divergence:
    test_diverging_run_keeps_logs_and_is_marked_failed.) A signal sent from outside may land
    inside the C library and hang OpenFOAM's handler; the watch then kills the solver
    (test_a_hung_solver_is_killed) and ``reason`` says so."""
    case, proc, solver = _run_and_find_solver(tmp_path)
    try:
        os.kill(solver, signal.SIGSEGV)
    finally:
        out = proc.communicate(timeout=120)[0]
    m = json.loads((case / "metrics.json").read_text())
    assert (m["status"], m["end_reason"]) == ("failed", "crashed"), out
    assert m["time_steps"] > 0 and (case / "log.interFoam").stat().st_size > 0
    assert ("signal 11 (Segmentation fault)" in m["reason"]
            or "still for" in m["reason"]), m["reason"]


@pytest.mark.openfoam
@pytest.mark.parametrize("backtrace, end, words", [
    ("", "crashed", "its log and its CPU time were still for"),
    ("#0  Foam::error::printStack(Foam::Ostream&) at ??\n#1  Foam::sigFpe::sigHandler(int)",
     "diverged", "signal 8 (Floating point exception), a floating-point trap; it then hung")])
def test_a_hung_solver_is_killed(tmp_path, backtrace, end, words):
    """A solver whose crash handler hangs (a signal inside the C library leaves it waiting on
    a lock, before or while it prints a backtrace) is alive, silent and idle: here it is
    stopped (SIGSTOP), the log ending where such a handler stopped. The watch kills it after
    HANG_POLLS still polls, long before the wall limit, and the run ends on what the log
    says: the signal where the handler names it (a floating-point trap: diverged), crashed
    where it names none."""
    case, proc, solver = _run_and_find_solver(tmp_path)
    try:
        os.kill(solver, signal.SIGSTOP)
        with open(case / "log.interFoam", "a") as log:   # a line the handler did not end
            log.write(backtrace)
        t0 = time.monotonic()
    finally:
        out = proc.communicate(timeout=120)[0]
    waited = time.monotonic() - t0
    m = json.loads((case / "metrics.json").read_text())
    assert (m["status"], m["end_reason"]) == ("failed", end), out
    assert words in m["reason"] and m["time_steps"] > 0, m["reason"]
    assert waited >= (HANG_POLLS - 1) * POLL_S, waited   # and ended long before 300 s


@pytest.mark.openfoam
def test_static_meniscus_stays_put(tmp_path):
    """Walls at rest, no supply, a puddle around the island, default settings (the polar
    ring, cAlpha 1): the meniscus stays where it started, the oil volume holds, and the
    spurious currents stay below the level measured for these defaults (a regression guard:
    the issue's 1 % of u is not reached at cAlpha 1, docs/validation.md#v-static-meniscus)."""
    from foamlib import FoamFieldFile

    from ehlfoam.run import fields as case_fields

    spec = make_case_spec({**SMALL, "walls_moving": False,
                           "supply": {"mode": "layers", "disc_layer": 0.0, "ball_layer": 0.0,
                                      "initial_puddle": 3.0},
                           "run": {"end_time": 4e-3, "writes_per_transit": 100}})
    case = tmp_path / "static"
    write_case(spec, case)
    m = run_case(case, wall_limit=300)
    assert m["status"] == "finished", m
    last = case_fields.time_folders(case)[-1][1]
    U = np.linalg.norm(np.asarray(FoamFieldFile(last / "U").internal_field, float), axis=1)
    alpha = np.asarray(FoamFieldFile(last / "alpha.oil").internal_field, float)
    # measured on this case: the 99th percentile of the speed in the oil is ~10 % of u with
    # the default interface compression (at rest the default schemes give 1-16 % of u,
    # docs/validation.md#v-static-meniscus); the 1 % is not reached. This guards
    # against regressions of that level and of the meniscus position.
    u_oil = float(np.percentile(U[alpha > 0.99], 99))
    assert u_oil < 0.2 * spec.speed, f"spurious velocity in the oil {u_oil:.3g} m/s"
    # within a third of the test mesh's cells there (~0.6 a; 0.03 a at the coarse level)
    assert m["inlet_meniscus_distance_over_a"] == pytest.approx(2.0, abs=0.2)
    assert m["oil_volume_m3"] == pytest.approx(m["oil_volume_initial_m3"], rel=1e-3)


#: (puddle radius [a], run options) of the static meniscus below 1 % of u at the default
#: compression (cAlpha 1), with the balanced interface schemes;
#: docs/validation.md#v-static-meniscus, docs/models/interface.md#numerics. The quiet
#: configuration at 3 a (three MULES sub-cycles and half the capillary limit: 0.70 % on this
#: case) takes some 100-200 s: bench/static_meniscus.py measures it.
QUIET_STATICS = {
    # at 5 a, where the nominal rolling meniscus's sides sit: the default time step and
    # sub-cycles (nominal gap, second half: 0.50 / 0.27 / 0.45 % coarse / medium / fine; the
    # standard schemes 1.1 / 6.7 / 15.8 %; measured on this case: 0.50 %, standard 1.10 %)
    "default step, 5 a": (5.0, {}),
}


@pytest.mark.openfoam
@pytest.mark.parametrize("config", list(QUIET_STATICS))
def test_static_meniscus_moves_less_than_1_percent_of_u_with_balanced_schemes(tmp_path, config):
    """Where the issue's 1 % holds at the default compression (cAlpha 1), here on the coarse
    level: the balanced interface schemes (at 3 a also three sub-cycles and half the
    capillary limit, the quiet configuration: bench/static_meniscus.py). What moves a
    meniscus in a thin gap is the gap-averaged oil velocity; at every write of the second
    half of 60 ms its largest value stays below 1 % of u, the meniscus stays where it
    started and the oil volume holds."""
    speed = 0.008
    puddle, run_options = QUIET_STATICS[config]
    spec = make_case_spec({
        "name": "static-quiet", "walls_moving": False,
        "contact": {"speed": speed, "grid": SMALL["contact"]["grid"],
                    "tol_residual": SMALL["contact"]["tol_residual"]},
        "mesh": {"resolution": "coarse"},
        "supply": {"mode": "layers", "disc_layer": 0.0, "ball_layer": 0.0,
                   "initial_puddle": puddle},
        "physics": {"interface_schemes": "balanced"},
        "run": {"end_time": 0.06, "writes_per_transit": 200, **run_options}})
    case = tmp_path / "static-quiet"
    write_case(spec, case)
    m = run_case(case, wall_limit=600)
    assert m["status"] == "finished", m
    st = case_fields.Structure.load(case)
    times = case_fields.time_folders(case)
    end = float(times[-1][0])

    def column_speeds(folder: Path) -> np.ndarray:
        U = np.asarray(FoamFieldFile(folder / "U").internal_field, float)
        alpha = np.asarray(FoamFieldFile(folder / "alpha.oil").internal_field, float)
        return st.oil_column_speeds(U, alpha)

    late = max(column_speeds(folder).max() for t, folder in times if float(t) >= 0.5 * end)
    assert late < 0.01 * speed, f"gap-averaged oil speed {late:.3g} m/s"
    # the inlet meniscus is measured from x = -a
    assert m["inlet_meniscus_distance_over_a"] + 1.0 == pytest.approx(puddle, abs=0.1)
    assert m["oil_volume_m3"] == pytest.approx(m["oil_volume_initial_m3"], rel=1e-3)


@pytest.mark.openfoam
@pytest.mark.skipif(os.geteuid() != 0 or shutil.which("unshare") is None,
                    reason="parallel runs of the embedded runtime need root and unshare")
def test_parallel_run_matches_serial(small_case, tmp_path):
    """decomposePar + mpirun on 2 ranks: same oil volume as the serial run."""
    spec = make_case_spec({**SMALL, "run": {**SMALL["run"], "end_time": 3e-4, "n_procs": 2}})
    case = tmp_path / "parallel"
    write_case(spec, case)
    m = run_case(case, wall_limit=300)
    assert m["status"] == "finished" and m["end_reason"] == "end_time", m
    assert (case / "processor1").is_dir()
    serial = _copy(small_case, tmp_path)
    with FoamFile(serial / "system" / "controlDict") as f:
        f["endTime"] = 3e-4
        f["writeInterval"] = 1e-4
    s = run_case(serial, wall_limit=300)
    assert m["simulated_time_s"] == pytest.approx(s["simulated_time_s"])
    assert m["oil_volume_m3"] == pytest.approx(s["oil_volume_m3"], rel=1e-3)


@pytest.mark.openfoam
@pytest.mark.skipif(os.geteuid() != 0 or shutil.which("unshare") is None,
                    reason="parallel runs of the embedded runtime need root and unshare")
def test_parallel_runs_side_by_side_keep_their_shared_memory_apart(tmp_path):
    """Two 2-rank runs at once (a batch's jobs with run.n_procs = 2): each run's ranks share
    memory with their own run only, so both finish with the same answer. Their segments were
    kept in the runtime's /dev/shm under a job id the same in every run's namespace: one
    run's ranks crashed with a segmentation fault, the other's hung."""
    spec = make_case_spec({**SMALL, "run": {**SMALL["run"], "end_time": 3e-4, "n_procs": 2}})
    cases = [tmp_path / name for name in ("a", "b")]
    for case in cases:
        write_case(spec, case)
    procs = [subprocess.Popen([*EHLFOAM, "run", str(case), "--quiet", "--wall-limit", "120"],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
             for case in cases]
    outs = [p.communicate(timeout=300)[0] for p in procs]
    ends = [json.loads((case / "metrics.json").read_text()) for case in cases]
    for m, out in zip(ends, outs):
        assert (m["status"], m["end_reason"]) == ("finished", "end_time"), out
    assert ends[0]["oil_volume_m3"] == pytest.approx(ends[1]["oil_volume_m3"], rel=1e-9)


@pytest.mark.openfoam
@pytest.mark.skipif(os.geteuid() != 0 or shutil.which("unshare") is None,
                    reason="parallel runs of the embedded runtime need root and unshare")
def test_parallel_restart_decomposes_its_latest_time_only(tmp_path):
    """A reconstructed case (no processor folders: say one run serially before) restarts on
    2 ranks from its latest time: decomposePar takes that time only, not every write, and the
    run goes on from it with its earlier writes in its history."""
    spec = make_case_spec({**SMALL, "run": {**SMALL["run"], "end_time": 2e-4, "n_procs": 2}})
    case = tmp_path / "restart"
    write_case(spec, case)
    first = run_case(case, wall_limit=300)
    assert first["status"] == "finished", first
    before = [t for t, _ in case_fields.time_folders(case)]
    assert len(before) >= 2
    for p in case.glob("processor*"):
        shutil.rmtree(p)
    with FoamFile(case / "system" / "controlDict") as f:
        f["endTime"] = 4e-4
    m = run_case(case, wall_limit=300)
    assert m["status"] == "finished" and m["end_reason"] == "end_time", m
    decomposed = [t for t, _ in case_fields.time_folders(case / "processor0")]
    assert min(decomposed) == pytest.approx(before[-1]), (decomposed, before)
    history = read_history(case / "history.csv")["time_s"]
    assert history[0] == pytest.approx(before[0]) and history[-1] >= 4e-4 * (1 - 1e-6)


@pytest.mark.openfoam
def test_stopped_run_samples_its_last_writes(tmp_path):
    """SIGTERM stops a serial run through controlDict (writeNow); its history.csv still holds
    every time it wrote, the last one included, and it is marked interrupted, not failed."""
    spec = make_case_spec({**SMALL, "run": {**SMALL["run"], "end_time": 0.05}})
    case = tmp_path / "stopped"
    write_case(spec, case)
    proc = subprocess.Popen([*EHLFOAM, "run", str(case), "--quiet"], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    deadline = time.monotonic() + 120
    while len(case_fields.time_folders(case)) < 3 and proc.poll() is None:
        assert time.monotonic() < deadline, "the run wrote no three times in 120 s"
        time.sleep(0.2)
    proc.send_signal(signal.SIGTERM)
    out, _ = proc.communicate(timeout=120)
    m = json.loads((case / "metrics.json").read_text())
    assert m["end_reason"] == "interrupted" and m["status"] == "interrupted", (m, out)
    written = [t for t, _ in case_fields.time_folders(case)]
    assert len(written) >= 3 and (case / "history.csv").is_file(), (written, out)
    assert list(read_history(case / "history.csv")["time_s"]) == pytest.approx(written)


@pytest.mark.openfoam
def test_full_domain_case_builds_and_runs(tmp_path):
    """symmetry = "full": both sides meshed, no symmetry patch, the same supply."""
    spec = make_case_spec({**SMALL, "domain": {**SMALL["domain"], "symmetry": "full"},
                           "run": {**SMALL["run"], "end_time": 2e-4}})
    case = tmp_path / "full"
    geom = write_case(spec, case)
    assert not geom.symmetric
    boundary = (case / "constant" / "polyMesh" / "boundary").read_text()
    assert "symmetry" not in boundary and "supply" in boundary
    log = FoamRuntime.from_environment().run("checkMesh", [], cwd=case).stdout
    assert "Mesh OK." in log
    m = run_case(case, wall_limit=120)
    assert m["status"] == "finished", m
    # the supply covers the whole track (both sides): the same flux as the half domain's total
    assert m["oil_inflow_m3_s"] == pytest.approx(0.02 * 6e-6 * 5e-4, rel=1e-6)


@pytest.mark.openfoam
def test_monitor_stops_a_steady_run(tmp_path):
    """A meniscus at rest is (nearly) steady: the monitor sees it hold still over one transit
    and stops the solver through controlDict before the time limit, at the write after the
    steady one (endTime set to it): two runs of the case end at the same write with the same
    metrics, whatever the wall clock. The tolerance is loose (0.2) because on this coarse test
    mesh the puddle creeps by ~0.01 a/ms as it relaxes; the test is about the stop
    mechanism."""
    spec = make_case_spec({**SMALL, "walls_moving": False,
                           "supply": {"mode": "layers", "disc_layer": 0.0, "ball_layer": 0.0,
                                      "initial_puddle": 3.0},
                           "run": {"transit_length": 1.0, "transits_max": 60.0,
                                   "writes_per_transit": 5, "steady_tolerance": 0.2}})
    case = tmp_path / "steady"
    write_case(spec, case)
    twin = _copy(case, tmp_path / "twin")
    m = run_case(case, wall_limit=300)
    assert m["status"] == "finished" and m["end_reason"] == "steady" and m["steady"], m
    assert m["simulated_time_s"] < 0.5 * spec.end_time
    control = FoamFile(case / "system" / "controlDict")
    assert control["stopAt"] == "endTime"
    last = case_fields.time_folders(case)[-1][0]
    assert control["endTime"] == pytest.approx(last) == pytest.approx(m["simulated_time_s"])
    again = run_case(twin, wall_limit=300)
    clock = {"wall_s", "wall_s_per_simulated_ms"}
    assert ({k: v for k, v in again.to_json().items() if k not in clock}
            == {k: v for k, v in m.to_json().items() if k not in clock})
    # --extend: two more transits past the stop, whatever the steady tests say
    t_stop, transit = m["simulated_time_s"], m["transit_time_s"]
    e = run_case(case, wall_limit=300, extend_transits=2.0)
    assert e["status"] == "finished" and e["end_reason"] == "end_time" and not e["steady"], e
    assert e["simulated_time_s"] == pytest.approx(t_stop + 2.0 * transit, rel=1e-3)
    with pytest.raises(ValueError, match="extend_transits = 0"):
        run_case(case, extend_transits=0)


@pytest.mark.openfoam
def test_cli_run_prints_metrics_and_exit_code(small_case, tmp_path):
    case = _copy(small_case, tmp_path)
    with FoamFile(case / "system" / "controlDict") as f:
        f["writeInterval"] = 1e-4
    # --extend on a case that has not run yet counts from its start: 2e-4 s of simulated time
    transits = 2e-4 / load_geometry(case).transit_time
    proc = subprocess.run([*EHLFOAM, "run", str(case), "--extend", f"{transits!r}"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.strip().splitlines()
    assert any(ln.startswith("t =") and "state" in ln for ln in lines)   # progress lines
    result = json.loads(lines[-1])
    assert result["status"] == "finished" and result["end_reason"] == "end_time"
    assert result["simulated_time_s"] == pytest.approx(2e-4, rel=1e-3)
    busy = subprocess.run([*EHLFOAM, "run", str(tmp_path / "nowhere")], capture_output=True,
                          text=True)
    assert busy.returncode == 2 and "nowhere" in busy.stderr
    bad = subprocess.run([*EHLFOAM, "run", str(case), "--extend", "-1"], capture_output=True,
                         text=True)
    assert bad.returncode == 2 and "--extend" in bad.stderr and "> 0" in bad.stderr


@pytest.mark.openfoam
def test_single_phase_case_stays_oil(tmp_path):
    """The single-phase scene (oil everywhere, the Reynolds check): oil is what enters on
    every open boundary, the fixed upstream one included, so no air appears in 1 ms."""
    case = tmp_path / "single"
    write_case(make_case_spec({**SMALL, "scene": "single-phase"}), case)
    with FoamFile(case / "0.orig" / "alpha.oil") as f:
        assert f["boundaryField"]["inlet"]["value"] == 1.0
        assert f["boundaryField"]['"(outlet|side)"']["inletValue"] == 1.0
    m = run_case(case, wall_limit=120)
    assert m["status"] == "finished", m.get("log_tail")
    last = case_fields.time_folders(case)[-1][1]
    alpha = np.asarray(FoamFieldFile(last / "alpha.oil").internal_field, dtype=float)
    assert alpha.min() > 0.999
    # the oil meets every boundary by design: no warning that the region reached one
    assert m["flooded_clearance_over_a"] == 0.0
    assert "boundary" not in m["warnings"], m["warnings"]
    # and lays no films at a rear meniscus
    assert m["rear_meniscus_cell_over_a"] is None and "rear meniscus" not in m["warnings"]
    # nor meets dry walls with a contact line
    assert m["front_contact_line_cells_over_wall_cell"] is None
