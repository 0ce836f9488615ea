"""Tests of ehlfoam.mesh: gmsh base mesh, extrusion, polyMesh writer.

Real gmsh and real OpenFOAM (checkMesh through ehlfoam.foam.runtime), no
mocks. Geometry: the reference contact (ball radius 9.525 mm, Hertz radius
0.1371 mm) with a dry-Hertz-like gap.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import gmsh
import numpy as np
import pytest

from ehlfoam.mesh import (PATCH_TYPES, BaseMesh, MeshParams, PolyMesh, build_base_mesh, extrude,
                          gap_mismatch, write_polymesh)
from ehlfoam.foam.runtime import FoamRuntime

R_BALL = 9.525e-3   # m
A_HERTZ = 1.371e-4  # m
H0 = 1e-8           # m
R_ISLAND = 1.5 * A_HERTZ
N_LAYERS = 6


def hertz_gap(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Dry-Hertz-like gap h(r) (m) outside the contact (r > a)."""
    a, R = A_HERTZ, R_BALL
    r = np.maximum(np.hypot(x, y), a)
    return (H0 + r**2 / (2 * R) - a**2 / R
            + ((2 * a**2 - r**2) * np.arcsin(a / r) + a * np.sqrt(r**2 - a**2)) / (np.pi * R))


def sizer(scale: float):
    """size(x, y): 0.04 a at the island growing linearly to 0.4 a, times scale (m)."""
    def size(x, y):
        r = np.hypot(x, y)
        return scale * np.clip(0.04 * A_HERTZ * r / R_ISLAND, 0.04 * A_HERTZ, 0.4 * A_HERTZ)
    return size


def params(symmetric: bool = True, **kw) -> MeshParams:
    base = dict(x_min=-6 * A_HERTZ, x_max=12 * A_HERTZ, y_max=6 * A_HERTZ,
                island_radius=R_ISLAND, n_layers=N_LAYERS, symmetric=symmetric)
    base.update(kw)
    return MeshParams(**base)


def gap_integral(p: MeshParams, gap=hertz_gap, n: int = 200) -> float:
    """Integral of gap over the domain (m^3), Gauss-Legendre in polar
    coordinates (r from the island to the rectangle, theta split at the corners)."""
    corners = sorted({math.atan2(y, x) for x in (p.x_min, p.x_max) for y in (p.y_min, p.y_max)})
    t_lo = 0.0 if p.symmetric else -math.pi
    cuts = [t_lo] + [t for t in corners if t_lo < t < math.pi] + [math.pi]
    g, w = np.polynomial.legendre.leggauss(n)
    total = 0.0
    for t0, t1 in zip(cuts[:-1], cuts[1:]):
        t = 0.5 * (t1 - t0) * g + 0.5 * (t1 + t0)
        wt = 0.5 * (t1 - t0) * w
        c, s = np.cos(t), np.sin(t)
        with np.errstate(divide="ignore"):
            rx = np.where(c > 0, p.x_max / c, np.where(c < 0, p.x_min / c, np.inf))
            ry = np.where(s > 0, p.y_max / s, np.where(s < 0, p.y_min / s, np.inf))
        r_out = np.minimum(rx, ry)
        r = p.island_radius + (r_out - p.island_radius)[:, None] * 0.5 * (g + 1)[None, :]
        wr = (r_out - p.island_radius)[:, None] * 0.5 * w[None, :]
        total += float(np.sum(wt[:, None] * wr * r * gap(r * c[:, None], r * s[:, None])))
    return total


# ------------------------------------------------------------------ fixtures
@pytest.fixture(scope="module")
def coarse_base() -> BaseMesh:
    return build_base_mesh(params(), sizer(2.0))


@pytest.fixture(scope="module")
def coarse(coarse_base: BaseMesh) -> PolyMesh:
    return extrude(coarse_base, hertz_gap, N_LAYERS)


@pytest.fixture(scope="module")
def reference() -> PolyMesh:
    """The realistic mesh at the reference resolution (~43k cells)."""
    return extrude(build_base_mesh(params(), sizer(1.0)), hertz_gap, N_LAYERS)


@pytest.fixture(scope="module")
def runtime() -> FoamRuntime:
    rt = FoamRuntime.from_environment()
    rt.ensure_present()  # fails (does not skip): ./Alltest installs it
    return rt


