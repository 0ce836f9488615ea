"""The contact-line strip (bench/contact_line_strip.py): its balance, the walls turned round,
and a short real interFoam run of a bridge that dry walls advance into."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from foamlib import FoamFieldFile, FoamFile

from bench.contact_line_strip import (angle_at_meniscus, balance, meniscus_for_angle,
                                      reverse_walls, wall_rows)
from bench.film_deposition import columns, measure, strip_mesh, write_strip_case
from ehlfoam.spec.case import make_case_spec
from ehlfoam.gap.source import load_gap
from ehlfoam.foam.runtime import FoamRuntime
from tests.tiny import SMALL


@pytest.fixture(scope="module")
def strip():
    spec = make_case_spec(SMALL)
    gap, _ = load_gap(spec.contact)
    a = spec.a
    return spec, gap, a, strip_mesh(spec, gap, 4 * a, 10 * a, 0.5 * a)


def test_the_meniscus_position_and_its_apparent_angle_invert_each_other(strip):
    spec, gap, a, _ = strip
    table = balance(spec, gap, 4 * a, 10 * a)
    x = [meniscus_for_angle(spec, table, t) for t in (15.0, 30.0, 47.0, 70.0)]
    assert all(4 * a < xi < 10 * a for xi in x)
    assert x == sorted(x, reverse=True)         # less suction: nearer the reservoir
    for theta, xi in zip((15.0, 30.0, 47.0, 70.0), x):
        assert angle_at_meniscus(spec, table, xi) == pytest.approx(theta, abs=0.5)
    # at the reservoir no drag has built up: no angle below a right one balances there
    assert np.isnan(angle_at_meniscus(spec, table, 4 * a))


def test_a_slip_takes_its_share_of_the_drag_off_the_balance(strip):
    """On a gap of uniform height h, walls slipping by lambda let the pressure drive
    (1 + 6 lambda / h) times the flux, so the drag's pressure drop is that much smaller."""
    spec, _, a, _ = strip
    h, lam = 30e-6, 1e-6
    slipping = make_case_spec({**SMALL, "physics": {"wall_slip_length": lam}})
    flat = lambda x, y: np.full_like(np.asarray(x, float), h)  # noqa: E731
    drop = balance(spec, flat, 4 * a, 10 * a)[3][-1]
    drop_slip = balance(slipping, flat, 4 * a, 10 * a)[3][-1]
    assert drop == pytest.approx(12 * spec.oil_viscosity * spec.speed * 6 * a / h**2, rel=1e-9)
    assert drop_slip == pytest.approx(drop / (1 + 6 * lam / h), rel=1e-9)


def test_dry_walls_run_into_a_bridge_fed_by_the_reservoir(strip, tmp_path):
    spec, gap, a, mesh = strip
    case = tmp_path / "strip"
    write_strip_case(spec, case, mesh, x_bridge=7 * a, film=0.0, dx=0.5 * a, end_time=0.02,
                     write_interval=0.01)
    reverse_walls(spec, case)
    u = FoamFile(case / "0" / "U")["boundaryField"]
    assert u["disc"]["value"][0] == pytest.approx(-spec.wall_speed)
    assert u["ball"]["omega"] == pytest.approx(spec.wall_speed / spec.contact.radius)
    assert u["supply"]["type"] == "pressureInletOutletVelocity"
    assert FoamFile(case / "0" / "alpha.oil")["boundaryField"]["supply"]["inletValue"] == 1.0
    FoamRuntime.from_environment().run("interFoam", cwd=case, log_path=case / "log.interFoam")
    rows = measure(case, mesh, a, 10 * a)
    assert [r["t_s"] for r in rows] == pytest.approx([0.01, 0.02])
    # the walls drag the oil towards the reservoir: on cells this coarse the meniscus holds
    # no suction that could stop it (docs/cases.md, "The region's sides are moving contact
    # lines"), and the reservoir keeps the bridge's narrow end full
    assert rows[-1]["x_rear_over_a"] < rows[0]["x_rear_over_a"] < 7.0
    alpha = np.asarray(FoamFile(case / "0.02" / "alpha.oil")["internalField"], float)
    _, h, oil = columns(mesh, alpha)
    assert oil[0] == pytest.approx(h[0], rel=0.02)
    assert oil[-1] < 0.05 * h[-1]               # the walls come in dry


