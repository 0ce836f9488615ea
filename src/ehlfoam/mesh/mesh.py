"""The thin-gap mesh: a 2D all-quad gmsh mesh extruded across the gap.

All lengths are SI metres. Coordinates: x is the rolling direction, y the
lateral direction, z across the gap; the origin is the contact centre. The
disc is the plane z = 0, the ball the surface z = h(x, y).

Three steps, each usable on its own:

:func:`build_base_mesh`
    A 2D mesh of the rectangle ``[x_min, x_max] x [0, y_max]`` (half domain,
    ``symmetric=True``) or ``[x_min, x_max] x [-y_max, y_max]`` (full
    domain) with a circular hole of radius ``island_radius`` at the origin
    (the "island" replacing the Hertzian contact; body-fitted circle arcs).
    Made by gmsh (Frontal-Delaunay for quads + blossom full-quad
    recombination: every element is a quadrilateral), with the cell size
    given by a user callable ``size(x, y)``.
:func:`extrude`
    The 2D mesh extruded into hexahedra with ``n_layers`` layers whose
    heights follow the local gap: node ``i`` at layer ``k`` sits at
    ``z = h(x_i, y_i) * k / n_layers``.
:func:`write_polymesh`
    The OpenFOAM ``constant/polyMesh`` files (ASCII), written directly by
    numpy (no OpenFOAM utility needed).

Patches (names and OpenFOAM types): ``disc`` (wall, z = 0), ``ball`` (wall,
z = h), ``island`` (wall, the hole's rim), ``inlet`` (patch, x = x_min),
``outlet`` (patch, x = x_max), ``side`` (patch, \\|y\\| = y_max) and, in the
half domain only, ``symmetry`` (symmetryPlane, y = 0).

Numbering: 2D quads are ordered by reverse Cuthill-McKee (small matrix
bandwidth); cell ``c`` is layer ``c % n_layers`` of quad ``c // n_layers``
(columns are contiguous), point ``p`` is level ``p % (n_layers + 1)`` of 2D
node ``p // (n_layers + 1)``.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import reverse_cuthill_mckee

__all__ = [
    "PATCH_TYPES",
    "BaseMesh",
    "MeshParams",
    "Patch",
    "PolyMesh",
    "build_base_mesh",
    "extrude",
    "gap_mismatch",
    "write_polymesh",
]

#: Patch name -> OpenFOAM patch type, in the order the patches are written.
PATCH_TYPES: dict[str, str] = {
    "disc": "wall",
    "ball": "wall",
    "island": "wall",
    "inlet": "patch",
    "outlet": "patch",
    "side": "patch",
    "symmetry": "symmetryPlane",
}
#: The patches made from 2D boundary edges (the others are the disc and ball).
EDGE_PATCHES: tuple[str, ...] = ("island", "inlet", "outlet", "side", "symmetry")

#: Default upper bound on the number of 2D quads the size field may ask for.
DEFAULT_MAX_QUADS = 2_000_000

SizeFunction = Callable[[np.ndarray, np.ndarray], np.ndarray]
GapFunction = Callable[[np.ndarray, np.ndarray], np.ndarray]


# ====================================================================== input
def _require_finite(name: str, value: float) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite number in metres, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be a finite number in metres, got {value!r}")
    return v


def _check_n_layers(n_layers: object) -> int:
    if isinstance(n_layers, bool) or not isinstance(n_layers, (int, np.integer)) or n_layers < 1:
        raise ValueError(f"n_layers must be an integer >= 1 (cells across the gap), "
                         f"got {n_layers!r}")
    return int(n_layers)


@dataclass(frozen=True)
class MeshParams:
    """Geometry of the thin-gap domain (metres).

    The rectangle is ``x_min <= x <= x_max`` and ``0 <= y <= y_max``
    (``symmetric=True``: half domain, symmetry plane y = 0) or
    ``-y_max <= y <= y_max`` (full domain). The circular hole of radius
    ``island_radius`` at the origin must lie strictly inside it:
    ``x_min < -island_radius``, ``island_radius < x_max``,
    ``island_radius < y_max``. ``n_layers`` is the number of cells across
    the gap. ``polar_radius`` (None: no ring) is the outer radius of a
    structured polar ring around the island (see :func:`build_base_mesh`);
    ``island_radius < polar_radius`` and the ring must lie strictly inside
    the rectangle.
    """

    x_min: float
    x_max: float
    y_max: float
    island_radius: float
    n_layers: int
    symmetric: bool = True
    polar_radius: float | None = None

    def __post_init__(self) -> None:
        for name in ("x_min", "x_max", "y_max", "island_radius"):
            _require_finite(name, getattr(self, name))
        r = float(self.island_radius)
        if r <= 0:
            raise ValueError(f"island_radius must be > 0 m, got {self.island_radius!r}")
        if not self.x_min < -r:
            raise ValueError(
                f"x_min must be < -island_radius = {-r:.6g} m (the island must lie inside "
                f"the rectangle), got x_min = {self.x_min!r}")
        if not self.x_max > r:
            raise ValueError(
                f"x_max must be > island_radius = {r:.6g} m (the island must lie inside "
                f"the rectangle), got x_max = {self.x_max!r}")
        if not self.y_max > r:
            raise ValueError(
                f"y_max must be > island_radius = {r:.6g} m (the island must lie inside "
                f"the rectangle), got y_max = {self.y_max!r}")
        _check_n_layers(self.n_layers)
        if self.polar_radius is not None:
            rp = _require_finite("polar_radius", self.polar_radius)
            nearest = min(-float(self.x_min), float(self.x_max), float(self.y_max))
            if not r < rp < nearest:
                raise ValueError(
                    f"polar_radius must lie between island_radius = {r:.6g} m and the nearest "
                    f"boundary ({nearest:.6g} m from the centre), got {self.polar_radius!r}")
        if not isinstance(self.symmetric, (bool, np.bool_)):
            raise ValueError(f"symmetric must be True or False, got {self.symmetric!r}")

    @property
    def y_min(self) -> float:
        """Lower y bound of the domain (m): 0 (half domain) or -y_max."""
        return 0.0 if self.symmetric else -float(self.y_max)

    @property
    def area(self) -> float:
        """Exact area of the domain (m^2): rectangle minus (half) disc."""
        hole = math.pi * self.island_radius**2 * (0.5 if self.symmetric else 1.0)
        return (self.x_max - self.x_min) * (self.y_max - self.y_min) - hole


# ================================================================ 2D mesh
@dataclass
class BaseMesh:
    """A 2D all-quad mesh (metres).

    ``points`` (n, 2); ``quads`` (m, 4) node ids, counter-clockwise seen
    from +z; ``edges`` patch name -> (k, 2) boundary edges (node ids),
    oriented so that their quad lies on the left (i.e. counter-clockwise
    along the quad).
    """

    points: np.ndarray
    quads: np.ndarray
    edges: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def n_points(self) -> int:
        return len(self.points)

    @property
    def n_quads(self) -> int:
        return len(self.quads)

    def quad_areas(self) -> np.ndarray:
        """Signed area of every quad (m^2; positive when counter-clockwise)."""
        p = self.points[self.quads]                     # (m, 4, 2)
        q = np.roll(p, -1, axis=1)
        return 0.5 * np.sum(p[..., 0] * q[..., 1] - q[..., 0] * p[..., 1], axis=1)


#: gmsh options set while meshing (restored afterwards if gmsh was already running).
_GMSH_OPTIONS: dict[str, float] = {
    "General.Terminal": 0,
    "General.NumThreads": 1,                 # deterministic
    "Mesh.Algorithm": 8,                     # Frontal-Delaunay for quads
    "Mesh.RecombineAll": 1,
    "Mesh.RecombinationAlgorithm": 3,        # blossom full-quad: no triangles left
    "Mesh.SubdivisionAlgorithm": 0,
    "Mesh.ElementOrder": 1,
    "Mesh.MeshSizeFactor": 1,
    "Mesh.MeshSizeMin": 0,
    "Mesh.MeshSizeMax": 1e22,
    "Mesh.MeshSizeFromPoints": 0,
    "Mesh.MeshSizeFromCurvature": 0,
    "Mesh.MeshSizeExtendFromBoundary": 0,
    "Mesh.Smoothing": 10,                    # Laplacian passes: max non-orthogonality ~12 deg
}


@contextmanager
def _gmsh_model(name: str) -> Iterator[None]:
    """A fresh gmsh model, cleaned up however the block ends.

    Initialises gmsh (without config files or signal handlers) and
    finalises it afterwards, unless the caller already runs gmsh: then the
    model is removed, the caller's current model and the options changed
    here are restored.
    """
    import gmsh

    owns = not gmsh.isInitialized()
    if owns:
        gmsh.initialize([], readConfigFiles=False, run=False, interruptible=False)
        previous_model = None
        saved: dict[str, float] = {}
    else:
        previous_model = gmsh.model.getCurrent()
        saved = {k: gmsh.option.getNumber(k) for k in _GMSH_OPTIONS}
    try:
        for key, value in _GMSH_OPTIONS.items():
            gmsh.option.setNumber(key, value)
        gmsh.model.add(name)
        yield
    finally:
        if owns:
            gmsh.finalize()
        else:
            try:
                gmsh.model.mesh.removeSizeCallback()
                gmsh.model.remove()
                if previous_model:
                    gmsh.model.setCurrent(previous_model)
            finally:
                for key, value in saved.items():
                    gmsh.option.setNumber(key, value)


def _polar_divisions(params: MeshParams, size: SizeFunction) -> tuple[int, int]:
    """Cells of the polar ring: (per quarter turn, across the ring).

    The ring's cells are near-squares in log-polar spacing: the angular step
    is the size at the island rim over the island radius, and the radii grow
    by the same factor, so the cell size grows in proportion to the radius
    from size(island rim) (what :func:`ehlfoam.case.writer.size_function`
    asks for everywhere). The quarter turn has an even number of cells.
    """
    r, rp = float(params.island_radius), float(params.polar_radius)
    rim = float(np.asarray(size(np.float64(0.0), np.float64(r)), dtype=float).reshape(-1)[0])
    quarter = max(2, 2 * round(0.25 * math.pi * r / rim))   # even: gmsh's full-quad
    # recombination needs an even number of segments on every curve of a free surface
    radial = max(1, round(math.log(rp / r) / (0.5 * math.pi / quarter)))
    return quarter, radial


def _add_polar_half(params: MeshParams, divisions: tuple[int, int]) -> dict[str, list[int]]:
    """The half domain with a structured polar ring around the island (transfinite,
    log-polar spacing, ``divisions`` from :func:`_polar_divisions`) and the rest meshed
    freely; return patch -> curve tags."""
    import gmsh

    geo = gmsh.model.geo
    r, rp, x0, x1, ym = (float(params.island_radius), float(params.polar_radius),
                         float(params.x_min), float(params.x_max), float(params.y_max))
    quarter, radial = divisions
    centre = geo.addPoint(0.0, 0.0, 0.0)
    p = {name: geo.addPoint(x, y, 0.0) for name, (x, y) in {
        "x0": (x0, 0.0), "-R": (-rp, 0.0), "-r": (-r, 0.0), "r_top": (0.0, r),
        "r": (r, 0.0), "R": (rp, 0.0), "R_top": (0.0, rp), "x1": (x1, 0.0),
        "x1_top": (x1, ym), "x0_top": (x0, ym)}.items()}
    sym = [geo.addLine(p["x0"], p["-R"]), geo.addLine(p["-r"], p["-R"]),
           geo.addLine(p["r"], p["R"]), geo.addLine(p["R"], p["x1"])]
    island = [geo.addCircleArc(p["-r"], centre, p["r_top"]),
              geo.addCircleArc(p["r_top"], centre, p["r"])]
    ring = [geo.addCircleArc(p["-R"], centre, p["R_top"]),
            geo.addCircleArc(p["R_top"], centre, p["R"])]
    outlet = geo.addLine(p["x1"], p["x1_top"])
    side = geo.addLine(p["x1_top"], p["x0_top"])
    inlet = geo.addLine(p["x0_top"], p["x0"])
    inner = geo.addPlaneSurface([geo.addCurveLoop(
        [island[0], island[1], sym[2], -ring[1], -ring[0], -sym[1]])])
    geo.addPlaneSurface([geo.addCurveLoop(
        [sym[0], ring[0], ring[1], sym[3], outlet, side, inlet])])
    geo.synchronize()
    mesh = gmsh.model.mesh
    for arc in island + ring:
        mesh.setTransfiniteCurve(arc, quarter + 1)
    growth = (rp / r) ** (1.0 / radial)
    for spoke in sym[1:3]:                          # both run outward from the island
        mesh.setTransfiniteCurve(spoke, radial + 1, "Progression", growth)
    mesh.setTransfiniteSurface(inner, cornerTags=[p["-r"], p["r"], p["R"], p["-R"]])
    mesh.setRecombine(2, inner)
    return {"island": island, "inlet": [inlet], "outlet": [outlet], "side": [side],
            "symmetry": sym}


def _snap_polar(points: np.ndarray, params: MeshParams, divisions: tuple[int, int]) -> None:
    """Put the ring's nodes exactly on their log-polar grid (in place): gmsh's transfinite
    interpolation leaves them up to ~1e-4 of the radius off their circles."""
    r, rp = float(params.island_radius), float(params.polar_radius)
    quarter, radial = divisions
    rho = np.hypot(points[:, 0], points[:, 1])
    ring = (rho >= r * (1.0 - 1e-6)) & (rho <= rp * (1.0 + 1e-6))   # not gmsh's centre point
    step_r = math.log(rp / r) / radial
    step_t = 0.5 * math.pi / quarter
    k = np.round(np.log(rho[ring] / r) / step_r)
    j = np.round(np.arctan2(points[ring, 1], points[ring, 0]) / step_t)
    points[ring] = (r * np.exp(k * step_r))[:, None] * np.stack(
        [np.cos(j * step_t), np.sin(j * step_t)], axis=1)


def _add_geometry(params: MeshParams,
                  divisions: tuple[int, int] | None) -> dict[str, list[int]]:
    """Build the domain in gmsh's built-in kernel (with the polar ring of ``divisions``
    when the params ask for one); return patch -> curve tags."""
    import gmsh

    if params.polar_radius is not None:
        return _add_polar_half(params, divisions)
    geo = gmsh.model.geo
    r, x0, x1, ym = (float(params.island_radius), float(params.x_min),
                     float(params.x_max), float(params.y_max))
    centre = geo.addPoint(0.0, 0.0, 0.0)
    if params.symmetric:
        p = [geo.addPoint(x, y, 0.0) for x, y in
             ((x0, 0.0), (-r, 0.0), (0.0, r), (r, 0.0), (x1, 0.0), (x1, ym), (x0, ym))]
        sym = [geo.addLine(p[0], p[1]), geo.addLine(p[3], p[4])]
        island = [geo.addCircleArc(p[1], centre, p[2]), geo.addCircleArc(p[2], centre, p[3])]
        outlet, side, inlet = geo.addLine(p[4], p[5]), geo.addLine(p[5], p[6]), geo.addLine(p[6], p[0])
        outer = geo.addCurveLoop([sym[0], island[0], island[1], sym[1], outlet, side, inlet])
        geo.addPlaneSurface([outer])
        curves = {"island": island, "inlet": [inlet], "outlet": [outlet], "side": [side],
                  "symmetry": sym}
    else:
        c = [geo.addPoint(x, y, 0.0) for x, y in ((x0, -ym), (x1, -ym), (x1, ym), (x0, ym))]
        bottom, outlet = geo.addLine(c[0], c[1]), geo.addLine(c[1], c[2])
        top, inlet = geo.addLine(c[2], c[3]), geo.addLine(c[3], c[0])
        q = [geo.addPoint(x, y, 0.0) for x, y in ((r, 0.0), (0.0, r), (-r, 0.0), (0.0, -r))]
        island = [geo.addCircleArc(q[i], centre, q[(i + 1) % 4]) for i in range(4)]
        outer = geo.addCurveLoop([bottom, outlet, top, inlet])
        hole = geo.addCurveLoop(island)
        geo.addPlaneSurface([outer, hole])
        curves = {"island": island, "inlet": [inlet], "outlet": [outlet],
                  "side": [bottom, top]}
    geo.synchronize()
    return curves


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


def _size_callback(size: SizeFunction, fallback: float, errors: list[str],
                   interrupts: list[BaseException]):
    """gmsh size callback calling ``size`` on one point (np.float64 scalars).

    Problems are recorded in ``errors`` (raising through gmsh's C code is
    not possible); the mesher then gets ``fallback`` so that it ends fast.
    A Ctrl-C or stop signal arriving in the callback (KeyboardInterrupt) is
    kept in ``interrupts`` for the caller to raise once gmsh has returned:
    ctypes would swallow it and hand gmsh a size of 0, a broken mesh.
    """
    def callback(dim: int, tag: int, x: float, y: float, z: float, lc: float) -> float:
        try:
            value = float(np.asarray(size(np.float64(x), np.float64(y)), dtype=float).reshape(-1)[0])
        except KeyboardInterrupt as exc:
            interrupts.append(exc)
            return fallback
        except Exception as exc:  # noqa: BLE001
            if not errors:
                errors.append(f"size({x:.6g}, {y:.6g}) raised {exc!r}")
            return fallback
        if not (math.isfinite(value) and value > 0):
            if not errors:
                errors.append(f"size({x:.6g}, {y:.6g}) = {value!r}, "
                              f"must be a positive finite length (m)")
            return fallback
        return value
    return callback


def _extract_mesh(curves: dict[str, list[int]]) -> tuple[np.ndarray, np.ndarray,
                                                          dict[str, np.ndarray]]:
    """gmsh's nodes, quads and boundary line elements (gmsh node tags)."""
    import gmsh

    tags, coords, _ = gmsh.model.mesh.getNodes()
    types, _, nodes = gmsh.model.mesh.getElements(dim=2)
    kinds = {int(t): gmsh.model.mesh.getElementProperties(int(t))[0] for t in types}
    if any(int(t) != 3 for t in types):
        raise RuntimeError(f"gmsh left non-quadrilateral elements: {sorted(kinds.values())}")
    quads = np.asarray(nodes[0], dtype=np.int64).reshape(-1, 4)
    lines: dict[str, np.ndarray] = {}
    for name, tags_of_patch in curves.items():
        parts = []
        for tag in tags_of_patch:
            ltypes, _, lnodes = gmsh.model.mesh.getElements(dim=1, tag=tag)
            parts += [np.asarray(n, dtype=np.int64).reshape(-1, 2)
                      for t, n in zip(ltypes, lnodes) if int(t) == 1]
        lines[name] = np.concatenate(parts) if parts else np.zeros((0, 2), np.int64)
    points = np.asarray(coords, dtype=float).reshape(-1, 3)[:, :2]
    index = np.full(int(np.max(tags)) + 1, -1, dtype=np.int64)
    index[np.asarray(tags, dtype=np.int64)] = np.arange(len(tags))
    return points, index[quads], {k: index[v] for k, v in lines.items()}


