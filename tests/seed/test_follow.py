"""The following levels (``mesh.follow``): a mesh with bands of the level's cells along the
meniscus of the state the case starts from (ehlfoam.seed.follow)."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

from ehlfoam.errors import SpecError
from ehlfoam.spec.case import make_case_spec
from ehlfoam.spec.levels import FOLLOW_BASE, FOLLOW_LEVELS, FOLLOW_POLAR_RADIUS
from ehlfoam.spec.mesh import RefineBand, SideBox
from ehlfoam.case.geometry import load_geometry
from ehlfoam.case.writer import write_case
from ehlfoam.seed.band import side_bands
from tests.case.test_writer import EHLFOAM, _thin_film_state, _toml
from tests.tiny import SMALL

ROOT = Path(__file__).resolve().parents[2]

SIDES = {"x_min": -1.0, "x_max": 8.0, "y_min": 5.0}


@pytest.mark.parametrize("level", ["coarse", "medium", "fine"])
def test_a_following_level_sets_its_band_and_wall_cell_on_the_common_base(level):
    """With mesh.follow the level sets the band's cells and one wall cell (FOLLOW_LEVELS);
    the in-plane base cells and 20 layers are common to the three, the polar ring ends at
    3 a, and an explicit override still wins."""
    spec = make_case_spec(**{"mesh.resolution": level, "mesh.follow": {"sides": SIDES}})
    got = spec.mesh.level()
    assert got == {**FOLLOW_BASE, "wall_grading": None,
                   "wall_cell": FOLLOW_LEVELS[level]["wall_cell"]}
    assert spec.mesh.follow_band == FOLLOW_LEVELS[level]["band"]
    assert spec.polar_radius == FOLLOW_POLAR_RADIUS
    assert make_case_spec(**{"mesh.resolution": level}).mesh.follow_band is None
    thicker = make_case_spec(**{"mesh.resolution": level, "mesh.follow": {},
                                "mesh.wall_cell": 5e-6, "mesh.n_layers": 8})
    assert thicker.mesh.level()["wall_cell"] == 5e-6 and thicker.mesh.level()["n_layers"] == 8
    graded = make_case_spec(**{"mesh.resolution": level, "mesh.follow": {},
                               "mesh.wall_grading": 4.0}).mesh.level()
    assert graded["wall_grading"] == 4.0 and graded["wall_cell"] is None


@pytest.mark.parametrize("follow, names", [
    ({"half_width": 0.0}, "mesh.follow.half_width"),
    ({"sides": {"x_min": 3.0, "x_max": 1.0}}, "x_min = 3 a must be below x_max = 1 a"),
    ({"sides": {"x_min": 0.0, "x_max": 1.0, "y_min": -2.0}}, "mesh.follow.sides.y_min"),
    ({"sides": {"x_min": 0.0, "x_max": 1.0, "size": 0.0}}, "mesh.follow.sides.size"),
    ({"spacing": 0.2}, "mesh.follow.spacing"),
])
def test_a_bad_follow_is_refused_naming_the_key(follow, names):
    with pytest.raises(SpecError, match=names.replace("(", r"\(")):
        make_case_spec(**{"mesh.follow": follow})


def test_side_bands_take_the_runs_of_points_in_the_box_at_half_the_cells():
    """Each run of consecutive points inside the sides' box becomes a band of half the size
    and half the half-width, or of the box's own size and half-width; a run of one point,
    and the points outside, do not."""
    pts = [(-3.0, 0.0), (-2.0, 5.5), (0.0, 6.0), (2.0, 6.5), (4.0, 4.0), (6.0, 5.5),
           (7.0, 6.0), (9.0, 6.0), (10.0, 5.2), (12.0, 0.0)]
    band = RefineBand(points=tuple(pts), half_width=1.0, size=0.24)
    sides = side_bands([band], SideBox(**SIDES))
    assert [b.points for b in sides] == [((0.0, 6.0), (2.0, 6.5)), ((6.0, 5.5), (7.0, 6.0))]
    assert all(b.size == 0.12 and b.half_width == 0.5 for b in sides)
    assert side_bands([band], SideBox(x_min=20.0, x_max=30.0)) == []
    own = side_bands([band], SideBox(**SIDES, size=0.03, half_width=0.25))
    assert [b.points for b in own] == [b.points for b in sides]
    assert all(b.size == 0.03 and b.half_width == 0.25 for b in own)


def test_cli_case_with_follow_needs_a_start_and_write_case_refuses_it(tmp_path):
    """Without --start-from there is no meniscus to follow: exit 2, nothing written; the
    case writer itself refuses a spec that still has mesh.follow."""
    spec = tmp_path / "small.toml"
    spec.write_text(_toml(SMALL))
    out = tmp_path / "case"
    proc = subprocess.run([*EHLFOAM, "case", str(spec), "--out", str(out), "--set",
                           "mesh.follow={half_width=0.5}"], capture_output=True, text=True)
    assert proc.returncode == 2 and "mesh.follow needs --start-from" in proc.stderr
    assert not out.exists()
    with pytest.raises(ValueError, match="mesh.follow needs the state the case starts from"):
        write_case(make_case_spec(SMALL, **{"mesh.follow": {}}), out)
    assert not out.exists()


def test_cli_case_follows_the_meniscus_of_the_state_it_starts_from(tmp_path):
    """`ehlfoam case --start-from STATE --set mesh.follow=...`: the mesh has bands of the
    level's cells along the state's meniscus (the state floods x < a: the band runs along
    x = a) and half as fine where the sides' box says; it starts from the state; its
    written spec has the bands and the level spelled out and no follow, and rebuilds the
    same mesh by itself."""
    a = make_case_spec(SMALL).a
    state = tmp_path / "state.npz"
    _thin_film_state(state, a, films=0.2)
    spec = tmp_path / "small.toml"
    spec.write_text(_toml({**SMALL, "mesh": {**SMALL["mesh"], "resolution": "medium"}}))
    plain, followed = tmp_path / "plain", tmp_path / "followed"
    common = ["--start-from", str(state)]
    proc = subprocess.run([*EHLFOAM, "case", str(spec), "--out", str(plain), *common],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    proc = subprocess.run([*EHLFOAM, "case", str(spec), "--out", str(followed), *common,
                           "--set", "mesh.follow={half_width=0.5,sides={x_min=0.5,x_max=1.5,"
                           "y_max=0.8}}"], capture_output=True, text=True)
    assert proc.returncode == 2 and "mesh.follow.sides.y_max" in proc.stderr
    assert not followed.exists()
    proc = subprocess.run([*EHLFOAM, "case", str(spec), "--out", str(followed), *common,
                           "--set", "mesh.follow={half_width=0.5,sides={x_min=0.5,x_max=1.5,"
                           "y_min=0.8}}"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "starts from" in proc.stdout and "thin-film" in proc.stdout
    written = json.loads((followed / "ehlfoam" / "spec.json").read_text())
    mesh = written["mesh"]
    assert mesh["follow"] is None and mesh["polar_radius"] == FOLLOW_POLAR_RADIUS
    assert (mesh["size_rim"], mesh["size_far"], mesh["n_layers"], mesh["wall_grading"]) == (
        0.25, 1.2, 3, 3.0)   # the small case's own, over the following levels' base
    band = FOLLOW_LEVELS["medium"]["band"]
    main = [b for b in mesh["refine"] if b["size"] == band]
    side = [b for b in mesh["refine"] if b["size"] == band / 2]
    assert main and side and len(main) + len(side) == len(mesh["refine"])
    assert all(b["half_width"] == 0.5 for b in main) and all(b["half_width"] == 0.25
                                                            for b in side)
    pts = np.concatenate([np.array(b["points"]) for b in main])
    rear = pts[(pts[:, 1] < 1.5) & (pts[:, 0] > 0)]   # the state's meniscus at x = a
    assert len(rear) >= 3 and np.abs(rear[:, 0] - 1.0).max() < 0.3
    sides = np.concatenate([np.array(b["points"]) for b in side])
    assert np.all((sides[:, 0] >= 0.5) & (sides[:, 0] <= 1.5) & (sides[:, 1] >= 0.8))
    cells = load_geometry(followed).cells
    assert cells > 1.2 * load_geometry(plain).cells
    ramp = json.loads((followed / "ehlfoam" / "ramp.json").read_text())
    assert ramp["method"] == "thin-film"
    again = write_case(make_case_spec(written), tmp_path / "again")
    assert again.cells == cells


def test_the_shipped_resolved_nominal_spec_is_the_converged_families_medium_level():
    """examples/cases/nominal_resolved.toml: the nominal case on the medium following level
    under the contact-line model whose three levels converge
    (docs/models/interface.md#the-contact-line-model-and-what-converges): the side band
    round the front off the track, walls halving with the side cells, 1 um slip, a 43 deg
    wall."""
    from ehlfoam.spec.case import load_case_spec

    spec = load_case_spec(ROOT / "examples" / "cases" / "nominal_resolved.toml")
    track = spec.supply.track_half_width / spec.a
    assert spec.mesh.follow is not None
    assert spec.mesh.follow.sides == SideBox(x_min=-8.0, x_max=8.0, y_min=2.2)
    assert track < spec.mesh.follow.sides.y_min < 1.01 * track
    assert spec.mesh.follow_band == 0.12 and spec.mesh.level()["wall_cell"] == 0.8e-6
    assert [FOLLOW_LEVELS[lv]["wall_cell"] for lv in ("coarse", "medium", "fine")] == \
        [1.6e-6, 0.8e-6, 0.4e-6]
    assert (spec.physics.wall_slip_length, spec.physics.contact_angle) == (1e-6, 43.0)
    assert spec.physics.interface_schemes == "balanced"
    assert spec.physics.isotropic_compression == 1.0
    assert (spec.domain.downstream, spec.domain.side) == (20.0, 10.0)