def write_case(mesh: PolyMesh, case: Path) -> Path:
    """A minimal OpenFOAM case around ``mesh``."""
    write_polymesh(mesh, case)
    system = case / "system"
    system.mkdir(parents=True, exist_ok=True)
    head = "FoamFile {{ version 2.0; format ascii; class dictionary; object {}; }}\n"
    (system / "controlDict").write_text(
        head.format("controlDict")
        + "application interFoam; startFrom startTime; startTime 0; stopAt endTime;\n"
          "endTime 1; deltaT 1; writeControl timeStep; writeInterval 1;\n")
    (system / "fvSchemes").write_text(
        head.format("fvSchemes")
        + "ddtSchemes { default Euler; } gradSchemes { default Gauss linear; }\n"
          "divSchemes { default none; } laplacianSchemes { default Gauss linear corrected; }\n"
          "interpolationSchemes { default linear; } snGradSchemes { default corrected; }\n")
    (system / "fvSolution").write_text(head.format("fvSolution"))
    return case


def check_mesh(runtime: FoamRuntime, case: Path) -> dict[str, float]:
    """Run checkMesh; assert "Mesh OK."; return its headline numbers."""
    out = runtime.run("checkMesh", [], cwd=case, log_path=case / "log.checkMesh").stdout
    assert "Mesh OK." in out, out[-3000:]
    assert "Failed" not in out, out[-3000:]

    def number(pattern: str) -> float:
        m = re.search(pattern.replace("NUM", r"([-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?)"), out)
        assert m, f"{pattern!r} not in checkMesh output"
        return float(m.group(1))

    stats = {
        "cells": number(r"\n\s*cells:\s+NUM"),
        "max_aspect_ratio": number(r"Max aspect ratio = NUM"),
        "max_non_orthogonality": number(r"Mesh non-orthogonality Max: NUM"),
        "max_skewness": number(r"Max skewness = NUM"),
        "total_volume": number(r"Total volume = NUM"),
    }
    print(f"\ncheckMesh {case.name}: {stats}")
    return stats


# ------------------------------------------------------------------ base mesh
def test_base_mesh_is_all_quad_counter_clockwise(coarse_base: BaseMesh) -> None:
    b, p = coarse_base, params()
    assert b.quads.shape[1] == 4 and b.n_quads > 500
    assert np.all(b.quad_areas() > 0)
    assert np.array_equal(np.unique(b.quads), np.arange(b.n_points))  # no unused nodes
    assert b.quad_areas().sum() == pytest.approx(p.area, rel=2e-3)   # polygonal island
    assert set(b.edges) == {"island", "inlet", "outlet", "side", "symmetry"}


def test_base_mesh_boundary_edges_lie_on_their_boundary_quad_on_left(
        coarse_base: BaseMesh) -> None:
    b, p = coarse_base, params()
    outward = {"inlet": (-1.0, 0.0), "outlet": (1.0, 0.0), "side": (0.0, 1.0),
               "symmetry": (0.0, -1.0)}
    n_boundary = 0
    for name, e in b.edges.items():
        pa, pb = b.points[e[:, 0]], b.points[e[:, 1]]
        d = pb - pa
        normal = np.stack([d[:, 1], -d[:, 0]], axis=1)   # right of a->b: out of the quad
        mid = 0.5 * (pa + pb)
        direction = -mid if name == "island" else np.array(outward[name])
        assert np.all(np.sum(normal * direction, axis=1) > 0), name
        n_boundary += len(e)
    pts = b.points
    assert np.all(pts[np.unique(b.edges["inlet"]), 0] == p.x_min)
    assert np.all(pts[np.unique(b.edges["outlet"]), 0] == p.x_max)
    assert np.all(pts[np.unique(b.edges["side"]), 1] == p.y_max)
    assert np.all(pts[np.unique(b.edges["symmetry"]), 1] == 0.0)
    r = np.hypot(*pts[np.unique(b.edges["island"])].T)
    assert np.allclose(r, p.island_radius, rtol=1e-12, atol=0)
    # every boundary edge (edges used by one quad) is in exactly one patch
    a, c = b.quads.ravel(), np.roll(b.quads, -1, axis=1).ravel()
    keys, counts = np.unique(np.minimum(a, c) * b.n_points + np.maximum(a, c), return_counts=True)
    assert n_boundary == np.sum(counts == 1)


def test_base_mesh_follows_size_and_island_is_smooth(coarse_base: BaseMesh) -> None:
    b = coarse_base
    e = b.edges["island"]
    seg = np.linalg.norm(b.points[e[:, 1]] - b.points[e[:, 0]], axis=1)
    target = sizer(2.0)(0.0, R_ISLAND)
    assert np.median(seg) == pytest.approx(target, rel=0.3)
    # the island polygon has many sides: the arc is resolved
    assert len(e) >= 30
    # cells far away are coarser than at the island
    c = b.points[b.quads].mean(axis=1)
    far = np.hypot(*c.T) > 8 * A_HERTZ
    assert np.sqrt(b.quad_areas()[far]).mean() > 5 * np.median(seg)


