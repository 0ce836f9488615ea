"""In-plane cell sizes of a case's base mesh, from its spec.

The level's size at the island rim grows in proportion to the distance from the contact
centre up to its far size; a refinement of ``mesh.refine`` (a box, or a band along a line)
asks for its own size inside it, growing back at :data:`REFINE_GROWTH` outside. All sizes
are in metres out of :func:`size_function`, in units of the Hertzian radius a inside the
refinements (as the spec states them).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.spatial import cKDTree

from ehlfoam.mesh.domain import MeshParams
from ehlfoam.spec.case import CaseSpec
from ehlfoam.spec.mesh import RefineBand, RefineBox

#: How fast, in a of cell size per a of distance, the cells grow back from a refinement
#: (mesh.refine) to the level's size: 0.1 a cells reach 0.55 a within 1.8 a.
REFINE_GROWTH = 0.25

#: A size field: cell size at arrays of points (x, y).
Size = Callable[[np.ndarray, np.ndarray], np.ndarray]


def _box_size(box: RefineBox) -> Size:
    """Cell size (a) the box asks for at (x, y) (a): its size inside, growing with the
    distance outside (|y|: a half domain's box serves the full domain too)."""
    def size(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        dx = np.maximum(np.maximum(box.x_min - x, x - box.x_max), 0.0)
        ay = np.abs(y)
        dy = np.maximum(np.maximum(box.y_min - ay, ay - box.y_max), 0.0)
        return box.size + REFINE_GROWTH * np.hypot(dx, dy)

    return size


def _band_size(band: RefineBand) -> Size:
    """Cell size (a) the band asks for at (x, y) (a): its size within half_width of its line
    through (x, |y|), growing with the distance further out. The line is sampled every
    quarter of the smaller of size and half-width: the distance to the samples is the
    distance to the line within an eighth of that."""
    p = np.asarray(band.points, float)
    step = 0.25 * min(band.size, band.half_width)
    seg = np.diff(p, axis=0)
    n = np.maximum(np.ceil(np.hypot(seg[:, 0], seg[:, 1]) / step).astype(int), 1)
    samples = [p[i] + np.outer(np.arange(k) / k, seg[i]) for i, k in enumerate(n)]
    tree = cKDTree(np.vstack(samples + [p[-1:]]))

    def size(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        x, y = np.broadcast_arrays(np.asarray(x, float), np.abs(np.asarray(y, float)))
        dist, _ = tree.query(np.stack([x.ravel(), y.ravel()], axis=1))
        beyond = np.maximum(dist.reshape(x.shape) - band.half_width, 0.0)
        return band.size + REFINE_GROWTH * beyond

    return size


def mesh_params(spec: CaseSpec) -> MeshParams:
    """The mesher's parameters of ``spec``'s case [m]: its domain, layers and polar ring."""
    a = spec.a
    return MeshParams(**spec.domain.box(a).fields(), n_layers=spec.mesh.level()["n_layers"],
                      polar_radius=None if spec.polar_radius is None
                      else spec.polar_radius * a)


def refinement_size(refinement: RefineBox | RefineBand) -> Size:
    """The size field (a, at points in a) of one ``mesh.refine`` entry."""
    if isinstance(refinement, RefineBand):
        return _band_size(refinement)
    return _box_size(refinement)


def size_function(spec: CaseSpec) -> Size:
    """In-plane cell size [m] at (x, y) [m]: size_rim at the island rim, growing in proportion
    to the distance from the contact centre (the gap grows like r^2, the meniscus sits a few
    a out), capped at size_far; smaller where a refinement (mesh.refine) asks for it."""
    level, a, ri = spec.mesh.level(), spec.a, spec.domain.island_radius * spec.a
    rim, far = level["size_rim"] * a, level["size_far"] * a
    refinements = [refinement_size(r) for r in spec.mesh.refine]

    def size(x, y):
        x, y = np.asarray(x, float), np.asarray(y, float)
        out = np.clip(rim * np.hypot(x, y) / ri, rim, far)
        for refined in refinements:
            out = np.minimum(out, refined(x / a, y / a) * a)
        return out

    return size


def smallest_cell_size(spec: CaseSpec) -> float:
    """The smallest in-plane cell [m] :func:`size_function` asks for: the level's size at the
    island rim, or a refinement's (mesh.refine) where it is finer. The capillary time step is
    set for it, so that a band finer than the rim runs at its own limit."""
    sizes = [spec.mesh.level()["size_rim"]] + [r.size for r in spec.mesh.refine]
    return min(sizes) * spec.a