@dataclass(frozen=True)
class _EdgeTopology:
    """Edges of a 2D quad mesh. Internal edge ``a -> b`` has quad ``left``
    on its left (counter-clockwise in it) and ``right`` on its right;
    boundary edge ``a -> b`` has its only quad ``quad`` on the left."""

    a: np.ndarray
    b: np.ndarray
    left: np.ndarray
    right: np.ndarray
    bnd_a: np.ndarray
    bnd_b: np.ndarray
    bnd_quad: np.ndarray
    bnd_key: np.ndarray      # sorted undirected keys of the boundary edges


def _edge_key(a: np.ndarray, b: np.ndarray, n_points: int) -> np.ndarray:
    return np.minimum(a, b).astype(np.int64) * n_points + np.maximum(a, b)


def _edge_topology(quads: np.ndarray, n_points: int) -> _EdgeTopology:
    """Pair up the half-edges of counter-clockwise quads."""
    m = len(quads)
    a = quads.ravel()
    b = np.roll(quads, -1, axis=1).ravel()
    q = np.repeat(np.arange(m, dtype=np.int64), 4)
    key = _edge_key(a, b, n_points)
    order = np.argsort(key, kind="stable")
    ks = key[order]
    _, start, count = np.unique(ks, return_index=True, return_counts=True)
    if count.size and count.max() > 2:
        raise ValueError("base mesh is not manifold: an edge is shared by more than two quads")
    first = order[start[count == 2]]
    second = order[start[count == 2] + 1]
    if np.any(a[second] != b[first]):
        raise ValueError("base mesh quads are not consistently oriented "
                         "(a shared edge runs the same way in both quads)")
    lone = order[start[count == 1]]               # sorted by key
    return _EdgeTopology(a=a[first], b=b[first], left=q[first], right=q[second],
                         bnd_a=a[lone], bnd_b=b[lone], bnd_quad=q[lone], bnd_key=key[lone])