def test_slipping_walls_drag_the_bridge_less(strip, tmp_path):
    """The same strip with a slip of 5 um on both walls (physics.wall_slip_length): the walls
    are Navier-slip directionMixed walls at -u on every face, and over the same 0.02 s they drag
    the meniscus less far towards the reservoir than the no-slip walls do."""
    spec, gap, a, mesh = strip
    moved = {}
    for lam in (0.0, 5e-6):
        s = make_case_spec({**SMALL, "physics": {"wall_slip_length": lam}})
        case = tmp_path / f"strip{lam:g}"
        write_strip_case(s, case, mesh, x_bridge=7 * a, film=0.0, dx=0.5 * a, end_time=0.02,
                         write_interval=0.01)
        reverse_walls(s, case, mesh=mesh)
        if lam:
            disc = FoamFieldFile(case / "0" / "U").boundary_field["disc"]
            assert disc["type"] == "directionMixed"
            np.testing.assert_allclose(disc["refValue"], [[-s.wall_speed, 0, 0]] * len(
                disc["refValue"]))
        FoamRuntime.from_environment().run("interFoam", cwd=case, log_path=case / "log")
        rows = measure(case, mesh, a, 10 * a)
        moved[lam] = 7.0 - rows[-1]["x_rear_over_a"]
    assert 0 < moved[5e-6] < 0.9 * moved[0.0], moved


def test_wall_rows_read_the_stall_the_air_and_the_pressure_of_the_wall_cells(strip, tmp_path):
    """Fields with a known answer: oil up to x = 6.5 a with 3 % air in its wall cells, whose
    pressure stands 250 Pa over mid-gap; the wall cells move with their walls (-u) but for
    the four columns around the meniscus (two oil, two air), which are at rest."""
    spec, gap, a, mesh = strip
    case = tmp_path / "strip"
    write_strip_case(spec, case, mesh, x_bridge=6.5 * a, film=0.0, dx=0.5 * a, end_time=0.01,
                     write_interval=0.01)
    n = int(mesh.layer.max()) + 1
    x = mesh.cell_centres[:, 0]
    wall = (mesh.layer == 0) | (mesh.layer == n - 1)
    alpha = np.where(x < 6.5 * a, np.where(wall, 0.97, 1.0), 0.0)
    u = np.zeros((mesh.n_cells, 3))
    u[wall, 0] = -spec.wall_speed
    stalled = wall & (np.abs(x - 6.5 * a) < 0.8 * a)       # columns at 5.75-7.25 a
    u[stalled, 0] = 0.0
    p = np.where(wall & (x < 6.5 * a), 250.0, 0.0)
    folder = case / "0.01"
    shutil.copytree(case / "0", folder)
    for name, value in (("alpha.oil", alpha), ("U", u), ("p_rgh", p)):
        with FoamFieldFile(folder / name) as f:
            f.internal_field = value
    rows = wall_rows(folder, mesh, spec.wall_speed, 6.5 * a, 1.0 * a)
    columns_at_rest = len(np.unique(mesh.base_cell[stalled]))
    assert columns_at_rest == 4
    assert rows["stalled_length_m"] == pytest.approx(4 * 0.5 * a, rel=0.02)
    assert rows["wall_air_fraction"] == pytest.approx(0.03)
    assert rows["wall_pressure_excess_pa"] == pytest.approx(250.0)
    # within a reach of 0.3 a only the two columns either side of the meniscus count
    near = wall_rows(folder, mesh, spec.wall_speed, 6.5 * a, 0.3 * a)
    assert near["stalled_length_m"] == pytest.approx(2 * 0.5 * a, rel=0.02)
