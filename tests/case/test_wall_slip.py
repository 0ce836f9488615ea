"""Navier slip on the walls (ehlfoam.case.wall_slip): the directionMixed entry's algebra, its
writing, and that v1912's solver holds the wall's fluid at u_s - U_w = lambda du/dn."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from foamlib import FoamFieldFile

from ehlfoam.spec.case import make_case_spec
from ehlfoam.case.geometry import load_spec_of
from ehlfoam.case.writer import case_mesh, write_case
from ehlfoam.gap.source import load_gap
from ehlfoam.case.wall_slip import navier_slip, slip_fraction, wall_normals
from ehlfoam.run import fields as case_fields
from ehlfoam.run.monitor import run_case
from tests.tiny import SMALL

SLIP = 2e-6   # m: of the tiny case's wall cells' centre-to-face distances (0.5-5 um)


@pytest.fixture(scope="module")
def slip_case(tmp_path_factory):
    case = tmp_path_factory.mktemp("slip") / "slip"
    write_case(make_case_spec({**SMALL, "scene": "single-phase",
                               "physics": {"wall_slip_length": SLIP}}), case)
    return case


def _mesh(case):
    """The case's mesh as the generator built it (the build is deterministic)."""
    spec = load_spec_of(case)
    return case_mesh(spec, load_gap(spec.contact)[0])[2]


def test_value_fraction_holds_the_normal_and_a_share_of_the_tangent(slip_case):
    mesh = _mesh(slip_case)
    entry = navier_slip(mesh, "ball", np.zeros(3), SLIP)
    f = slip_fraction(mesh, "ball", SLIP)
    assert 0.05 < f.min() and f.max() < 0.95        # the tiny case's cells span the slip
    n = wall_normals(mesh, "ball")
    xx, xy, xz, yy, yz, zz = entry["valueFraction"].T
    vf = np.stack([np.stack([xx, xy, xz], 1), np.stack([xy, yy, yz], 1),
                   np.stack([xz, yz, zz], 1)], 1)
    t = np.cross(n, [0.0, 1.0, 0.0])
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    np.testing.assert_allclose(np.einsum("fij,fj->fi", vf, n), n, atol=1e-12)
    np.testing.assert_allclose(np.einsum("fij,fj->fi", vf, t), f[:, None] * t, atol=1e-12)
    # no slip is f = 1; a negative length is refused, naming it
    np.testing.assert_allclose(slip_fraction(mesh, "disc", 0.0), 1.0)
    with pytest.raises(ValueError, match="slip_length: -1e-06"):
        slip_fraction(mesh, "disc", -1e-6)


def test_spec_refuses_a_slip_beyond_its_range():
    with pytest.raises(Exception, match="wall_slip_length"):
        make_case_spec({**SMALL, "physics": {"wall_slip_length": 1e-3}})


@pytest.mark.openfoam
def test_solver_holds_the_walls_fluid_at_the_navier_slip(slip_case, tmp_path):
    """After 1 ms of the single-phase flow, every disc and ball face's written velocity is the
    wall's plus (1 - f) of its cell's tangential velocity relative to the wall, and none
    through the wall: what a slip length means on the wall cell. Off the supply track only:
    on it (|y| < supply.track_half_width) the walls come in wetted and keep no slip."""
    case = tmp_path / "run"
    shutil.copytree(slip_case, case)
    m = run_case(case, wall_limit=120)
    assert m["status"] == "finished", m.get("log_tail")
    mesh = _mesh(case)
    last = case_fields.time_folders(case)[-1][1]
    with FoamFieldFile(last / "U") as f:
        cells = np.asarray(f.internal_field, float)
        faces = {p: np.asarray(f.boundary_field[p]["value"], float) for p in ("disc", "ball")}
        walls = {p: np.asarray(f.boundary_field[p]["refValue"], float) for p in ("disc", "ball")}
    for patch in ("disc", "ball"):
        sl = mesh.patch_slice(patch)
        n = wall_normals(mesh, patch)
        dry = np.abs(mesh.face_centres[sl, 1]) > SMALL["supply"]["track_half_width"]
        assert 0 < dry.sum() < len(dry)
        rel = cells[mesh.owner[sl]] - walls[patch]
        rel_t = rel - n * np.einsum("fd,fd->f", n, rel)[:, None]
        slip = 1.0 - slip_fraction(mesh, patch, np.where(dry, SLIP, 0.0))
        assert slip[dry].min() > 0.05 and slip[~dry].max() == 0.0
        expect = walls[patch] + slip[:, None] * rel_t
        assert np.abs(rel_t).max() > 1e-4                # the fluid does move on the wall
        np.testing.assert_allclose(faces[patch], expect, atol=1e-6 * np.abs(rel_t).max())
        assert np.abs(np.einsum("fd,fd->f", n, faces[patch] - walls[patch])).max() < 1e-8
