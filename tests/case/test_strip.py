"""The 2D strip cases (ehlfoam.case.strip): the strip's columns follow the gap, a fed bridge
runs in the real OpenFOAM and lays films behind its rear meniscus, and with its walls turned
round dry walls advance into a bridge that a reservoir feeds, less far when they slip."""

from __future__ import annotations

import numpy as np
import pytest
from foamlib import FoamFieldFile, FoamFile

from ehlfoam.case.strip import reverse_walls, strip_mesh, supply_cell_size, write_strip_case
from ehlfoam.foam.runtime import FoamRuntime
from ehlfoam.gap.source import load_gap
from ehlfoam.metrics.strip import columns, film_history
from ehlfoam.run.fields import time_folders
from ehlfoam.spec.case import make_case_spec
from ehlfoam.thinfilm.bridge import x_at_gap
from ehlfoam.thinfilm.problem import landau_levich
from tests.tiny import SMALL, small_contact


@pytest.fixture(scope="module")
def small():
    return small_contact()


def _run(case):
    FoamRuntime.from_environment().run("interFoam", cwd=case, log_path=case / "log.interFoam")


def test_the_strip_columns_hold_the_gap_and_the_oil(small):
    spec, gap, a = small
    mesh = strip_mesh(spec, gap, 3 * a, 10 * a, 0.5 * a)
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


def test_cells_finer_than_the_columns_lean_at_the_supply_stay_right_side_out():
    """The normal columns lean upstream by h h' / 2 at the ball, 0.037 a at 9 a on the nominal
    gap: uniform cells of 0.035 a from there turned the first ones inside out (the strip then
    diverged within 2 ms); the strip grows its cells near the supply."""
    spec = make_case_spec({"mesh": {"resolution": "fine"}})
    gap, _ = load_gap(spec.contact)
    a = spec.a
    assert 0.035 * a < supply_cell_size(gap, 9 * a) < 0.1 * a
    strip = strip_mesh(spec, gap, 9 * a, 12 * a, 0.035 * a)
    assert strip.cell_volumes.min() > 0
    x, _, _ = columns(strip, np.zeros(strip.n_cells))
    assert np.isclose(x[-1] - x[-2], 0.035 * a, rtol=0.05)          # dx where it is read
    assert x[1] - x[0] > 1.5 * 0.035 * a                              # coarser at the supply


@pytest.mark.openfoam
def test_a_fed_bridge_runs_and_lays_films_behind_its_rear_meniscus(small, tmp_path):
    """The bridge reaches past where Landau-Levich's films balance the feed (5.7 a), so its
    rear meniscus recedes and the walls carry films of about that law's thickness out of it.

    On 6 layers: the films, 0.033 of the gap a wall, fill 40 % of a wall cell (0.083 of the
    gap). On the tiny case's 3 layers (wall cells 0.2 of the gap, 17 % full) interFoam lays
    no film at all: its columns behind the meniscus held round-off only (1e-29 m with one
    precalc, exactly 0 with another whose gap differs by 4 pm)."""
    _, gap, a = small
    spec = make_case_spec({**SMALL, "mesh": {**SMALL["mesh"], "n_layers": 6}})
    mesh = strip_mesh(spec, gap, 3 * a, 10 * a, 0.5 * a)
    case = tmp_path / "strip"
    dt = write_strip_case(spec, case, mesh, x_bridge=7 * a, film=2e-6, dx=0.5 * a,
                          end_time=0.03, write_interval=0.01)
    assert 0 < dt < 0.01
    assert FoamFile(case / "system" / "controlDict")["maxDeltaT"] == pytest.approx(dt)
    _run(case)
    rows = film_history(time_folders(case), mesh, a, 10 * a)
    assert [r["t_s"] for r in rows] == pytest.approx([0.01, 0.02, 0.03])
    assert all(6.5 < r["x_rear_over_a"] < 7.5 for r in rows)   # a bridge, not drained nor spilled
    assert rows[-1]["x_rear_over_a"] < rows[0]["x_rear_over_a"]   # the films take the feed
    last = rows[-1]
    ll = landau_levich(spec.oil_viscosity, spec.speed, spec.physics.surface_tension)
    assert x_at_gap(gap, 2e-6 / ll, 3 * a, 10 * a) < 6.0 * a      # where they balance it
    # the walls carry films out: at least half Landau-Levich's, thinner than 0.3 of the gap
    assert 0.5 * ll < last["deposited_fraction"] < 0.3
    assert last["deposited_fraction"] == pytest.approx(last["film_m"] / last["gap_rear_m"])
    assert last["oil_per_width_m2"] > 0


