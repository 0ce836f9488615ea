"""The levels of the cells across the gap, as fractions of the gap (0 on the disc, 1 on the
ball): uniform, graded toward both walls, or graded column by column for one wall-cell
height."""

from __future__ import annotations

import numpy as np


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
    (docs/models/interface.md#the-mesh; the 15 wall cells:
    docs/models/interface.md#the-contact-line-model-and-what-converges)."""
    h = np.asarray(h, float)
    s = np.arange(n_layers + 1) / n_layers
    if n_layers < 3:
        return np.broadcast_to(s, (len(h), n_layers + 1)).copy()
    beta_max = _stretching(n_layers, max_grading)
    table = np.linspace(0.0, beta_max, 400)
    wall = _tanh_levels(s, table)[:, 1]                       # falls as beta grows
    beta = np.interp(wall_cell / h, wall[::-1], table[::-1])  # clamps at both ends
    return _tanh_levels(s, beta)
