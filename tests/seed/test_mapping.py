"""Interpolation of cell values between two generated layered meshes (ehlfoam.seed.mapping)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import Delaunay

from ehlfoam.spec.case import make_case_spec
from ehlfoam.case.geometry import load_geometry
from ehlfoam.case.writer import write_case
from ehlfoam.run.fields import Structure
from ehlfoam.seed.mapping import LayeredMesh, carry_oil, conserve_oil, interpolate, oil_carried
from tests.tiny import SMALL


#: How exactly a linear field is carried over, by the meshes' columns: exact where the
#: columns stand upright (every column graded alike); where they lean along the levels'
#: normals (the default) a layer's relative height varies by 4e-4 from column to column,
#: which moved the field below by 6.4e-4 at most (measured 2026-11-24).
LINEAR_TOLERANCE = {"vertical": 1e-9, "normal": 2e-3, "wall_cell": 2e-3}


@pytest.fixture(scope="module", params=sorted(LINEAR_TOLERANCE))
def meshes(request, tmp_path_factory):
    """The tiny case's mesh (3 layers) and a finer one (smaller cells, 5 layers), with the
    node columns of ``request.param``."""
    root = tmp_path_factory.mktemp(f"mapping_{request.param}")
    coarse, fine = root / "coarse", root / "fine"
    if request.param == "wall_cell":   # one wall cell height: each column graded its own way
        mesh = {k: v for k, v in SMALL["mesh"].items() if k != "wall_grading"} | {
            "wall_cell": 2e-6}
    else:
        mesh = {**SMALL["mesh"], "columns": request.param}
    write_case(make_case_spec({**SMALL, "mesh": mesh}), coarse)
    write_case(make_case_spec({**SMALL, "mesh": {**mesh, "size_rim": 0.18, "n_layers": 5}}), fine)
    return coarse, fine, LINEAR_TOLERANCE[request.param], request.param


def test_relative_heights_span_the_gap(meshes):
    m = LayeredMesh.load(meshes[1])
    assert m.shape[1] == 5
    assert np.all((m.zeta > 0) & (m.zeta < 1))
    z = m.zeta_columns().mean(axis=0)                       # each layer's mean height
    assert np.all(np.diff(z) > 0) and z[0] < 0.2 and z[-1] > 0.8
    # graded symmetrically toward both walls
    assert z[0] == pytest.approx(1 - z[-1], abs=1e-3)
    wall = m.zeta_columns()[:, 0]                           # each column's first layer
    if meshes[3] == "wall_cell":      # graded more where the gap is wider, uniform at the rim
        assert wall.min() < 0.5 * wall.max() and wall.max() == pytest.approx(0.1, rel=0.02)
    else:
        assert np.ptp(wall) < 2e-3


def test_a_linear_field_is_carried_over_exactly_inside_the_source(meshes):
    src, dst = (LayeredMesh.load(c) for c in meshes[:2])
    tolerance = meshes[2]
    a = load_geometry(meshes[0]).a

    def field(m: LayeredMesh) -> np.ndarray:
        xy = m.base_xy[m.base_cell] / a
        return 1.0 + xy[:, 0] - 2.0 * xy[:, 1] + 0.5 * m.zeta

    got = interpolate(field(src), src, dst)
    want = field(dst)
    # exact where the target cell lies between source layer centres across the gap and
    # inside the hull of the source columns in plane (outside: nearest column)
    z_s = src.zeta_columns()                              # (columns, layers)
    inner = (dst.zeta >= z_s[:, 0].max()) & (dst.zeta <= z_s[:, -1].min())
    in_hull = Delaunay(src.base_xy).find_simplex(dst.base_xy[dst.base_cell]) >= 0
    interior = inner & in_hull
    assert interior.sum() > 0.5 * len(dst.zeta)
    np.testing.assert_allclose(got[interior], want[interior], atol=tolerance)
    # vectors: component by component
    vec = np.stack([field(src), 2 * field(src), np.zeros(len(src.zeta))], axis=1)
    got_vec = interpolate(vec, src, dst)
    assert got_vec.shape == (len(dst.zeta), 3)
    np.testing.assert_allclose(got_vec[interior, 1], 2 * want[interior], atol=2 * tolerance)


def test_values_stay_within_the_source_range(meshes):
    src, dst = (LayeredMesh.load(c) for c in meshes[:2])
    rng = np.random.default_rng(1)
    alpha = (rng.random(len(src.zeta)) > 0.5).astype(float)
    got = interpolate(alpha, src, dst)
    assert got.min() >= 0.0 and got.max() <= 1.0


def test_conserve_oil_moves_only_the_interface_cells_to_the_volume_asked():
    rng = np.random.default_rng(3)
    volumes = rng.uniform(1.0, 2.0, 400)
    alpha = np.r_[np.zeros(150), np.ones(150), rng.uniform(0.0, 1.0, 100)]
    for target in (volumes @ alpha * 1.01, volumes @ alpha * 0.99):
        out, c = conserve_oil(alpha, volumes, target)
        assert volumes @ out == pytest.approx(target, rel=1e-12)
        assert abs(c) <= 1.0 and out.min() >= 0.0 and out.max() <= 1.0
        np.testing.assert_array_equal(out[:300], alpha[:300])   # full and empty cells kept
        assert np.all(np.sign(out[300:] - alpha[300:]) == np.sign(target - volumes @ alpha))
    # more than the interface cells can take: shifted as far as they go, and no further
    out, c = conserve_oil(alpha, volumes, volumes @ alpha * 1.5)
    assert c == 1.0 and out.max() <= 1.0 and volumes @ out < volumes @ alpha * 1.5
    # no interface: nothing to move
    sharp = np.r_[np.zeros(5), np.ones(5)]
    out, c = conserve_oil(sharp, np.ones(10), 6.0)
    assert c == 0.0 and np.array_equal(out, sharp)


def test_carry_oil_keeps_the_sources_oil_across_meshes_of_one_domain(meshes):
    """A sharp oil patch interpolated onto a finer mesh of the same domain gains or loses
    oil where the interface crosses cells; carried over, it holds the source's volume."""
    src, dst = (LayeredMesh.load(c) for c in meshes[:2])
    v_src, v_dst = (Structure.load(c).cell_volumes for c in meshes[:2])
    a = load_geometry(meshes[0]).a
    xy = src.base_xy[src.base_cell] / a
    alpha = ((xy[:, 0] + 1.0) ** 2 + xy[:, 1] ** 2 < 9.0).astype(float)
    source_oil = float(v_src @ alpha)
    mapped = interpolate(alpha, src, dst)
    assert abs(v_dst @ mapped / source_oil - 1.0) > 1e-4          # interpolation drifts
    out, record = carry_oil(mapped, v_dst, source_oil, float(v_src.sum()))
    assert record["conserved"] and record["reason"] == ""
    assert v_dst @ out == pytest.approx(source_oil, rel=1e-9)
    assert out.min() >= 0.0 and out.max() <= 1.0
    assert np.abs(out - mapped).max() < 0.25                        # within the cells
    # another domain (its volume 5 % off): interpolated only, and the record says why
    other, record = carry_oil(mapped, v_dst, source_oil, 1.05 * float(v_src.sum()))
    assert not record["conserved"] and "domains' volumes differ by" in record["reason"]
    np.testing.assert_array_equal(other, mapped)
    assert "not kept" in oil_carried(record)