def _renumber(points: np.ndarray, quads: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Drop unused nodes, order quads by reverse Cuthill-McKee and nodes by
    first use in the reordered quads. Returns (points, quads, new id of
    every old node, -1 if unused)."""
    topo = _edge_topology(quads, len(points))
    m = len(quads)
    adj = coo_matrix((np.ones(2 * len(topo.a)),
                      (np.r_[topo.left, topo.right], np.r_[topo.right, topo.left])),
                     shape=(m, m)).tocsr()
    quads = quads[reverse_cuthill_mckee(adj, symmetric_mode=True)]
    flat = quads.ravel()
    _, first_use = np.unique(flat, return_index=True)
    used = flat[np.sort(first_use)]               # node ids in order of first use
    new_id = np.full(len(points), -1, dtype=np.int64)
    new_id[used] = np.arange(len(used))
    return points[used], new_id[quads], new_id


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
    the wrong unit: a ValueError is raised when the estimated number of
    quads (integral of 1/size^2) exceeds it. Deterministic: the same input
    gives the same mesh.

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
    along it (docs/cases.md, "A polar ring around the contact").
    """
    import gmsh

    if not isinstance(params, MeshParams):
        raise ValueError(f"params must be a MeshParams, got {type(params).__name__}")
    if not callable(size):
        raise ValueError(f"size must be a callable size(x, y) -> metres, got {size!r}")
    s_min, s_max, estimate, even = _sample_size(params, size)
    if estimate > max_quads:
        raise ValueError(
            f"size(x, y) asks for about {estimate:.3g} quads (sizes {s_min:.3g}..{s_max:.3g} m), "
            f"more than max_quads = {max_quads}; is size in metres?")
    mirror = not params.symmetric and even
    if params.polar_radius is not None and not params.symmetric and not mirror:
        raise ValueError("a polar ring in the full domain needs a size even in y "
                         "(size(x, -y) == size(x, y)): the half ring is meshed and mirrored")
    mesh_params = replace(params, symmetric=True) if mirror else params
    divisions = _polar_divisions(params, size) if params.polar_radius is not None else None
    errors: list[str] = []
    with _gmsh_model("ehlfoam-gap"):
        if params.polar_radius is not None:
            # blossom recombination leaves quads 40-58 degrees non-orthogonal along the
            # ring's fixed nodes; simple full-quad keeps them below ~30 (docs/cases.md)
            gmsh.option.setNumber("Mesh.RecombinationAlgorithm", 2)
        curves = _add_geometry(mesh_params, divisions)
        interrupts: list[BaseException] = []
        gmsh.model.mesh.setSizeCallback(_size_callback(size, s_max, errors, interrupts))
        gmsh.model.mesh.generate(2)
        if interrupts:
            raise interrupts[0]
        if errors:
            raise ValueError(f"size(x, y) failed while meshing: {errors[0]}")
        points, quads, lines = _extract_mesh(curves)
    if params.polar_radius is not None:
        _snap_polar(points, mesh_params, divisions)
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
    points, quads, old_to_new = _renumber(points, quads)
    return BaseMesh(points=points, quads=quads,
                    edges={name: old_to_new[e] for name, e in edges.items()})


def _finish_base_mesh(points: np.ndarray, quads: np.ndarray, lines: dict[str, np.ndarray],
                      params: MeshParams) -> BaseMesh:
    """Orient, renumber and classify gmsh's raw mesh."""
    p, qd = points[quads], np.roll(points[quads], -1, axis=1)
    area = 0.5 * np.sum(p[..., 0] * qd[..., 1] - qd[..., 0] * p[..., 1], axis=1)
    quads = np.where((area < 0)[:, None], quads[:, ::-1], quads)
    points, quads, old_to_new = _renumber(points, quads)
    topo = _edge_topology(quads, len(points))
    edges: dict[str, np.ndarray] = {}
    for name, line in lines.items():
        if len(line) == 0:
            continue
        a, b = old_to_new[line[:, 0]], old_to_new[line[:, 1]]
        key = _edge_key(a, b, len(points))
        pos = np.minimum(np.searchsorted(topo.bnd_key, key), len(topo.bnd_key) - 1)
        if np.any(topo.bnd_key[pos] != key):
            raise RuntimeError(f"gmsh's {name} curve edges are not on the quads' boundary")
        edges[name] = np.stack([topo.bnd_a[pos], topo.bnd_b[pos]], axis=1)
    _snap_boundary(points, edges, params)
    return BaseMesh(points=points, quads=quads, edges=edges)


# ============================================================ polyMesh
@dataclass(frozen=True)
class Patch:
    """A boundary patch: faces ``start .. start + size - 1``."""

    name: str
    type: str
    start: int
    size: int


@dataclass
class PolyMesh:
    """A 3D OpenFOAM-style mesh (metres) of hexahedra.

    ``faces`` (F, 4) point ids, normal (right-hand rule) from owner to
    neighbour, pointing out of the domain on boundary faces; internal faces
    first in upper-triangular order. ``face_centres``/``face_areas``
    (F, 3) and ``cell_centres`` (C, 3)/``cell_volumes`` (C,) are computed as
    OpenFOAM does (m, m^2, m^3). ``base_cell`` is the 2D quad of each cell,
    ``layer`` its layer (0 at the disc); ``spans`` (C, 2) the bottom and top of each
    cell across its column as fractions of the gap (0 on the disc, 1 on the ball: the mean
    of its nodes' levels, :func:`extrude`).
    """

    points: np.ndarray
    faces: np.ndarray
    owner: np.ndarray
    neighbour: np.ndarray
    patches: list[Patch]
    cell_centres: np.ndarray
    cell_volumes: np.ndarray
    base_cell: np.ndarray
    layer: np.ndarray
    face_centres: np.ndarray
    face_areas: np.ndarray
    spans: np.ndarray

    @property
    def n_cells(self) -> int:
        return len(self.cell_volumes)

    @property
    def n_internal_faces(self) -> int:
        return len(self.neighbour)

    @property
    def _points_per_node(self) -> int:
        """n_layers + 1: the levels of each base node's column (:func:`extrude`'s order)."""
        return int(self.layer.max()) + 2

    def base_node(self, point_ids: np.ndarray) -> np.ndarray:
        """The 2D base-mesh node of each point id: point ``p`` is a level of node
        ``p // (n_layers + 1)`` (:func:`extrude`'s order), whether or not its column
        leans."""
        return np.asarray(point_ids) // self._points_per_node

    def top_point(self, nodes: np.ndarray) -> np.ndarray:
        """The point id of the top of each 2D base-mesh node's column, on the ball (the
        inverse of :meth:`base_node` at the last level)."""
        return (np.asarray(nodes) + 1) * self._points_per_node - 1

    def patch(self, name: str) -> Patch:
        """The patch called ``name`` (KeyError if absent)."""
        for p in self.patches:
            if p.name == name:
                return p
        raise KeyError(f"no patch {name!r}; patches: {[p.name for p in self.patches]}")

    def patch_slice(self, name: str) -> slice:
        p = self.patch(name)
        return slice(p.start, p.start + p.size)


def _gap_at_nodes(base: BaseMesh, gap: GapFunction) -> np.ndarray:
    """h at every 2D node (m); ValueError naming where it is not > 0 and finite."""
    x, y = base.points[:, 0], base.points[:, 1]
    try:
        h = np.asarray(gap(x, y), dtype=float)
        h = np.broadcast_to(h, x.shape).astype(float)
    except Exception as exc:  # noqa: BLE001 - report any failure of the user callable
        raise ValueError(f"gap(x, y) failed on the {len(x)} base-mesh nodes: {exc!r}") from exc
    bad = ~(np.isfinite(h) & (h > 0))
    if bad.any():
        i = np.flatnonzero(bad)
        where = ", ".join(f"gap({x[k]:.6g}, {y[k]:.6g}) = {h[k]!r}" for k in i[:3])
        raise ValueError(f"gap must be > 0 and finite (m) at every node; {len(i)} of {len(x)} "
                         f"nodes are not: {where}{' ...' if len(i) > 3 else ''}")
    return h


def _lateral_faces(a: np.ndarray, b: np.ndarray, n_layers: int) -> np.ndarray:
    """Vertical faces above 2D edges ``a -> b``: (k * n_layers, 4) point ids,
    edge-major, normal to the right of ``a -> b``."""
    lev = np.arange(n_layers)
    s = n_layers + 1
    pa, pb = (a * s)[:, None] + lev, (b * s)[:, None] + lev
    return np.stack([pa, pb, pb + 1, pa + 1], axis=-1).reshape(-1, 4)


def _level_faces(quads: np.ndarray, levels: np.ndarray, n_layers: int) -> np.ndarray:
    """Faces of ``quads`` at ``levels``: (m * len(levels), 4), quad-major,
    normal +z."""
    s = n_layers + 1
    return ((quads * s)[:, None, :] + levels[None, :, None]).reshape(-1, 4)


def _internal_faces(quads: np.ndarray, topo: _EdgeTopology,
                    n_layers: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Internal faces, owners and neighbours in upper-triangular order."""
    L = n_layers
    m = len(quads)
    lev = np.arange(L)
    # between layers k-1 and k of each column
    f_lay = _level_faces(quads, np.arange(1, L), L)
    o_lay = (np.arange(m)[:, None] * L + np.arange(L - 1)).ravel()
    n_lay = o_lay + 1
    # across 2D internal edges; owner = lower cell index
    f_lat = _lateral_faces(topo.a, topo.b, L)
    c_left = (topo.left[:, None] * L + lev).ravel()
    c_right = (topo.right[:, None] * L + lev).ravel()
    flip = c_left > c_right
    f_lat[flip] = f_lat[flip][:, ::-1]            # reversed order: normal to the left
    o_lat, n_lat = np.minimum(c_left, c_right), np.maximum(c_left, c_right)
    faces = np.concatenate([f_lay, f_lat])
    own = np.concatenate([o_lay, o_lat])
    nei = np.concatenate([n_lay, n_lat])
    order = np.lexsort((nei, own))
    return faces[order], own[order], nei[order]


def _boundary_faces(base: BaseMesh, topo: _EdgeTopology,
                    n_layers: int) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Patch name -> (faces, owners), each sorted by owner."""
    L = n_layers
    m = len(base.quads)
    cols = np.arange(m)
    out = {
        "disc": (_level_faces(base.quads[:, ::-1], np.array([0]), L), cols * L),
        "ball": (_level_faces(base.quads, np.array([L]), L), cols * L + L - 1),
    }
    covered = np.zeros(len(topo.bnd_key), dtype=np.int64)
    n_pts = len(base.points)
    for name, e in base.edges.items():
        if name not in EDGE_PATCHES:
            raise ValueError(f"base.edges has unknown patch {name!r}; expected one of "
                             f"{', '.join(EDGE_PATCHES)}")
        e = np.asarray(e, dtype=np.int64).reshape(-1, 2)
        if len(e) == 0:
            continue
        key = _edge_key(e[:, 0], e[:, 1], n_pts)
        pos = np.minimum(np.searchsorted(topo.bnd_key, key), len(topo.bnd_key) - 1)
        if np.any(topo.bnd_key[pos] != key):
            raise ValueError(f"base.edges[{name!r}] has edges that are not on the "
                             f"boundary of the quads")
        np.add.at(covered, pos, 1)
        faces = _lateral_faces(topo.bnd_a[pos], topo.bnd_b[pos], L)
        own = (topo.bnd_quad[pos][:, None] * L + np.arange(L)).ravel()
        order = np.argsort(own, kind="stable")
        out[name] = (faces[order], own[order])
    if np.any(covered != 1):
        raise ValueError(f"base.edges must put every boundary edge in exactly one patch: "
                         f"{int(np.sum(covered == 0))} edges in none, "
                         f"{int(np.sum(covered > 1))} in several")
    return out


def _face_geometry(points: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Face centres and area vectors as OpenFOAM computes them (triangles
    around the point average, centroid weighted by triangle area)."""
    px, py, pz = (points[:, d][faces] for d in range(3))     # (F, 4) each
    ax, ay, az = px.mean(axis=1), py.mean(axis=1), pz.mean(axis=1)
    nx_, ny_, nz_ = (c[:, [1, 2, 3, 0]] for c in (px, py, pz))
    ux, uy, uz = nx_ - px, ny_ - py, nz_ - pz                 # edge
    vx, vy, vz = ax[:, None] - px, ay[:, None] - py, az[:, None] - pz
    cx, cy, cz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx   # 2 x triangle areas
    mag = np.sqrt(cx * cx + cy * cy + cz * cz)
    sum_a = mag.sum(axis=1)
    ok = sum_a > 0
    w = mag / np.where(ok, 3.0 * sum_a, 1.0)[:, None]
    centres = np.stack([np.where(ok, np.sum(w * (p + q), axis=1) + a * np.sum(w, axis=1), a)
                        for p, q, a in ((px, nx_, ax), (py, ny_, ay), (pz, nz_, az))], axis=1)
    areas = 0.5 * np.stack([cx.sum(axis=1), cy.sum(axis=1), cz.sum(axis=1)], axis=1)
    return centres, areas


def _cell_geometry(n_cells: int, owner: np.ndarray, neighbour: np.ndarray,
                   fc: np.ndarray, sf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cell centres and volumes as OpenFOAM computes them (pyramids from
    the face-centre average)."""
    nf = len(neighbour)
    cells = np.concatenate([owner, neighbour])
    fcs = np.concatenate([fc, fc[:nf]])
    count = np.bincount(cells, minlength=n_cells)
    est = np.stack([np.bincount(cells, fcs[:, d], n_cells) for d in range(3)], axis=1)
    est /= count[:, None]
    sign = np.concatenate([np.ones(len(owner)), -np.ones(nf)])
    sfs = np.concatenate([sf, sf[:nf]])
    pyr = sign * np.einsum("fd,fd->f", sfs, fcs - est[cells])     # 3 x pyramid volume
    pc = 0.75 * fcs + 0.25 * est[cells]
    vol3 = np.bincount(cells, pyr, n_cells)
    ctr = np.stack([np.bincount(cells, pyr * pc[:, d], n_cells) for d in range(3)], axis=1)
    ok = np.abs(vol3) > 1e-300
    ctr = np.where(ok[:, None], ctr / np.where(ok, vol3, 1.0)[:, None], est)
    return ctr, vol3 / 3.0


def _tanh_levels(s: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """Level fractions 0 .. 1 at uniform ``s`` (L + 1,) of the tanh stretching of strength
    ``beta`` (shape (...,)): shape (..., L + 1); beta -> 0 is uniform."""
    beta = np.maximum(np.asarray(beta, float), 1e-6)[..., None]
    f = 0.5 * (1 + np.tanh(beta * (2 * s - 1)) / np.tanh(beta))
    f[..., 0], f[..., -1] = 0.0, 1.0
    return f


def _stretching(n_layers: int, wall_grading: float) -> float:
    """The tanh stretching strength whose mid-gap cell is ``wall_grading`` times the wall
    cell (bisection: the ratio grows with the strength)."""
    s = np.arange(n_layers + 1) / n_layers

    def ratio(beta: float) -> float:
        d = np.diff(_tanh_levels(s, beta))
        return d[len(d) // 2] / d[0]

    lo, hi = 1e-6, 20.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ratio(mid) < wall_grading else (lo, mid)
    return 0.5 * (lo + hi)


def layer_fractions(n_layers: int, wall_grading: float = 1.0) -> np.ndarray:
    """Level heights as fractions of the gap, 0 .. 1 (n_layers + 1 values), symmetric about
    mid-gap; ``wall_grading`` is the ratio of the middle cell's height to the wall cell's
    (1: uniform). A tanh stretching, so that the growth from cell to cell is smooth; it
    resolves oil layers and films on both walls."""
    s = np.arange(n_layers + 1) / n_layers
    if not wall_grading > 1.0 or n_layers < 3:
        return s
    return _tanh_levels(s, _stretching(n_layers, wall_grading))


def column_fractions(h: np.ndarray, n_layers: int, wall_cell: float,
                     max_grading: float = 100.0) -> np.ndarray:
    """Level fractions (n, n_layers + 1) for columns of gap ``h`` (n,) [m] whose wall cells
    are ``wall_cell`` [m] high: each column graded (tanh, as :func:`layer_fractions`) just
    enough for it, uniform where h / n_layers is that thin already, and graded
    ``max_grading`` where even that leaves the wall cell thicker. One wall cell height
    everywhere puts thin cells (a small share of the gap) where the gap is wide, at the rear
    meniscus whose films they must hold, and thick ones near the contact, where the dry walls
    run into the region's front and in-plane cells within some 15 wall cells suffice
    (docs/cases.md, "One wall cell everywhere")."""
    h = np.asarray(h, float)
    s = np.arange(n_layers + 1) / n_layers
    if n_layers < 3:
        return np.broadcast_to(s, (len(h), n_layers + 1)).copy()
    beta_max = _stretching(n_layers, max_grading)
    table = np.linspace(0.0, beta_max, 400)
    wall = _tanh_levels(s, table)[:, 1]                       # falls as beta grows
    beta = np.interp(wall_cell / h, wall[::-1], table[::-1])  # clamps at both ends
    return _tanh_levels(s, beta)


#: How the columns of nodes run across the gap (:func:`extrude`).
COLUMNS = ("normal", "vertical")


def _column_tilt(base: BaseMesh, gap: GapFunction, h: np.ndarray) -> np.ndarray:
    """In-plane offset (m, (n, 2)) of each node column at the ball, for columns that cross
    the levels z = f h(x, y) at right angles.

    Such a column solves dx/dz = -z grad(h) / h; with h and grad h taken at its foot on
    the disc, x(z) = x0 - z^2 grad(h) / (2 h), so level f sits at x0 + f^2 d with
    d = -h grad(h) / 2: a few um where the gap is tens of um and sloping, next to nothing
    at the contact. Boundary nodes keep the component along their boundary only, so the
    planar patches stay planar and the island a cylinder."""
    x, y = base.points[:, 0], base.points[:, 1]
    edge = np.linalg.norm(np.diff(base.points[base.quads], axis=1), axis=2).min()
    eps = 1e-2 * edge
    hx = (np.asarray(gap(x + eps, y)) - np.asarray(gap(x - eps, y))) / (2 * eps)
    hy = (np.asarray(gap(x, y + eps)) - np.asarray(gap(x, y - eps))) / (2 * eps)
    d = -0.5 * h[:, None] * np.stack([hx, hy], axis=1)
    for name, e in base.edges.items():
        ids = np.unique(e)
        if name in ("inlet", "outlet"):
            d[ids, 0] = 0.0
        elif name in ("side", "symmetry"):
            d[ids, 1] = 0.0
        elif name == "island":
            radial = base.points[ids] / np.linalg.norm(base.points[ids], axis=1)[:, None]
            d[ids] -= np.sum(d[ids] * radial, axis=1)[:, None] * radial
    return d


def extrude(base: BaseMesh, gap: GapFunction, n_layers: int,
            wall_grading: float = 1.0, columns: str = "normal",
            wall_cell: float | None = None) -> PolyMesh:
    """Extrude ``base`` across the gap into ``n_layers`` layers of hexahedra.

    ``gap(x, y)`` is the local gap height h (m) at arrays of points (m); it
    must be > 0 and finite at every base node. Level ``k`` of node ``i`` lies
    on the surface z = f_k h(x, y): disc at z = 0, ball at z = h, with
    f_k = k / n_layers or graded toward both walls (:func:`layer_fractions`), or with
    ``wall_cell`` [m] graded column by column so that every wall cell is that high where the
    gap allows (:func:`column_fractions`; ``wall_grading`` is then unused).

    ``columns = "vertical"``: the node sits at ``(x_i, y_i, h_i * f_k)``.
    ``columns = "normal"`` (default): the column leans so that it crosses every level at
    right angles (:func:`_column_tilt`; an in-plane shift of a few um at most), which takes
    away the non-orthogonality that vertical columns give every face where the ball slopes
    (the line between two cell centres follows the sloping level, the face between them
    stands upright), and makes the wall cells meet both walls at right angles. On the
    nominal case this removed an oil film that crept off the track along the ball
    (docs/cases.md, "Columns across the gap").
    """
    L = _check_n_layers(n_layers)
    points2, quads = np.asarray(base.points, float), np.asarray(base.quads, np.int64)
    if points2.ndim != 2 or points2.shape[1] != 2 or quads.ndim != 2 or quads.shape[1] != 4:
        raise ValueError(f"base must have points (n, 2) and quads (m, 4), got "
                         f"{points2.shape} and {quads.shape}")
    if len(quads) == 0 or quads.min() < 0 or quads.max() >= len(points2):
        raise ValueError("base.quads must be non-empty and refer to existing points")
    if np.any(base.quad_areas() <= 0):
        raise ValueError("base.quads must all be counter-clockwise seen from +z "
                         f"({int(np.sum(base.quad_areas() <= 0))} are not)")
    h = _gap_at_nodes(base, gap)
    if not (np.isfinite(wall_grading) and 1.0 <= wall_grading <= 100.0):
        raise ValueError(f"wall_grading must be in [1, 100], got {wall_grading!r}")
    if columns not in COLUMNS:
        raise ValueError(f"columns must be one of {COLUMNS}, got {columns!r}")
    if wall_cell is not None and not (np.isfinite(wall_cell) and wall_cell > 0.0):
        raise ValueError(f"wall_cell must be a height > 0 (m), got {wall_cell!r}")
    frac = (column_fractions(h, L, wall_cell) if wall_cell is not None
            else np.broadcast_to(layer_fractions(L, wall_grading), (len(h), L + 1)))
    points = np.empty((len(points2), L + 1, 3))
    points[..., :2] = points2[:, None, :]
    points[..., 2] = h[:, None] * frac
    if columns == "normal":
        tilt = _column_tilt(base, gap, h)
        points[:, 1:, :2] += frac[:, 1:, None] ** 2 * tilt[:, None, :]   # f = 1: the ball
        inner = points[:, 1:, :2].reshape(-1, 2)
        points[:, 1:, 2] = (np.asarray(gap(inner[:, 0], inner[:, 1]), float)
                            .reshape(len(points2), L) * frac[:, 1:])
    points = points.reshape(-1, 3)

    topo = _edge_topology(quads, len(points2))
    f_int, own_int, nei_int = _internal_faces(quads, topo, L)
    bnd = _boundary_faces(base, topo, L)
    faces, owners, patches = [f_int], [own_int], []
    start = len(f_int)
    for name, ptype in PATCH_TYPES.items():
        if name in bnd and len(bnd[name][0]):
            faces.append(bnd[name][0])
            owners.append(bnd[name][1])
            patches.append(Patch(name, ptype, start, len(bnd[name][0])))
            start += len(bnd[name][0])
    faces_a = np.concatenate(faces)
    owner = np.concatenate(owners)
    n_cells = len(quads) * L
    fc, sf = _face_geometry(points, faces_a)
    cc, vol = _cell_geometry(n_cells, owner, nei_int, fc, sf)
    cells = np.arange(n_cells)
    quad_frac = frac[quads].mean(axis=1)                      # (quads, L + 1)
    spans = np.stack([quad_frac[:, :-1], quad_frac[:, 1:]], axis=2).reshape(n_cells, 2)
    return PolyMesh(points=points, faces=faces_a, owner=owner, neighbour=nei_int,
                    patches=patches, cell_centres=cc, cell_volumes=vol,
                    base_cell=cells // L, layer=cells % L, face_centres=fc, face_areas=sf,
                    spans=spans)


def wall_steps(base: BaseMesh, mesh: PolyMesh) -> np.ndarray:
    """Per base quad, how many wall-cell heights the ball surface rises or falls across the
    quad: (max h - min h over its nodes) / (mean wall-cell height over its nodes), read off
    ``mesh = extrude(base, ...)`` (its node columns: disc, the wall cell's top, ..., ball).
    Where the ball slopes (|grad h| ~ r / R), thin wall cells under wide quads stair-step
    along it; above ~10 steps a spurious oil film creeps along the ball beside the flooded
    region (docs/cases.md, "Thinner wall cells: the ball's stair-steps")."""
    quads = np.asarray(base.quads, np.int64)
    column_z = mesh.points[:, 2].reshape(len(base.points), -1)   # extrude's node order
    h, wall = column_z[quads, -1], column_z[quads, 1]
    return (h.max(axis=1) - h.min(axis=1)) / wall.mean(axis=1)


def split_patch(mesh: PolyMesh, name: str, select: np.ndarray, new_name: str,
                new_type: str = "patch") -> PolyMesh:
    """A copy of ``mesh`` in which the faces of patch ``name`` where ``select`` (bool, one per
    face of the patch) form a new patch ``new_name`` placed right after it. Faces are only
    reordered within the old patch's range, so the rest of the mesh is unchanged."""
    sl = mesh.patch_slice(name)
    select = np.asarray(select, dtype=bool)
    if select.shape != (sl.stop - sl.start,):
        raise ValueError(f"select must have one entry per face of {name!r} "
                         f"({sl.stop - sl.start}), got shape {select.shape}")
    if any(p.name == new_name for p in mesh.patches):
        raise ValueError(f"patch {new_name!r} exists already")
    order = np.r_[np.flatnonzero(~select), np.flatnonzero(select)] + sl.start
    perm = np.arange(len(mesh.faces))
    perm[sl] = order
    patches = []
    for p in mesh.patches:
        if p.name != name:
            patches.append(p)
            continue
        kept = int((~select).sum())
        if kept:
            patches.append(Patch(p.name, p.type, p.start, kept))
        if select.any():
            patches.append(Patch(new_name, new_type, p.start + kept, int(select.sum())))
    return PolyMesh(points=mesh.points, faces=mesh.faces[perm], owner=mesh.owner[perm],
                    neighbour=mesh.neighbour, patches=patches, cell_centres=mesh.cell_centres,
                    cell_volumes=mesh.cell_volumes, base_cell=mesh.base_cell, layer=mesh.layer,
                    face_centres=mesh.face_centres[perm], face_areas=mesh.face_areas[perm],
                    spans=mesh.spans)


def gap_mismatch(mesh: PolyMesh, gap: GapFunction) -> float:
    """Largest relative error of the mesh's gap height on the ball:
    max over ``ball`` faces of \\|z(face centre) - h(x, y)\\| / h(x, y) (the
    disc is z = 0, so the face centre's z is the column height there)."""
    fc = mesh.face_centres[mesh.patch_slice("ball")]
    h = np.asarray(gap(fc[:, 0], fc[:, 1]), dtype=float)
    return float(np.max(np.abs(fc[:, 2] - h) / h))


# =============================================================== writing
_BANNER = """\
/*--------------------------------*- C++ -*----------------------------------*\\
| ehlfoam: thin-gap mesh (generator/mesh.py)                                  |
\\*---------------------------------------------------------------------------*/
"""
#: Rows formatted per chunk when writing large lists.
_CHUNK = 65536


def _header(cls: str, obj: str, note: str | None = None) -> str:
    lines = ["FoamFile", "{", "    version     2.0;", "    format      ascii;",
             f"    class       {cls};"]
    if note:
        lines.append(f'    note        "{note}";')
    lines += ['    location    "constant/polyMesh";', f"    object      {obj};", "}"]
    return _BANNER + "\n".join(lines) + "\n// " + "* " * 37 + "//\n\n"


def _write_atomic(path: Path, chunks: Iterator[str]) -> None:
    """Write ``chunks`` to a temporary file next to ``path``, then rename it
    into place (readers never see a partial file)."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{os.urandom(4).hex()}.tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    try:
        with os.fdopen(fd, "w", encoding="ascii", newline="\n") as fh:
            for chunk in chunks:
                fh.write(chunk)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _list_chunks(header: str, rows: np.ndarray, row_format: str) -> Iterator[str]:
    """An OpenFOAM list: header, count, ``(``, one formatted row per line, ``)``."""
    yield header + f"{len(rows)}\n(\n"
    for i in range(0, len(rows), _CHUNK):
        block = rows[i:i + _CHUNK]
        yield (row_format * len(block)) % tuple(block.reshape(-1).tolist())
    yield ")\n\n// " + "*" * 73 + " //\n"


def _boundary_text(patches: list[Patch]) -> str:
    body = [f"{len(patches)}", "("]
    for p in patches:
        body += [f"    {p.name}", "    {", f"        type            {p.type};"]
        if p.type in ("wall", "symmetryPlane"):
            body.append(f"        inGroups        List<word> 1({p.type});")
        body += [f"        nFaces          {p.size};", f"        startFace       {p.start};",
                 "    }"]
    body += [")", "", "// " + "*" * 73 + " //", ""]
    return _header("polyBoundaryMesh", "boundary") + "\n".join(body)


#: Files in constant/polyMesh that describe an earlier mesh and would clash.
_STALE = ("points.gz", "faces.gz", "owner.gz", "neighbour.gz", "boundary.gz",
          "cellZones", "faceZones", "pointZones", "cellZones.gz", "faceZones.gz",
          "pointZones.gz")


def write_polymesh(mesh: PolyMesh, case_dir: str | os.PathLike[str]) -> None:
    """Write ``case_dir/constant/polyMesh/{points,faces,owner,neighbour,boundary}``
    (ASCII; points with 12 significant digits, m). Each file is written to a
    temporary file and renamed into place; compressed copies and zone files
    left by an earlier mesh are removed."""
    poly = Path(case_dir) / "constant" / "polyMesh"
    poly.mkdir(parents=True, exist_ok=True)
    n_faces, n_int, n_cells = len(mesh.faces), len(mesh.neighbour), mesh.n_cells
    if len(mesh.owner) != n_faces or sum(p.size for p in mesh.patches) != n_faces - n_int:
        raise ValueError(f"inconsistent mesh: {n_faces} faces, {len(mesh.owner)} owners, "
                         f"{n_int} internal faces, {sum(p.size for p in mesh.patches)} "
                         f"patch faces")
    note = f"nPoints:{len(mesh.points)}  nCells:{n_cells}  nFaces:{n_faces}  nInternalFaces:{n_int}"
    for name in _STALE:
        (poly / name).unlink(missing_ok=True)
    _write_atomic(poly / "points", _list_chunks(
        _header("vectorField", "points"), np.asarray(mesh.points, float),
        "(%.12g %.12g %.12g)\n"))
    _write_atomic(poly / "faces", _list_chunks(
        _header("faceList", "faces"), np.asarray(mesh.faces, np.int64), "4(%d %d %d %d)\n"))
    _write_atomic(poly / "owner", _list_chunks(
        _header("labelList", "owner", note), np.asarray(mesh.owner, np.int64)[:, None], "%d\n"))
    _write_atomic(poly / "neighbour", _list_chunks(
        _header("labelList", "neighbour", note), np.asarray(mesh.neighbour, np.int64)[:, None],
        "%d\n"))
    _write_atomic(poly / "boundary", iter([_boundary_text(mesh.patches)]))