def test_base_mesh_is_deterministic(coarse_base: BaseMesh) -> None:
    again = build_base_mesh(params(), sizer(2.0))
    assert np.array_equal(again.points, coarse_base.points)
    assert np.array_equal(again.quads, coarse_base.quads)
    assert all(np.array_equal(again.edges[k], coarse_base.edges[k]) for k in coarse_base.edges)
    assert not gmsh.isInitialized()


# ------------------------------------------------------------------ polyMesh
def test_polymesh_topology_invariants(coarse: PolyMesh, coarse_base: BaseMesh) -> None:
    m = coarse
    n_int, n_faces, n_cells = m.n_internal_faces, len(m.faces), m.n_cells
    assert n_cells == coarse_base.n_quads * N_LAYERS
    assert len(m.points) == coarse_base.n_points * (N_LAYERS + 1)
    own, nei = m.owner, m.neighbour
    assert np.all(own[:n_int] < nei)
    order = np.lexsort((nei, own[:n_int]))
    assert np.array_equal(order, np.arange(n_int))                      # upper-triangular
    assert np.all(np.bincount(np.r_[own, nei], minlength=n_cells) == 6)  # hexahedra
    assert own.min() == 0 and own.max() == n_cells - 1
    # patches: contiguous, in PATCH_TYPES order, covering all boundary faces
    assert [p.name for p in m.patches] == [k for k in PATCH_TYPES]
    assert all(p.type == PATCH_TYPES[p.name] for p in m.patches)
    assert m.patches[0].start == n_int
    for p, q in zip(m.patches[:-1], m.patches[1:]):
        assert q.start == p.start + p.size
    assert sum(p.size for p in m.patches) == n_faces - n_int
    assert m.patch("disc").size == m.patch("ball").size == coarse_base.n_quads
    assert m.patch("island").size == len(coarse_base.edges["island"]) * N_LAYERS
    # every face has 4 distinct points
    assert np.all(np.sort(m.faces, axis=1)[:, 1:] != np.sort(m.faces, axis=1)[:, :-1])
    assert np.array_equal(m.base_cell * N_LAYERS + m.layer, np.arange(n_cells))


def test_polymesh_cells_closed_volumes_positive_and_total(coarse: PolyMesh) -> None:
    m = coarse
    n_int = m.n_internal_faces
    closure = np.zeros((m.n_cells, 3))
    scale = np.zeros(m.n_cells)
    mag = np.linalg.norm(m.face_areas, axis=1)
    for d in range(3):
        closure[:, d] = (np.bincount(m.owner, m.face_areas[:, d], m.n_cells)
                         - np.bincount(m.neighbour, m.face_areas[:n_int, d], m.n_cells))
    scale = np.bincount(m.owner, mag, m.n_cells) + np.bincount(m.neighbour, mag[:n_int], m.n_cells)
    assert np.max(np.linalg.norm(closure, axis=1) / scale) < 1e-10
    assert np.all(m.cell_volumes > 0)
    exact = gap_integral(params())
    assert m.cell_volumes.sum() == pytest.approx(exact, rel=0.01)
    # cell centres inside their column, layers ordered upwards
    h = hertz_gap(m.cell_centres[:, 0], m.cell_centres[:, 1])
    z = m.cell_centres[:, 2] / h
    assert np.all(np.abs(z - (m.layer + 0.5) / N_LAYERS) < 0.05)


def test_polymesh_normals_point_from_owner_to_neighbour_and_out(coarse: PolyMesh) -> None:
    m = coarse
    n_int = m.n_internal_faces
    d = m.cell_centres[m.neighbour] - m.cell_centres[m.owner[:n_int]]
    assert np.all(np.sum(d * m.face_areas[:n_int], axis=1) > 0)
    out = m.face_centres[n_int:] - m.cell_centres[m.owner[n_int:]]
    assert np.all(np.sum(out * m.face_areas[n_int:], axis=1) > 0)
    expected = {"disc": (2, -1), "ball": (2, 1), "inlet": (0, -1), "outlet": (0, 1),
                "side": (1, 1), "symmetry": (1, -1)}
    for name, (axis, sign) in expected.items():
        sf = m.face_areas[m.patch_slice(name)]
        assert np.all(sign * sf[:, axis] > 0.9 * np.linalg.norm(sf, axis=1) * (axis != 2)
                      + 0.95 * np.linalg.norm(sf, axis=1) * (axis == 2)), name
    isl = m.patch_slice("island")
    radial = m.face_centres[isl, :2]
    assert np.all(np.sum(radial * m.face_areas[isl, :2], axis=1) < 0)   # into the hole
    disc = m.face_centres[m.patch_slice("disc")]
    assert np.all(disc[:, 2] == 0)


