"""The edges of a 2D quad mesh and its numbering (reverse Cuthill-McKee).

Quads are counter-clockwise seen from +z; an internal edge has a quad on each side, a
boundary edge one, on its left.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import reverse_cuthill_mckee


@dataclass(frozen=True)
class EdgeTopology:
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


def edge_key(a: np.ndarray, b: np.ndarray, n_points: int) -> np.ndarray:
    return np.minimum(a, b).astype(np.int64) * n_points + np.maximum(a, b)


def edge_topology(quads: np.ndarray, n_points: int) -> EdgeTopology:
    """Pair up the half-edges of counter-clockwise quads."""
    m = len(quads)
    a = quads.ravel()
    b = np.roll(quads, -1, axis=1).ravel()
    q = np.repeat(np.arange(m, dtype=np.int64), 4)
    key = edge_key(a, b, n_points)
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
    return EdgeTopology(a=a[first], b=b[first], left=q[first], right=q[second],
                         bnd_a=a[lone], bnd_b=b[lone], bnd_quad=q[lone], bnd_key=key[lone])


def renumber(points: np.ndarray, quads: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Drop unused nodes, order quads by reverse Cuthill-McKee and nodes by
    first use in the reordered quads. Returns (points, quads, new id of
    every old node, -1 if unused)."""
    topo = edge_topology(quads, len(points))
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