@pytest.mark.openfoam
def test_dry_walls_run_into_a_bridge_fed_by_the_reservoir(small, tmp_path):
    spec, gap, a = small
    mesh = strip_mesh(spec, gap, 4 * a, 10 * a, 0.5 * a)
    case = tmp_path / "strip"
    write_strip_case(spec, case, mesh, x_bridge=7 * a, film=0.0, dx=0.5 * a, end_time=0.02,
                     write_interval=0.01)
    reverse_walls(spec, case)
    u = FoamFile(case / "0" / "U")["boundaryField"]
    assert u["disc"]["value"][0] == pytest.approx(-spec.wall_speed)
    assert u["ball"]["omega"] == pytest.approx(spec.wall_speed / spec.contact.radius)
    assert u["supply"]["type"] == "pressureInletOutletVelocity"
    assert FoamFile(case / "0" / "alpha.oil")["boundaryField"]["supply"]["inletValue"] == 1.0
    _run(case)
    rows = film_history(time_folders(case), mesh, a, 10 * a)
    assert [r["t_s"] for r in rows] == pytest.approx([0.01, 0.02])
    # the walls drag the oil towards the reservoir: on cells this coarse the meniscus holds
    # no suction that could stop it, and the reservoir keeps the bridge's narrow end full
    assert rows[-1]["x_rear_over_a"] < rows[0]["x_rear_over_a"] < 7.0
    alpha = np.asarray(FoamFile(case / "0.02" / "alpha.oil")["internalField"], float)
    _, h, oil = columns(mesh, alpha)
    assert oil[0] == pytest.approx(h[0], rel=0.02)
    assert oil[-1] < 0.05 * h[-1]               # the walls come in dry


@pytest.mark.openfoam
def test_slipping_walls_drag_the_bridge_less(small, tmp_path):
    """The same strip with a slip of 5 um on both walls (physics.wall_slip_length): the walls
    are Navier-slip directionMixed walls at -u on every face, and over the same 0.02 s they drag
    the meniscus less far towards the reservoir than the no-slip walls do. Slipping walls
    need the strip's mesh."""
    _, gap, a = small
    moved = {}
    for lam in (0.0, 5e-6):
        s = make_case_spec({**SMALL, "physics": {"wall_slip_length": lam}})
        mesh = strip_mesh(s, gap, 4 * a, 10 * a, 0.5 * a)
        case = tmp_path / f"strip{lam:g}"
        write_strip_case(s, case, mesh, x_bridge=7 * a, film=0.0, dx=0.5 * a, end_time=0.02,
                         write_interval=0.01)
        if lam:
            with pytest.raises(ValueError, match="physics.wall_slip_length = 5e-06 m"):
                reverse_walls(s, case)
        reverse_walls(s, case, mesh=mesh)
        if lam:
            disc = FoamFieldFile(case / "0" / "U").boundary_field["disc"]
            assert disc["type"] == "directionMixed"
            np.testing.assert_allclose(disc["refValue"], [[-s.wall_speed, 0, 0]] * len(
                disc["refValue"]))
        _run(case)
        rows = film_history(time_folders(case), mesh, a, 10 * a)
        moved[lam] = 7.0 - rows[-1]["x_rear_over_a"]
    assert 0 < moved[5e-6] < 0.9 * moved[0.0], moved


@pytest.mark.openfoam
def test_a_dynamic_wall_gives_the_line_dry_walls_advance_its_advancing_angle(small, tmp_path):
    """The sign of v1912's dynamicAlphaContactAngle (ehlfoam.case.wall_angle): with advancing
    41 deg and receding 0 deg the walls running dry into the bridge drive its meniscus as far
    as a static 41 deg wall does, not as a 0 deg one (0.04 s on 0.25 a cells: 5.47 / 5.47 /
    6.47 a when written)."""
    _, gap, a = small
    reached = {}
    for name, physics in (("static41", {"contact_angle": 41.0}),
                          ("static0", {"contact_angle": 0.0}),
                          ("dynamic", {"advancing_angle": 41.0, "receding_angle": 0.0})):
        s = make_case_spec({**SMALL, "physics": physics})
        mesh = strip_mesh(s, gap, 4 * a, 10 * a, 0.25 * a)
        case = tmp_path / name
        write_strip_case(s, case, mesh, x_bridge=7 * a, film=0.0, dx=0.25 * a, end_time=0.04,
                         write_interval=0.04)
        reverse_walls(s, case)
        walls = FoamFile(case / "0" / "alpha.oil")["boundaryField"]['"(disc|ball|island)"']
        assert walls["type"] == ("dynamicAlphaContactAngle" if name == "dynamic"
                                 else "constantAlphaContactAngle")
        _run(case)
        reached[name] = film_history(time_folders(case), mesh, a, 10 * a)[-1]["x_rear_over_a"]
    spread = reached["static0"] - reached["static41"]
    assert spread > 0.5, reached                    # the angle matters on these cells
    assert abs(reached["dynamic"] - reached["static41"]) < 0.2 * spread, reached