def test_gap_mismatch_small_at_reference_resolution(reference: PolyMesh) -> None:
    assert 10_000 < reference.n_cells < 60_000
    err = gap_mismatch(reference, hertz_gap)
    print(f"\ngap_mismatch (reference, {reference.n_cells} cells) = {err:.3g}")
    assert err < 0.01
    ball = reference.face_centres[reference.patch_slice("ball")]
    assert np.allclose(ball[:, 2], hertz_gap(ball[:, 0], ball[:, 1]), rtol=0.01)


# ------------------------------------------------------------------ writer + OpenFOAM
def test_write_polymesh_files(coarse: PolyMesh, tmp_path: Path) -> None:
    poly = tmp_path / "constant" / "polyMesh"
    poly.mkdir(parents=True)
    (poly / "points.gz").write_bytes(b"stale")
    (poly / "cellZones").write_text("stale")
    write_polymesh(coarse, tmp_path)
    assert sorted(f.name for f in poly.iterdir()) == [
        "boundary", "faces", "neighbour", "owner", "points"]
    owner = (poly / "owner").read_text()
    assert "class       labelList;" in owner
    assert (f'note        "nPoints:{len(coarse.points)}  nCells:{coarse.n_cells}  '
            f'nFaces:{len(coarse.faces)}  nInternalFaces:{coarse.n_internal_faces}";') in owner
    assert "class       vectorField;" in (poly / "points").read_text()
    assert "class       faceList;" in (poly / "faces").read_text()
    boundary = (poly / "boundary").read_text()
    assert "class       polyBoundaryMesh;" in boundary
    assert "symmetryPlane;" in boundary and "empty" not in boundary
    # points read back to 12 significant digits
    text = (poly / "points").read_text()
    body = text[text.index("\n(\n") + 3:text.rindex("\n)\n")]
    back = np.array(body.replace("(", "").replace(")", "").split(), dtype=float).reshape(-1, 3)
    assert np.allclose(back, coarse.points, rtol=1e-11, atol=0)
    faces = (poly / "faces").read_text()
    first = faces[faces.index("\n(\n") + 3:].split("\n", 1)[0]
    assert first == "4(%d %d %d %d)" % tuple(coarse.faces[0])


@pytest.mark.openfoam
def test_checkmesh_ok_on_realistic_mesh(reference: PolyMesh, runtime: FoamRuntime,
                                        tmp_path: Path) -> None:
    case = write_case(reference, tmp_path / "reference")
    stats = check_mesh(runtime, case)
    assert stats["cells"] == reference.n_cells
    assert stats["total_volume"] == pytest.approx(reference.cell_volumes.sum(), rel=1e-5)


@pytest.mark.openfoam
def test_full_domain_is_the_half_mirrored(coarse: PolyMesh, coarse_base: BaseMesh,
                                           runtime: FoamRuntime, tmp_path: Path) -> None:
    p_full = params(symmetric=False)
    base = build_base_mesh(p_full, sizer(2.0))          # even size: half mesh + mirror image
    assert base.n_quads == 2 * coarse_base.n_quads
    pts = base.points
    order, order_mirrored = np.lexsort(pts.T[::-1]), np.lexsort((pts * [1, -1]).T[::-1])
    assert np.array_equal(pts[order], (pts * [1, -1])[order_mirrored])
    full = extrude(base, hertz_gap, N_LAYERS)
    assert [p.name for p in full.patches] == ["disc", "ball", "island", "inlet", "outlet",
                                              "side"]
    assert full.n_cells == 2 * coarse.n_cells
    assert full.cell_volumes.sum() == pytest.approx(2 * coarse.cell_volumes.sum(), rel=1e-9)
    assert full.cell_volumes.sum() == pytest.approx(gap_integral(p_full), rel=0.01)
    y = full.face_centres[full.patch_slice("side"), 1]
    assert np.allclose(np.abs(y), p_full.y_max, rtol=1e-12, atol=0)
    assert (y > 0).sum() == (y < 0).sum() > 0
    assert full.patch("island").size == 2 * coarse.patch("island").size
    assert gap_mismatch(full, hertz_gap) == pytest.approx(gap_mismatch(coarse, hertz_gap))
    check_mesh(runtime, write_case(full, tmp_path / "full"))


