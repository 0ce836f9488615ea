"""The oil fraction on the mid-gap surface, resampled onto a regular grid.

The input is the oil volume fraction ``alpha`` (0 = air, 1 = oil) at the 2D cell centres
``(x, y)`` [m] of the thin-gap mesh's base mesh, plus the :class:`Geometry` of the domain:
``x`` is the rolling direction (oil comes from ``x < 0`` toward the contact at the origin),
the Hertzian contact has radius ``a`` and the mesh has a circular hole (the "island" wall) of
radius ``island_radius >= a`` at the origin. The island is the contact: neither oil nor gas.
The domain is the rectangle ``x_min <= x <= x_max`` and ``0 <= y <= y_max`` (``symmetric``,
a half domain mirrored to the full picture ``y -> -y``) or ``-y_max <= y <= y_max``; its
edges are open to the outer air.

:func:`raster` resamples the field onto a regular grid of the full domain (linear
interpolation on the Delaunay triangulation of the cell centres, nearest centre outside
their convex hull), island pixels flagged: the :class:`Raster` that the flow-pattern metrics
(:mod:`ehlfoam.metrics.pattern`) and the reports' pictures read. Everything is SI.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import ndimage
from scipy.spatial import QhullError

from ehlfoam.spec.sections import DomainBox

__all__ = ["Geometry", "Raster", "check_threshold", "raster"]

#: Default raster spacing as a fraction of the contact radius ``a``.
DEFAULT_CELL_OVER_A = 1.0 / 20.0
#: Largest raster accepted (pixels), to refuse a ``cell`` far too small.
MAX_PIXELS = 20_000_000
#: alpha values further than this outside [0, 1] are refused (not a fraction).
ALPHA_TOLERANCE = 0.5
#: Relative slack on the domain rectangle when checking the cell centres.
DOMAIN_SLACK = 0.01


@dataclass(frozen=True, kw_only=True)
class Geometry(DomainBox):
    """The domain around the contact (:class:`~ehlfoam.spec.sections.DomainBox`, metres) with
    the Hertzian contact radius ``a`` [m] the metrics are measured in; the island (the mesh's
    hole at the origin) is at least as large as the contact, ``island_radius >= a``. A half
    domain (``symmetric``) is mirrored for the analysis."""

    a: float

    def __post_init__(self) -> None:
        if (isinstance(self.a, bool) or not isinstance(self.a, (int, float, np.integer, np.floating))
                or not math.isfinite(self.a) or self.a <= 0):
            raise ValueError(f"a: must be a finite number > 0 in metres, got {self.a!r}")
        super().__post_init__()
        if self.island_radius < self.a:
            raise ValueError(f"island_radius: must be >= a ({self.a!r}), got {self.island_radius!r}")

    @classmethod
    def of(cls, box: DomainBox, a: float) -> "Geometry":
        """The metrics' geometry of a domain box and a contact radius [m]."""
        return cls(**box.fields(), a=a)


@dataclass(frozen=True, eq=False)
class Raster:
    """The field on a regular grid of the full (mirrored) domain.

    ``x`` (nx,) and ``y`` (ny,) are the pixel centres [m], ascending; the grid
    includes the domain edges and the row ``y = 0``. ``alpha`` (ny, nx) is
    clipped to [0, 1] and NaN on the island; ``island`` (ny, nx) flags the
    pixels with ``x^2 + y^2 <= island_radius^2``.
    """

    x: np.ndarray
    y: np.ndarray
    alpha: np.ndarray
    island: np.ndarray
    geom: Geometry

    @property
    def dx(self) -> float:
        """Pixel spacing along x [m]."""
        return float(self.x[1] - self.x[0])

    @property
    def dy(self) -> float:
        """Pixel spacing along y [m]."""
        return float(self.y[1] - self.y[0])

    @functools.cached_property
    def rim(self) -> np.ndarray:
        """Pixels outside the island that touch it (8-neighbourhood), (ny, nx)."""
        island, rim = self.island, np.zeros_like(self.island)
        rows, cols = np.flatnonzero(island.any(axis=1)), np.flatnonzero(island.any(axis=0))
        if rows.size:          # on the island's bounding box and a pixel round it
            box = (slice(max(rows[0] - 1, 0), rows[-1] + 2),
                   slice(max(cols[0] - 1, 0), cols[-1] + 2))
            near = island[box]
            rim[box] = ndimage.binary_dilation(near, structure=np.ones((3, 3), bool)) & ~near
        return rim

    @property
    def axis_row(self) -> int:
        """Index of the row ``y = 0``."""
        return int(np.argmin(np.abs(self.y)))

    def oil(self, threshold: float = 0.5) -> np.ndarray:
        """Oil pixels: ``alpha >= threshold`` outside the island."""
        return ~self.island & (self.alpha >= threshold)      # NaN: neither oil nor gas

    def gas(self, threshold: float = 0.5) -> np.ndarray:
        """Gas pixels: ``alpha < threshold`` outside the island."""
        return ~self.island & (self.alpha < threshold)


# --------------------------------------------------------------------------
# input checks


def _as_1d(name: str, values: Any) -> np.ndarray:
    arr = np.asarray(values, dtype=float)
    if arr.ndim != 1:
        raise ValueError(f"{name}: must be one-dimensional, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: contains non-finite values")
    return arr


def check_threshold(threshold: float) -> float:
    if not isinstance(threshold, (int, float, np.integer, np.floating)) or not 0.0 < threshold < 1.0:
        raise ValueError(f"threshold: must be in (0, 1), got {threshold!r}")
    return float(threshold)


