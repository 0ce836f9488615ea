"""What a strip's writes say (ehlfoam.metrics.strip), read off fields written by hand with a
known answer: the rear meniscus and its films, and the wall cells at a contact line."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from foamlib import FoamFieldFile

from ehlfoam.case.strip import strip_mesh, write_strip_case
from ehlfoam.metrics.strip import columns, rear_films, wall_rows
from tests.tiny import small_contact


@pytest.fixture(scope="module")
def strip():
    spec, gap, a = small_contact()
    return spec, gap, a, strip_mesh(spec, gap, 4 * a, 10 * a, 0.5 * a)


def test_rear_films_read_a_known_bridge_and_its_films(strip):
    """Oil wall to wall up to x = 6.5 a, then 10 % of each column's gap: the rear meniscus
    half way between the last full column and the first filmed one, films of 0.1 h behind."""
    spec, gap, a, mesh = strip
    x_cell = mesh.cell_centres[:, 0]
    alpha = np.where(x_cell < 6.5 * a, 1.0, 0.1)
    x, h, _ = columns(mesh, alpha)
    row = rear_films(mesh, alpha, a, 10 * a)
    k = np.searchsorted(x, 6.5 * a)                # the first filmed column
    w = (1.0 - 0.5) / (1.0 - 0.1)
    assert row["x_rear_over_a"] == pytest.approx((x[k - 1] + w * (x[k] - x[k - 1])) / a)
    assert row["gap_rear_m"] == pytest.approx(h[k - 1] + w * (h[k] - h[k - 1]))
    behind = (x > row["x_rear_over_a"] * a + a) & (x < 9.5 * a)
    assert row["film_m"] == pytest.approx(np.median(0.1 * h[behind]))
    assert row["deposited_fraction"] == pytest.approx(row["film_m"] / row["gap_rear_m"])
    width = np.ptp(mesh.points[:, 1])
    assert row["oil_per_width_m2"] == pytest.approx(np.sum(alpha * mesh.cell_volumes) / width)
    assert rear_films(mesh, np.zeros(mesh.n_cells), a, 10 * a) is None      # no bridge


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