@pytest.mark.openfoam
def test_full_domain_with_uneven_size_is_meshed_whole(runtime: FoamRuntime,
                                                      tmp_path: Path) -> None:
    p_full = params(symmetric=False)

    def uneven(x, y):                       # coarser for y < 0
        return sizer(2.0)(x, y) * np.where(y < 0, 1.5, 1.0)
    base = build_base_mesh(p_full, uneven)
    upper = base.points[base.quads].mean(axis=1)[:, 1] > 0
    assert upper.sum() > 1.5 * (~upper).sum()
    assert base.quad_areas().sum() == pytest.approx(p_full.area, rel=2e-3)
    full = extrude(base, hertz_gap, N_LAYERS)
    assert "symmetry" not in [p.name for p in full.patches]
    assert full.cell_volumes.sum() == pytest.approx(gap_integral(p_full), rel=0.01)
    check_mesh(runtime, write_case(full, tmp_path / "uneven"))


@pytest.mark.openfoam
def test_polar_ring_is_log_polar_and_the_rest_is_free(runtime: FoamRuntime,
                                                       tmp_path: Path) -> None:
    r_polar = 4 * A_HERTZ
    p = params(polar_radius=r_polar)
    base = build_base_mesh(p, sizer(2.0))
    assert base.quad_areas().min() > 0
    assert base.quad_areas().sum() == pytest.approx(p.area, rel=2e-3)
    # the ring: nodes on a few exact circles and spokes, radii in geometric progression
    rho = np.hypot(*base.points.T)
    ring = rho <= r_polar * (1 + 1e-9)
    radii = np.unique(np.round(rho[ring] / A_HERTZ, 9))
    assert radii[0] == pytest.approx(R_ISLAND / A_HERTZ) and radii[-1] == pytest.approx(4.0)
    assert len(radii) < 0.1 * ring.sum()                      # a handful of circles
    assert np.allclose(radii[1:] / radii[:-1], radii[1] / radii[0], rtol=1e-9)
    angles = np.unique(np.round(np.arctan2(*base.points[ring].T[::-1]), 9))
    step = math.pi / (len(angles) - 1)
    assert np.allclose(np.diff(angles), step, rtol=1e-6)
    # near-square cells of angular step size(rim) / island radius: as many as the free mesh
    assert step == pytest.approx(0.04 * 2.0 * A_HERTZ / R_ISLAND, rel=0.1)
    assert radii[1] / radii[0] == pytest.approx(math.exp(step), rel=0.01)
    assert base.n_quads == pytest.approx(build_base_mesh(params(), sizer(2.0)).n_quads, rel=0.1)
    # every ring quad is a polar cell: two nodes on each of two neighbouring circles
    centres = base.points[base.quads].mean(axis=1)
    in_ring = np.hypot(*centres.T) < r_polar
    k = np.round(np.log(rho[base.quads[in_ring]] / R_ISLAND) / math.log(radii[1] / radii[0]))
    assert np.all(np.sort(k, axis=1)[:, [0, 1, 2, 3]] - np.sort(k, axis=1)[:, [0, 0, 2, 2]]
                  == 0)
    assert np.all(np.sort(k, axis=1)[:, 2] - np.sort(k, axis=1)[:, 0] == 1)
    mesh = extrude(base, hertz_gap, N_LAYERS)
    assert mesh.cell_volumes.sum() == pytest.approx(gap_integral(p), rel=0.01)
    stats = check_mesh(runtime, write_case(mesh, tmp_path / "polar"))
    assert stats["max_non_orthogonality"] < 30
    full = build_base_mesh(params(symmetric=False, polar_radius=r_polar), sizer(2.0))
    assert full.n_quads == 2 * base.n_quads                  # the half ring mirrored
    with pytest.raises(ValueError, match="even in y"):
        build_base_mesh(params(symmetric=False, polar_radius=r_polar),
                        lambda x, y: sizer(2.0)(x, y) * np.where(y < 0, 1.5, 1.0))


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize("change, word", [
    (dict(island_radius=-1e-4), "island_radius"),
    (dict(island_radius=float("nan")), "island_radius"),
    (dict(x_min=-1e-4), "x_min"),
    (dict(x_max=1e-4), "x_max"),
    (dict(y_max=2e-4), "y_max"),
    (dict(x_min="left"), "x_min"),
    (dict(n_layers=0), "n_layers"),
    (dict(n_layers=2.5), "n_layers"),
    (dict(symmetric="yes"), "symmetric"),
    (dict(polar_radius=R_ISLAND), "polar_radius"),
    (dict(polar_radius=6 * A_HERTZ), "polar_radius"),
])
def test_bad_params_raise_value_error_naming_them(change: dict, word: str) -> None:
    with pytest.raises(ValueError, match=word):
        params(**change)


