"""bench/film_width_chart.py: which strip series a strip row belongs to (wall layers and
interface schemes) and which cells a 3D case's rear meniscus sits in (size_far, or a
refinement box's)."""

from __future__ import annotations

import pytest

from bench.film_width_chart import _series, rear_cell_size, strip_table
from ehlfoam.spec.case import make_case_spec
from ehlfoam.spec.levels import RESOLUTIONS


def test_a_strip_row_is_filed_by_its_wall_layers_and_schemes():
    fine = RESOLUTIONS["fine"]
    standard = _series({"level": "fine", "options": {}})
    assert standard == (fine["n_layers"], fine["wall_grading"], "standard")
    balanced = _series({"level": "fine", "options": {
        "physics.interface_schemes": "balanced", "run.alpha_subcycles": 3,
        "run.capillary_safety": 0.5}})
    assert balanced == (fine["n_layers"], fine["wall_grading"], "balanced")
    layers = _series({"level": "fine", "options": {"mesh.n_layers": 20,
                                                    "mesh.wall_grading": 20}})
    assert layers == (20, 20.0, "standard")


def test_the_strip_table_keeps_the_nominal_physics_only():
    table = strip_table()
    assert table, "the strip records in bench/results/ were not read"
    allowed = {"mesh.n_layers", "mesh.wall_grading", "physics.interface_schemes",
               "run.alpha_subcycles", "run.capillary_safety"}
    for rows in table.values():
        for row in rows.values():
            assert row["status"] == "ok"
            assert set(row.get("options", {})) <= allowed   # e.g. no other surface tension


@pytest.mark.parametrize("refine, expected", [
    ([], RESOLUTIONS["medium"]["size_far"]),
    ([{"x_min": 2.0, "x_max": 14.0, "y_max": 9.0, "size": 0.1}], 0.1),
    # a box that ends upstream of the rear meniscus: its cells have grown back
    ([{"x_min": 2.0, "x_max": 5.0, "y_max": 9.0, "size": 0.1}],
     RESOLUTIONS["medium"]["size_far"]),
])
def test_the_rear_meniscus_sits_in_the_far_cells_or_a_box(refine, expected):
    spec = make_case_spec({"mesh": {"resolution": "medium", "refine": refine},
                           "domain": {"side": 10.0}})
    # inlet meniscus 6.6 a upstream of x = -a, a region 21.1 a long: the rear at x = 13.5 a
    last = {"inlet_meniscus_distance_over_a": 6.6, "flooded_length_over_a": 21.1}
    assert rear_cell_size(spec, last) == pytest.approx(expected, rel=1e-6)
