"""The 2D base mesh extruded across the gap into hexahedra.

:func:`extrude` puts ``n_layers`` layers of cells on each base quad, whose heights follow the
local gap: level ``k`` of node ``i`` lies on the surface z = f_k h(x, y) (disc at z = 0, ball
at z = h). Cell ``c`` is layer ``c % n_layers`` of quad ``c // n_layers`` (columns are
contiguous), point ``p`` is level ``p % (n_layers + 1)`` of 2D node ``p // (n_layers + 1)``.
Face centres, areas, cell centres and volumes are computed as OpenFOAM computes them.
"""

from __future__ import annotations

import numpy as np

from ehlfoam.mesh.domain import EDGE_PATCHES, PATCH_TYPES, BaseMesh, GapFunction, check_n_layers
from ehlfoam.mesh.layers import column_fractions, layer_fractions
from ehlfoam.mesh.polymesh import Patch, PolyMesh
from ehlfoam.mesh.topology import EdgeTopology, edge_key, edge_topology


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


def _internal_faces(quads: np.ndarray, topo: EdgeTopology,
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


def _boundary_faces(base: BaseMesh, topo: EdgeTopology,
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
        key = edge_key(e[:, 0], e[:, 1], n_pts)
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
    (docs/models/interface.md#the-mesh).
    """
    L = check_n_layers(n_layers)
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

    topo = edge_topology(quads, len(points2))
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
    region (docs/models/interface.md#ball-wall-steps)."""
    quads = np.asarray(base.quads, np.int64)
    column_z = mesh.points[:, 2].reshape(len(base.points), -1)   # extrude's node order
    h, wall = column_z[quads, -1], column_z[quads, 1]
    return (h.max(axis=1) - h.min(axis=1)) / wall.mean(axis=1)


def gap_mismatch(mesh: PolyMesh, gap: GapFunction) -> float:
    """Largest relative error of the mesh's gap height on the ball:
    max over ``ball`` faces of \\|z(face centre) - h(x, y)\\| / h(x, y) (the
    disc is z = 0, so the face centre's z is the column height there)."""
    fc = mesh.face_centres[mesh.patch_slice("ball")]
    h = np.asarray(gap(fc[:, 0], fc[:, 1]), dtype=float)
    return float(np.max(np.abs(fc[:, 2] - h) / h))