def test_bad_size_raises_value_error() -> None:
    with pytest.raises(ValueError, match=r"size\(x, y\) must be a positive finite"):
        build_base_mesh(params(), lambda x, y: np.where(x > 0, -1.0, 1e-5))
    with pytest.raises(ValueError, match="max_quads"):
        build_base_mesh(params(), lambda x, y: np.full(np.shape(x), 1e-8))   # too fine
    with pytest.raises(ValueError, match="size"):
        build_base_mesh(params(), 1e-5)
    assert not gmsh.isInitialized()


def test_interrupt_while_meshing_is_an_interrupt_not_a_broken_mesh() -> None:
    """A Ctrl-C or a batch's stop signal that lands in gmsh's size callback comes out as
    KeyboardInterrupt once gmsh returns (ctypes would swallow it and mesh with a size of 0:
    a batch once recorded such a case as a failed build, "non-quadrilateral elements")."""
    calls = {"n": 0}

    def interrupted(x, y):
        if np.ndim(x) == 0:
            calls["n"] += 1
            if calls["n"] == 50:
                raise KeyboardInterrupt
        return np.full(np.shape(x), 2e-5)
    with pytest.raises(KeyboardInterrupt):
        build_base_mesh(params(), interrupted)
    assert calls["n"] >= 50 and not gmsh.isInitialized()


def test_size_failing_inside_gmsh_leaves_no_gmsh_state() -> None:
    def scalar_hostile(x, y):
        if np.ndim(x) == 0:
            raise RuntimeError("no scalars please")
        return np.full(np.shape(x), 2e-5)
    with pytest.raises(ValueError, match="no scalars please"):
        build_base_mesh(params(), scalar_hostile)
    assert not gmsh.isInitialized()


