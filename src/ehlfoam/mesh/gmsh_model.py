"""The gmsh side of the base mesh: the domain's geometry (with the polar ring), gmsh's
options and size callback, and its mesh read back as arrays.

gmsh is imported inside the functions, so that importing the package does not load it.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np

from ehlfoam.mesh.domain import MeshParams, SizeFunction


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
def gmsh_model(name: str) -> Iterator[None]:
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


def polar_divisions(params: MeshParams, size: SizeFunction) -> tuple[int, int]:
    """Cells of the polar ring: (per quarter turn, across the ring).

    The ring's cells are near-squares in log-polar spacing: the angular step
    is the size at the island rim over the island radius, and the radii grow
    by the same factor, so the cell size grows in proportion to the radius
    from size(island rim) (what :func:`ehlfoam.mesh.sizing.size_function`
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
    log-polar spacing, ``divisions`` from :func:`polar_divisions`) and the rest meshed
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


def snap_polar(points: np.ndarray, params: MeshParams, divisions: tuple[int, int]) -> None:
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


def add_geometry(params: MeshParams,
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


def size_callback(size: SizeFunction, fallback: float, errors: list[str],
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


def extract_mesh(curves: dict[str, list[int]]) -> tuple[np.ndarray, np.ndarray,
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