def _check_inputs(x: Any, y: Any, alpha: Any, geom: Geometry) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Validate the cell-centre data; returns float arrays, alpha clipped to [0, 1]."""
    if not isinstance(geom, Geometry):
        raise ValueError(f"geom: must be a Geometry, got {type(geom).__name__}")
    x, y, alpha = _as_1d("x", x), _as_1d("y", y), _as_1d("alpha", alpha)
    if len(y) != len(x):
        raise ValueError(f"y: length {len(y)} differs from x's {len(x)}")
    if len(alpha) != len(x):
        raise ValueError(f"alpha: length {len(alpha)} differs from x's {len(x)}")
    if len(x) < 3:
        raise ValueError(f"x: at least 3 cell centres needed, got {len(x)}")
    if alpha.min() < -ALPHA_TOLERANCE or alpha.max() > 1.0 + ALPHA_TOLERANCE:
        raise ValueError(
            f"alpha: values in [{alpha.min():g}, {alpha.max():g}] are not a volume fraction")
    slack_x = DOMAIN_SLACK * (geom.x_max - geom.x_min)
    slack_y = DOMAIN_SLACK * geom.y_max
    if x.min() < geom.x_min - slack_x or x.max() > geom.x_max + slack_x:
        raise ValueError(
            f"x: centres span [{x.min():g}, {x.max():g}] m, outside the domain "
            f"[{geom.x_min:g}, {geom.x_max:g}] m (units?)")
    if y.min() < geom.y_min - slack_y or y.max() > geom.y_max + slack_y:
        raise ValueError(
            f"y: centres span [{y.min():g}, {y.max():g}] m, outside the domain "
            f"[{geom.y_min:g}, {geom.y_max:g}] m (symmetric={geom.symmetric}; units?)")
    return x, y, np.clip(alpha, 0.0, 1.0)


# --------------------------------------------------------------------------
# resampling


def _grid(geom: Geometry, cell: float) -> tuple[np.ndarray, np.ndarray]:
    """Pixel centres spanning the full domain, edges and ``y = 0`` included."""
    nx = max(2, int(round((geom.x_max - geom.x_min) / cell)) + 1)
    half = max(1, int(round(geom.y_max / cell)))
    if nx * (2 * half + 1) > MAX_PIXELS:
        raise ValueError(f"cell: {cell:g} m gives more than {MAX_PIXELS} pixels")
    xs = np.linspace(geom.x_min, geom.x_max, nx)
    ys = np.linspace(-geom.y_max, geom.y_max, 2 * half + 1)
    ys[half] = 0.0
    return xs, ys


@functools.lru_cache(maxsize=8)
def _resampler(points_b: bytes, n: int, xs_b: bytes, ys_b: bytes) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (k, 3) and weights (k, 3) that interpolate values at the points linearly onto
    the grid (Delaunay triangulation; pixels outside the hull take the nearest point). Cached:
    a case's cell centres never change, so the triangulation is built once per mesh."""
    from scipy.spatial import Delaunay, cKDTree

    points = np.frombuffer(points_b).reshape(n, 2)
    gx, gy = np.meshgrid(np.frombuffer(xs_b), np.frombuffer(ys_b))
    grid = np.column_stack([gx.ravel(), gy.ravel()])
    try:
        tri = Delaunay(points)
    except QhullError as exc:
        raise ValueError(f"x, y: the cell centres cannot be triangulated ({exc})") from None
    simplex = tri.find_simplex(grid)
    inside = simplex >= 0
    vertices = np.zeros((len(grid), 3), dtype=np.int64)
    weights = np.zeros((len(grid), 3))
    T = tri.transform[simplex[inside]]
    b = np.einsum("ijk,ik->ij", T[:, :2], grid[inside] - T[:, 2])
    vertices[inside] = tri.simplices[simplex[inside]]
    weights[inside] = np.column_stack([b, 1.0 - b.sum(axis=1)])
    if (~inside).any():
        _, nearest = cKDTree(points).query(grid[~inside])
        vertices[~inside, 0] = nearest
        weights[~inside, 0] = 1.0
    return vertices, weights


def raster(x: Any, y: Any, alpha: Any, geom: Geometry, cell: float | None = None) -> Raster:
    """Resample ``alpha`` at cell centres ``(x, y)`` onto a regular full-domain grid.

    ``cell`` is the pixel size [m] (default ``a/20``; the spacing is adjusted
    so the grid ends on the domain edges). A half domain is mirrored
    (``y -> -y``) before the interpolation. Linear interpolation on the
    Delaunay triangulation of the centres; pixels outside their convex hull
    (next to the domain edges) take the nearest centre's value. alpha is
    clipped to [0, 1]; island pixels are NaN.

    Raises ValueError (naming the parameter) on malformed input.
    """
    x, y, alpha = _check_inputs(x, y, alpha, geom)
    if cell is None:
        cell = DEFAULT_CELL_OVER_A * geom.a
    if not isinstance(cell, (int, float, np.integer, np.floating)) or not math.isfinite(cell) or cell <= 0:
        raise ValueError(f"cell: must be a positive finite length, got {cell!r}")
    if geom.symmetric:
        upper = y > 0.0
        x, y, alpha = (np.concatenate([x, x[upper]]), np.concatenate([y, -y[upper]]),
                       np.concatenate([alpha, alpha[upper]]))
    xs, ys = _grid(geom, float(cell))
    gx, gy = np.meshgrid(xs, ys)
    points = np.column_stack([x, y])
    vertices, weights = _resampler(points.tobytes(), len(points), xs.tobytes(), ys.tobytes())
    values = np.einsum("ij,ij->i", alpha[vertices], weights).reshape(gx.shape)
    island = gx**2 + gy**2 <= geom.island_radius**2
    values = np.clip(values, 0.0, 1.0)
    values[island] = np.nan
    return Raster(x=xs, y=ys, alpha=values, island=island, geom=geom)