def test_caller_gmsh_session_is_left_as_it_was(coarse_base: BaseMesh) -> None:
    gmsh.initialize([], readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("callers")
        gmsh.option.setNumber("Mesh.Algorithm", 5)
        b = build_base_mesh(params(), sizer(2.0))
        assert gmsh.model.getCurrent() == "callers"
        assert gmsh.option.getNumber("Mesh.Algorithm") == 5
        assert np.array_equal(b.quads, coarse_base.quads)
    finally:
        gmsh.finalize()


def test_bad_gap_and_layers_raise_value_error(coarse_base: BaseMesh) -> None:
    def holed(x, y):
        h = hertz_gap(x, y)
        return np.where(x > 10 * A_HERTZ, np.nan, h)
    with pytest.raises(ValueError, match=r"gap must be > 0 and finite.*gap\(0\.00"):
        extrude(coarse_base, holed, N_LAYERS)
    with pytest.raises(ValueError, match="gap must be > 0"):
        extrude(coarse_base, lambda x, y: hertz_gap(x, y) - 1e-6, N_LAYERS)
    with pytest.raises(ValueError, match="n_layers"):
        extrude(coarse_base, hertz_gap, 0)
    bad = BaseMesh(coarse_base.points, coarse_base.quads[:, ::-1], coarse_base.edges)
    with pytest.raises(ValueError, match="counter-clockwise"):
        extrude(bad, hertz_gap, N_LAYERS)
    partial = BaseMesh(coarse_base.points, coarse_base.quads,
                       {k: v for k, v in coarse_base.edges.items() if k != "inlet"})
    with pytest.raises(ValueError, match="exactly one patch"):
        extrude(partial, hertz_gap, N_LAYERS)


# ---------------------------------------------------------------- grading and patch split
def test_layer_fractions_graded_toward_both_walls():
    from ehlfoam.mesh import layer_fractions

    f = layer_fractions(8, 4.0)
    d = np.diff(f)
    assert f[0] == 0.0 and f[-1] == 1.0 and np.all(d > 0)
    assert np.allclose(d, d[::-1])                        # symmetric about mid-gap
    assert d[len(d) // 2] / d[0] == pytest.approx(4.0, rel=1e-6)
    assert np.allclose(layer_fractions(5, 1.0), np.linspace(0, 1, 6))


def test_wall_steps_count_the_ball_stair_steps():
    """A square quad of side d under a ball sloping by g in x: the ball rises g d across it,
    which is g d / (f_1 h_mean) wall cells of height f_1 h_mean; thinner wall cells (graded
    layers) step over proportionally more of them."""
    from ehlfoam.mesh import layer_fractions, wall_steps

    d, h0, g = 1e-4, 1e-5, 0.05
    base = BaseMesh(points=np.array([[0.0, 0.0], [d, 0.0], [d, d], [0.0, d]]),
                    quads=np.array([[0, 1, 2, 3]]),
                    edges={"side": np.array([[0, 1], [1, 2], [2, 3], [3, 0]])})
    gap = lambda x, y: h0 + g * x  # noqa: E731
    h_mean = h0 + g * d / 2

    def steps(gap, n_layers, grading=1.0):
        return wall_steps(base, extrude(base, gap, n_layers, grading, columns="vertical"))[0]

    assert steps(gap, 4) == pytest.approx(g * d / (0.25 * h_mean))
    wall = np.diff(layer_fractions(10, 8.0))[0]
    assert steps(gap, 10, 8.0) / steps(gap, 10) == pytest.approx(0.1 / wall)
    assert steps(lambda x, y: h0 + 0 * x, 4) == 0.0                    # a flat ball: none


def _face_tilt_mismatch(mesh: PolyMesh) -> tuple[np.ndarray, np.ndarray]:
    """Per internal face, degrees: the non-orthogonality of the level faces (normal mostly
    along z) and, for the lateral faces, the difference between the elevation of the
    owner-to-neighbour vector and that of the face normal (the part of their
    non-orthogonality that the columns, not the 2D mesh, make)."""
    n = mesh.n_internal_faces
    d = mesh.cell_centres[mesh.neighbour] - mesh.cell_centres[mesh.owner[:n]]
    s = mesh.face_areas[:n]
    dn, sn = np.linalg.norm(d, axis=1), np.linalg.norm(s, axis=1)
    level = np.abs(s[:, 2]) > 0.5 * sn
    angle = np.degrees(np.arccos(np.clip(np.sum(d * s, axis=1) / (dn * sn), -1, 1)))
    elevation = np.degrees(np.abs(np.arcsin(d[:, 2] / dn) - np.arcsin(s[:, 2] / sn)))
    return angle[level], elevation[~level]


def test_normal_columns_meet_the_levels_at_right_angles(coarse_base: BaseMesh) -> None:
    """Vertical columns tilt every face where the ball slopes; columns along the levels'
    normals do not, and they keep the boundaries where they were and the gap as it was."""
    vertical = extrude(coarse_base, hertz_gap, N_LAYERS, columns="vertical")
    normal = extrude(coarse_base, hertz_gap, N_LAYERS)              # the default
    lv, ev = _face_tilt_mismatch(vertical)
    ln, en = _face_tilt_mismatch(normal)
    assert lv.mean() > 1.0 and ev.mean() > 0.5                     # what the slope makes
    assert ln.mean() < 0.1 * lv.mean() and en.mean() < 0.1 * ev.mean()
    assert np.percentile(en, 99) < 0.1 * np.percentile(ev, 99)
    # the same cells, the same volume, the ball still on the gap
    assert normal.n_cells == vertical.n_cells
    assert normal.cell_volumes.min() > 0
    assert normal.cell_volumes.sum() == pytest.approx(vertical.cell_volumes.sum(), rel=1e-3)
    assert gap_mismatch(normal, hertz_gap) < 0.01
    # the disc's nodes and every boundary stay put: planes planar, the island a cylinder
    p = params()
    cols = normal.points.reshape(coarse_base.n_points, N_LAYERS + 1, 3)
    assert np.array_equal(cols[:, 0, :2], coarse_base.points)
    assert np.all(cols[:, 0, 2] == 0.0)
    on = {name: np.unique(e) for name, e in coarse_base.edges.items()}
    assert np.all(cols[on["inlet"], :, 0] == p.x_min)
    assert np.all(cols[on["outlet"], :, 0] == p.x_max)
    assert np.all(cols[on["side"], :, 1] == p.y_max)
    assert np.all(cols[on["symmetry"], :, 1] == 0.0)
    r = np.hypot(cols[on["island"], :, 0], cols[on["island"], :, 1])
    assert r == pytest.approx(np.full_like(r, p.island_radius), rel=1e-12)
    # the lean (h |grad h| / 2 at the ball) is a fraction of the node's shortest edge
    shift = np.linalg.norm(cols[:, -1, :2] - coarse_base.points, axis=1)
    quads = coarse_base.quads
    edge = np.linalg.norm(coarse_base.points[np.roll(quads, -1, axis=1)]
                          - coarse_base.points[quads], axis=2)
    shortest = np.full(coarse_base.n_points, np.inf)
    for k in range(4):
        np.minimum.at(shortest, quads[:, k], edge[:, k])
        np.minimum.at(shortest, np.roll(quads, -1, axis=1)[:, k], edge[:, k])
    assert 0 < np.max(shift / shortest) < 0.25
    with pytest.raises(ValueError, match="columns must be one of"):
        extrude(coarse_base, hertz_gap, N_LAYERS, columns="slanted")


def test_split_patch_keeps_a_valid_mesh():
    from ehlfoam.mesh import split_patch

    params = MeshParams(x_min=-6 * A_HERTZ, x_max=12 * A_HERTZ, y_max=6 * A_HERTZ, island_radius=1.5 * A_HERTZ,
                        n_layers=3)
    mesh = extrude(build_base_mesh(params, lambda x, y: np.full_like(np.asarray(x, float), 0.5 * A_HERTZ)),
                   hertz_gap, 3)
    sl = mesh.patch_slice("inlet")
    select = mesh.face_centres[sl, 1] < 2 * A_HERTZ
    out = split_patch(mesh, "inlet", select, "supply")
    assert out.patch("supply").size == select.sum()
    assert out.patch("inlet").size + out.patch("supply").size == sl.stop - sl.start
    assert out.patch("supply").start == out.patch("inlet").start + out.patch("inlet").size
    assert np.all(out.face_centres[out.patch_slice("supply"), 1] < 2 * A_HERTZ)
    # the same faces, reordered within the old patch only
    assert np.array_equal(np.sort(out.owner[sl]), np.sort(mesh.owner[sl]))
    assert np.array_equal(out.faces[:sl.start], mesh.faces[:sl.start])
    with pytest.raises(ValueError, match="one entry per face"):
        split_patch(mesh, "inlet", select[:-1], "supply")


def test_one_wall_cell_height_grades_each_column_just_enough(coarse_base):
    """``wall_cell``: the wall cell is that height wherever the gap allows it (graded between
    uniform and 100), uniform where the gap is too thin for it, graded 100 where even that
    leaves it thicker; each cell's span across its column is what its nodes make."""
    from ehlfoam.mesh import column_fractions, layer_fractions

    n = 10
    h = np.array([5e-6, 2e-5, 1e-4, 2e-4, 1e-2])
    frac = column_fractions(h, n, 1e-6)
    wall = frac[:, 1] * h
    np.testing.assert_allclose(frac[0], np.arange(n + 1) / n)          # h / n = 0.5 um: uniform
    np.testing.assert_allclose(wall[1:4], 1e-6, rtol=2e-3)             # graded to 1 um
    assert np.all(np.diff(frac, axis=1) > 0) and np.all(frac[:, [0, -1]] == [0.0, 1.0])
    np.testing.assert_allclose(frac[:, ::-1], 1 - frac, atol=1e-12)    # symmetric about mid-gap
    np.testing.assert_allclose(frac[4], layer_fractions(n, 100.0), atol=1e-3)   # capped
    assert wall[4] > 1e-6

    mesh = extrude(coarse_base, hertz_gap, N_LAYERS, wall_cell=1e-6)
    column_z = mesh.points[:, 2].reshape(len(coarse_base.points), -1)
    h_nodes = column_z[:, -1]
    graded = h_nodes / N_LAYERS > 1.001e-6
    assert graded.any() and (~graded).any()
    np.testing.assert_allclose(column_z[graded, 1], 1e-6, rtol=0.02)  # normal columns lean
    np.testing.assert_allclose(column_z[~graded, 1], h_nodes[~graded] / N_LAYERS, rtol=0.02)
    # spans: each cell's bottom and top as fractions of its column, in order, 0 to 1
    lo, hi = mesh.spans.T
    assert np.all(hi > lo)
    assert np.all(lo[mesh.layer == 0] == 0.0) and np.allclose(hi[mesh.layer == N_LAYERS - 1], 1.0)
    share = mesh.cell_volumes / np.bincount(mesh.base_cell, mesh.cell_volumes)[mesh.base_cell]
    h_quad = h_nodes[coarse_base.quads][mesh.base_cell]
    even = h_quad.max(axis=1) < 1.15 * h_quad.min(axis=1)     # the gap's rise across a quad
    assert even.sum() > 0.3 * len(even)
    np.testing.assert_allclose((hi - lo)[even], share[even], rtol=0.1)
    with pytest.raises(ValueError, match="wall_cell must be a height > 0"):
        extrude(coarse_base, hertz_gap, N_LAYERS, wall_cell=-1e-6)
