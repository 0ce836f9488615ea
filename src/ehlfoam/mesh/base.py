"""The 2D all-quad base mesh of the domain, made by gmsh.

:func:`build_base_mesh` meshes the rectangle ``[x_min, x_max] x [0, y_max]`` (half domain,
``symmetric=True``) or ``[x_min, x_max] x [-y_max, y_max]`` (full domain) with a circular hole
of radius ``island_radius`` at the origin (the "island" replacing the Hertzian contact;
body-fitted circle arcs), optionally with a structured polar ring around it. gmsh's
Frontal-Delaunay for quads and full-quad recombination leave every element a quadrilateral,
of the size a user callable ``size(x, y)`` [m] asks for. Quads are ordered by reverse
Cuthill-McKee (small matrix bandwidth).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ehlfoam.errors import SpecError
from ehlfoam.mesh.domain import DEFAULT_MAX_QUADS, BaseMesh, MeshParams, SizeFunction
from ehlfoam.mesh.gmsh_model import (add_geometry, extract_mesh, gmsh_model, polar_divisions,
                                     size_callback, snap_polar)
from ehlfoam.mesh.topology import edge_key, edge_topology, renumber


def _sample_size(params: MeshParams, size: SizeFunction) -> tuple[float, float, float, bool]:
    """Check ``size`` on a 161 x 81 grid of the rectangle.

    Returns (smallest size, largest size, estimated number of quads
    = integral of 1/size^2 over the domain, whether size(x, -y) ==
    size(x, y) on the grid). Raises ValueError where the size is not a
    positive finite length.
    """
    xs = np.linspace(params.x_min, params.x_max, 161)
    ys = np.linspace(params.y_min, params.y_max, 81)
    X, Y = np.meshgrid(xs, ys)
    try:
        S = np.broadcast_to(np.asarray(size(X, Y), dtype=float), X.shape)
        S_mirror = np.broadcast_to(np.asarray(size(X, -Y), dtype=float), X.shape)
    except Exception as exc:  # noqa: BLE001 - report any failure of the user callable
        raise ValueError(f"size(x, y) failed on numpy arrays of points: {exc!r}") from exc
    bad = ~(np.isfinite(S) & (S > 0))
    if bad.any():
        i = np.flatnonzero(bad.ravel())[0]
        raise ValueError(
            f"size(x, y) must be a positive finite length (m) everywhere in the domain; "
            f"{int(bad.sum())} of {bad.size} sample points are not, e.g. "
            f"size({X.flat[i]:.6g}, {Y.flat[i]:.6g}) = {S.flat[i]!r}")
    outside = np.hypot(X, Y) >= params.island_radius
    density = np.where(outside, 1.0 / S**2, 0.0)
    estimate = float(np.trapezoid(np.trapezoid(density, xs, axis=1), ys))
    even = bool(np.allclose(S_mirror, S, rtol=1e-12, atol=0.0))
    return float(S.min()), float(S.max()), estimate, even


def estimate_quads(params: MeshParams, size: SizeFunction) -> float:
    """About how many quads :func:`build_base_mesh` makes of ``params`` with ``size``: the
    integral of 1 / size^2 over the domain outside the island, sampled on a 161 x 81 grid
    (milliseconds, whatever the sizes; within some 30 % of the mesh gmsh makes)."""
    return _sample_size(params, size)[2]


def _snap_boundary(points: np.ndarray, edges: dict[str, np.ndarray], params: MeshParams) -> None:
    """Put boundary nodes exactly on their boundary (in place): planar
    patches stay planar, island nodes lie on the circle."""
    for name, e in edges.items():
        ids = np.unique(e)
        if name == "inlet":
            points[ids, 0] = params.x_min
        elif name == "outlet":
            points[ids, 0] = params.x_max
        elif name == "side":
            points[ids, 1] = np.where(points[ids, 1] > 0, params.y_max, -params.y_max)
        elif name == "symmetry":
            points[ids, 1] = 0.0
        elif name == "island":
            r = np.hypot(points[ids, 0], points[ids, 1])
            points[ids] *= (params.island_radius / r)[:, None]


def build_base_mesh(params: MeshParams, size: SizeFunction,
                    max_quads: int = DEFAULT_MAX_QUADS) -> BaseMesh:
    """Mesh the 2D domain of ``params`` with quadrilaterals of size ``size``.

    ``size(x, y)`` gives the target cell edge length (m) at (x, y) (m); it
    must accept numpy arrays (checked on a grid first) and scalars (gmsh
    calls it point by point). ``max_quads`` guards against a size field in
    the wrong unit or a mesh too big for the machine: a
    :class:`~ehlfoam.errors.SpecError` (a ValueError) naming it is raised,
    before gmsh starts, when the estimated number of quads
    (:func:`estimate_quads`) exceeds it. Deterministic: the same input gives
    the same mesh.

    Full domain (``params.symmetric`` False): when ``size`` is even in y
    (size(x, -y) == size(x, y) on a sample grid) the half domain is meshed
    and mirrored, so the mesh itself is symmetric about y = 0; otherwise
    gmsh meshes the whole rectangle.

    Polar ring (``params.polar_radius`` set): the annulus between the island
    and ``polar_radius`` is a structured log-polar grid (radial spokes,
    circular rings, near-square cells of angular step size(rim) / island
    radius), the rest is meshed freely. A meniscus that follows a circle
    about the contact then meets every cell of the ring the same way, so
    the error of its discrete curvature does not change from cell to cell
    along it (docs/models/interface.md#the-mesh).
    """
    import gmsh

    if not isinstance(params, MeshParams):
        raise ValueError(f"params must be a MeshParams, got {type(params).__name__}")
    if not callable(size):
        raise ValueError(f"size must be a callable size(x, y) -> metres, got {size!r}")
    s_min, s_max, estimate, even = _sample_size(params, size)
    if estimate > max_quads:
        raise SpecError(
            f"max_quads = {max_quads}: size(x, y) asks for about {estimate:.3g} quads (sizes "
            f"{s_min:.3g}..{s_max:.3g} m), more than that (is size in metres? else raise "
            f"max_quads)")
    mirror = not params.symmetric and even
    if params.polar_radius is not None and not params.symmetric and not mirror:
        raise ValueError("a polar ring in the full domain needs a size even in y "
                         "(size(x, -y) == size(x, y)): the half ring is meshed and mirrored")
    mesh_params = replace(params, symmetric=True) if mirror else params
    divisions = polar_divisions(params, size) if params.polar_radius is not None else None
    errors: list[str] = []
    with gmsh_model("ehlfoam-gap"):
        if params.polar_radius is not None:
            # blossom recombination leaves quads 40-58 degrees non-orthogonal along the
            # ring's fixed nodes; simple full-quad keeps them below ~30
            # (docs/models/interface.md#the-mesh)
            gmsh.option.setNumber("Mesh.RecombinationAlgorithm", 2)
        curves = add_geometry(mesh_params, divisions)
        interrupts: list[BaseException] = []
        gmsh.model.mesh.setSizeCallback(size_callback(size, s_max, errors, interrupts))
        gmsh.model.mesh.generate(2)
        if interrupts:
            raise interrupts[0]
        if errors:
            raise ValueError(f"size(x, y) failed while meshing: {errors[0]}")
        points, quads, lines = extract_mesh(curves)
    if params.polar_radius is not None:
        snap_polar(points, mesh_params, divisions)
    base = _finish_base_mesh(points, quads, lines, mesh_params)
    return _mirror(base) if mirror else base


def _mirror(half: BaseMesh) -> BaseMesh:
    """The full-domain mesh made of ``half`` (y >= 0) and its mirror image
    in y = 0, joined along the symmetry edges (which disappear)."""
    n = half.n_points
    on_plane = np.zeros(n, dtype=bool)
    on_plane[np.unique(half.edges["symmetry"])] = True
    image = np.arange(n, dtype=np.int64)
    image[~on_plane] = n + np.arange(int(np.sum(~on_plane)))
    points = np.concatenate([half.points, half.points[~on_plane] * np.array([1.0, -1.0])])
    quads = np.concatenate([half.quads, image[half.quads][:, ::-1]])   # reflection: reverse
    edges = {name: np.concatenate([e, image[e][:, ::-1]])
             for name, e in half.edges.items() if name != "symmetry"}
    points, quads, old_to_new = renumber(points, quads)
    return BaseMesh(points=points, quads=quads,
                    edges={name: old_to_new[e] for name, e in edges.items()})


def _finish_base_mesh(points: np.ndarray, quads: np.ndarray, lines: dict[str, np.ndarray],
                      params: MeshParams) -> BaseMesh:
    """Orient, renumber and classify gmsh's raw mesh."""
    p, qd = points[quads], np.roll(points[quads], -1, axis=1)
    area = 0.5 * np.sum(p[..., 0] * qd[..., 1] - qd[..., 0] * p[..., 1], axis=1)
    quads = np.where((area < 0)[:, None], quads[:, ::-1], quads)
    points, quads, old_to_new = renumber(points, quads)
    topo = edge_topology(quads, len(points))
    edges: dict[str, np.ndarray] = {}
    for name, line in lines.items():
        if len(line) == 0:
            continue
        a, b = old_to_new[line[:, 0]], old_to_new[line[:, 1]]
        key = edge_key(a, b, len(points))
        pos = np.minimum(np.searchsorted(topo.bnd_key, key), len(topo.bnd_key) - 1)
        if np.any(topo.bnd_key[pos] != key):
            raise RuntimeError(f"gmsh's {name} curve edges are not on the quads' boundary")
        edges[name] = np.stack([topo.bnd_a[pos], topo.bnd_b[pos]], axis=1)
    _snap_boundary(points, edges, params)
    return BaseMesh(points=points, quads=quads, edges=edges)
