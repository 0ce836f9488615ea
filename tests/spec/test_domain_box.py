"""One record of the domain's rectangle: the spec's domain (units a) in metres, which the mesh,
the metrics and a written case extend or give; bad rectangles refused naming the key."""

from __future__ import annotations

import pytest

from ehlfoam.case.geometry import CaseGeometry
from ehlfoam.mesh import MeshParams
from ehlfoam.metrics.raster import Geometry
from ehlfoam.spec import DomainBox, make_case_spec


def test_the_specs_domain_in_metres_is_what_mesh_and_metrics_extend():
    spec = make_case_spec({"domain": {"upstream": 10.0, "downstream": 20.0, "side": 6.0,
                                      "symmetry": "full"}})
    a = spec.a
    box = spec.domain.box(a)
    assert (box.x_min, box.x_max, box.y_max) == pytest.approx((-10 * a, 20 * a, 6 * a))
    assert box.island_radius == pytest.approx(1.5 * a) and box.symmetric is False
    assert box.y_min == -box.y_max
    mesh = MeshParams(**box.fields(), n_layers=4)
    pattern = Geometry.of(box, a)
    assert isinstance(mesh, DomainBox) and isinstance(pattern, DomainBox)
    assert mesh.fields() == pattern.fields() == box.fields()
    assert mesh.area == pytest.approx(30 * a * 12 * a - 3.14159265 * (1.5 * a) ** 2, rel=1e-6)


def test_a_written_cases_record_gives_the_same_box():
    from tests.tiny import tiny_geometry

    geom: CaseGeometry = tiny_geometry()
    box = geom.box
    assert (box.x_min, box.x_max, box.y_max, box.island_radius, box.symmetric) == (
        geom.x_min, geom.x_max, geom.y_max, geom.island_radius, geom.symmetric)


@pytest.mark.parametrize("change, words", [
    ({"x_min": -1e-5}, "x_min must be < -island_radius"),
    ({"x_max": 1e-5}, "x_max must be > island_radius"),
    ({"y_max": 1e-5}, "y_max must be > island_radius"),
    ({"island_radius": 0.0}, "island_radius must be > 0 m"),
    ({"x_min": float("nan")}, "x_min must be a finite number in metres"),
    ({"x_max": True}, "x_max must be a finite number in metres"),
    ({"symmetric": "yes"}, "symmetric must be True or False"),
])
def test_a_rectangle_that_does_not_hold_the_island_is_refused_naming_the_key(change, words):
    good = {"x_min": -1e-3, "x_max": 2e-3, "y_max": 1e-3, "island_radius": 2e-4}
    with pytest.raises(ValueError, match=words):
        DomainBox(**{**good, **change})
    with pytest.raises(ValueError, match="^a: must be a finite number > 0"):
        Geometry(**good, a=float("inf"))
    with pytest.raises(ValueError, match="island_radius: must be >= a"):
        Geometry(**good, a=1e-3)
