"""Flow-pattern metrics from the oil volume fraction on the mid-gap surface.

The input is the oil volume fraction ``alpha`` (0 = air, 1 = oil) at the 2D
cell centres ``(x, y)`` [m] of the thin-gap mesh's base mesh, plus the
:class:`Geometry` of the domain: ``x`` is the rolling direction (oil comes
from ``x < 0`` toward the contact at the origin), the Hertzian contact has
radius ``a`` and the mesh has a circular hole (the "island" wall) of radius
``island_radius >= a`` at the origin. The island is the contact: neither oil
nor gas. The domain is the rectangle ``x_min <= x <= x_max`` and
``0 <= y <= y_max`` (``symmetric``, a half domain mirrored to the full picture
``y -> -y``) or ``-y_max <= y <= y_max``; its edges are open to the outer air.

Two steps:

:func:`raster` (:mod:`ehlfoam.metrics.raster`)
    resamples the field onto a regular grid of the full domain (linear
    interpolation on the Delaunay triangulation of the cell centres, nearest
    centre outside their convex hull), island pixels flagged.
:func:`flow_pattern` (or :func:`flow_pattern_from_raster`)
    classifies the topology of oil (``alpha >= threshold``) and gas and
    measures the meniscus. Gas regions are labelled with 4-connectivity,
    oil regions with 8-connectivity (the usual complementary pair, so that a
    gas region that is not connected to the edge is truly enclosed by oil).
    "Outer air" is gas connected to the domain edge, the "flooded region"
    the oil connected to the island rim (the pixels next to the island).
    State I: no outer air touches the island rim (the flooded region closes
    around the contact; gas at the rim, if any, is an enclosed bubble).
    State II: outer air reaches the rim (an open wake, or a starved inlet).

Inside, everything is SI; the lengths returned are ratios to ``a``, under the keys of the
metrics record (:class:`ehlfoam.metrics.record.MetricsRecord`).
:func:`meniscus_contours` gives the ``alpha = threshold`` lines for plots.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit
from scipy import ndimage

from ehlfoam.metrics.raster import Geometry, Raster, check_threshold, raster

#: Geometry, Raster and raster are re-exported: a caller of the metrics needs them.
__all__ = [
    "Geometry",
    "Raster",
    "advancing_front",
    "bubble_mask",
    "flooded_widths_at",
    "flow_pattern",
    "flow_pattern_from_raster",
    "meniscus_contours",
    "pattern_and_bubble",
    "raster",
]

_FOUR = ndimage.generate_binary_structure(2, 1)
_EIGHT = ndimage.generate_binary_structure(2, 2)


# --------------------------------------------------------------------------
# topology


def _edge_mask(shape: tuple[int, int]) -> np.ndarray:
    edge = np.zeros(shape, dtype=bool)
    edge[0, :] = edge[-1, :] = edge[:, 0] = edge[:, -1] = True
    return edge


@njit(cache=True)
def _touching(labels: np.ndarray, count: int, where: np.ndarray) -> np.ndarray:
    """The pixels of the labelled regions (``labels`` 1..``count``, 0 outside them) that
    have a pixel in ``where``."""
    ny, nx = labels.shape
    hit = np.zeros(count + 1, np.bool_)
    for i in range(ny):
        for j in range(nx):
            if where[i, j]:
                hit[labels[i, j]] = True
    hit[0] = False
    out = np.empty((ny, nx), np.bool_)
    for i in range(ny):
        for j in range(nx):
            out[i, j] = hit[labels[i, j]]
    return out


def _outer_air(labels: np.ndarray, count: int) -> tuple[np.ndarray, int]:
    """(gas connected to the domain edge, number of enclosed gas regions), from the gas's
    regions (4-connected, ``labels`` 1..``count``)."""
    edge = _edge_mask(labels.shape)
    edge_regions = np.count_nonzero(np.unique(labels[edge]))
    return _touching(labels, count, edge), int(count - edge_regions)


def _flooded(oil: np.ndarray, rim: np.ndarray) -> np.ndarray:
    """Oil pixels connected (8-neighbourhood) to the island rim."""
    labels, count = ndimage.label(oil, structure=_EIGHT)
    return _touching(labels, count, rim)


# --------------------------------------------------------------------------
# measurements


def _crossing(x0: float, a0: float, x1: float, a1: float, threshold: float) -> float:
    """Where the linear interpolant between (x0, a0) and (x1, a1) crosses threshold."""
    if a1 == a0:
        return float(0.5 * (x0 + x1))
    return float(x0 + (x1 - x0) * (threshold - a0) / (a1 - a0))


@njit(cache=True)
def _far_extent(region: np.ndarray, alpha: np.ndarray, gas: np.ndarray,
                coords: np.ndarray, threshold: float, axis: int) -> float:
    """Largest coordinate of ``region`` (not empty) along ``axis`` (0: rows, 1: columns;
    ascending ``coords``), read row by row whichever the axis (no transposed walk).

    A region pixel whose next pixel along the axis is gas extends to the interpolated
    ``alpha = threshold`` crossing between the two (the fraction of the step clipped to
    0-1; 0 where it is not a number).
    """
    best = -np.inf
    ny, nx = region.shape
    di, dj = (1, 0) if axis == 0 else (0, 1)
    for i in range(ny):
        for j in range(nx):
            if not region[i, j]:
                continue
            k = i if axis == 0 else j
            reach = coords[k]
            ii, jj = i + di, j + dj
            if ii < ny and jj < nx and gas[ii, jj]:
                num, den = alpha[i, j] - threshold, alpha[i, j] - alpha[ii, jj]
                if den != 0.0:
                    frac = num / den
                else:
                    frac = 1.0 if num > 0.0 else 0.0
                frac = 0.0 if not frac >= 0.0 else min(frac, 1.0)
                reach = coords[k] + frac * (coords[k + 1] - coords[k])
            best = max(best, reach)
    return best


def _extent(region: np.ndarray, alpha: np.ndarray, gas: np.ndarray,
            coords: np.ndarray, threshold: float, axis: int = 1) -> tuple[float, float]:
    """(min, max) coordinate of ``region`` along ``axis`` (``coords`` its pixels'), sub-pixel."""
    coords = np.asarray(coords, dtype=float)
    hi = _far_extent(region, alpha, gas, coords, threshold, axis)
    flip = (slice(None, None, -1), slice(None)) if axis == 0 else \
        (slice(None), slice(None, None, -1))
    lo = -_far_extent(region[flip], alpha[flip], gas[flip], -coords[::-1], threshold, axis)
    return lo, hi


@njit(cache=True)
def _walk_upstream(x: np.ndarray, island: np.ndarray, region: np.ndarray) -> tuple[int, int]:
    """On one row (pixel centres ``x`` ascending, its ``island`` and ``region`` pixels): the
    last pixel upstream of the island (x < 0, not island) and, walking upstream from it
    through ``region``, the first pixel outside it; -1 for either where there is none (no
    walk when the first is not in ``region``)."""
    start = -1
    for j in range(x.size):
        if x[j] < 0.0 and not island[j]:
            start = j
    if start < 0 or not region[start]:
        return start, -1
    for j in range(start, -1, -1):
        if not region[j]:
            return start, j
    return start, -1


def _upstream_meniscus(r: Raster, row: int, region: np.ndarray, threshold: float) -> tuple[float | None, bool]:
    """Upstream meniscus x [m] on one raster row, and whether it is at the rim.

    Walks upstream from the first pixel upstream of the island through the
    ``region`` pixels to the first pixel outside it, and interpolates the
    ``alpha = threshold`` crossing. If the starting pixel is not in
    ``region`` the meniscus is at (or inside) the island rim: returns the rim
    position ``-sqrt(R^2 - y^2)`` (0 beyond the island) and True. Returns
    (None, False) when ``region`` reaches the inlet edge.
    """
    start, k = _walk_upstream(r.x, r.island[row], region[row])
    if start < 0:
        return None, False
    if not region[row, start]:
        rim = -math.sqrt(max(r.geom.island_radius**2 - float(r.y[row]) ** 2, 0.0))
        return rim, True
    if k < 0:
        return None, False
    alpha = r.alpha[row]
    return _crossing(r.x[k], alpha[k], r.x[k + 1], alpha[k + 1], threshold), False


def _meniscus_shape(r: Raster, region: np.ndarray, threshold: float) -> tuple[str | None, float | None]:
    """("convex" | "concave" | None, c2) from a fit x_m/a = c0 + c2 (y/a)^2 over |y| <= R, the
    meniscus on each row bounding ``region``."""
    a = r.geom.a
    ys, xm, any_free = [], [], False
    for row in np.flatnonzero(np.abs(r.y) <= r.geom.island_radius):
        pos, at_rim = _upstream_meniscus(r, int(row), region, threshold)
        if pos is None:
            continue
        ys.append(float(r.y[row]) / a)
        xm.append(pos / a)
        any_free |= not at_rim
    if not any_free or len(set(np.round(np.square(ys), 12))) < 2 or len(ys) < 3:
        return None, None
    design = np.column_stack([np.ones(len(ys)), np.square(ys)])
    (_, c2), *_ = np.linalg.lstsq(design, np.asarray(xm), rcond=None)
    # A bulge below a tenth of a pixel over the fitted span is a flat meniscus.
    bulge = abs(c2) * max(np.square(ys)) * a
    if bulge < 0.1 * r.dx:
        return None, float(c2)
    return ("convex" if c2 > 0 else "concave"), float(c2)


def _wake_gas_end(r: Raster, gas: np.ndarray, oil: np.ndarray, threshold: float) -> float | None:
    """x [m] where the gas run downstream of the island ends on y = 0, None if oil follows the rim."""
    row = r.axis_row
    downstream = np.flatnonzero((r.x > 0.0) & ~r.island[row])
    start = int(downstream[0])
    if not gas[row, start]:
        return None
    after = np.flatnonzero(oil[row, start:])
    if after.size == 0:
        return float(r.x[-1])
    k = start + int(after[0])
    alpha = r.alpha[row]
    return _crossing(r.x[k - 1], alpha[k - 1], r.x[k], alpha[k], threshold)


def bubble_mask(r: Raster, threshold: float = 0.5) -> np.ndarray:
    """The cavitation bubble: gas pixels (4-connected regions) that touch the island rim
    downstream of the contact (rim pixels at x > 0). Empty when oil follows the rim."""
    return _bubble_mask(r, *ndimage.label(r.gas(threshold), structure=_FOUR))


def _bubble_mask(r: Raster, labels: np.ndarray, count: int) -> np.ndarray:
    """:func:`bubble_mask` from the gas's regions (4-connected, ``labels`` 1..``count``)."""
    return _touching(labels, count, r.rim & (np.broadcast_to(r.x, r.island.shape) > 0.0))


def _bubble(r: Raster, outer: np.ndarray, bubble: np.ndarray, oil: np.ndarray,
            threshold: float) -> dict[str, Any]:
    """Bubble metrics (see :func:`flow_pattern`) of the ``bubble`` pixels (``oil``: the oil
    pixels; the extents read alpha only on the bubble and the oil, never the island's NaN)."""
    a = r.geom.a
    if not bubble.any():
        return {"bubble_length_over_a": 0.0, "bubble_width_over_a": 0.0,
                "bubble_enclosed": False}
    alpha = r.alpha
    _, tip = _extent(bubble, alpha, oil, r.x, threshold)
    y_lo, y_hi = _extent(bubble, alpha, oil, r.y, threshold, axis=0)
    return {"bubble_length_over_a": max(0.0, float((tip - a) / a)),
            "bubble_width_over_a": float((y_hi - y_lo) / a),
            "bubble_enclosed": not bool((bubble & outer).any())}


# --------------------------------------------------------------------------
# public API


def advancing_front(r: Raster, track_half_width: float, threshold: float = 0.5) -> np.ndarray:
    """Points (x, y) [m], shape (n, 2), of the flooded region's edge that the walls, rolling
    along +x, run into from dry ground: flooded pixels whose upstream neighbour is neither
    flooded nor island, off the supply track (|y| > ``track_half_width`` [m]). There the oil
    meets the walls in contact lines advancing onto dry walls
    (docs/models/interface.md#the-contact-line-model-and-what-converges). Empty without a
    flooded region."""
    if not isinstance(r, Raster):
        raise ValueError(f"r: must be a Raster, got {type(r).__name__}")
    if not (math.isfinite(track_half_width) and track_half_width >= 0):
        raise ValueError(f"track_half_width: must be a finite length >= 0 m, got "
                         f"{track_half_width!r}")
    flooded = _flooded(r.oil(check_threshold(threshold)), r.rim)
    behind = np.zeros_like(flooded)                # the pixel upstream is flooded or island
    behind[:, 1:] = flooded[:, :-1] | r.island[:, :-1]
    behind[:, 0] = True                            # the domain's upstream edge: not known
    xx, yy = np.meshgrid(r.x, r.y)
    front = flooded & ~behind & (np.abs(yy) > track_half_width)
    return np.stack([xx[front], yy[front]], axis=1)


def flow_pattern_from_raster(r: Raster, threshold: float = 0.5) -> dict[str, Any]:
    """Flow-pattern metrics of a :class:`Raster`; see :func:`flow_pattern`."""
    return pattern_and_bubble(r, threshold)[0]


def pattern_and_bubble(r: Raster, threshold: float = 0.5) -> tuple[dict[str, Any], np.ndarray]:
    """:func:`flow_pattern_from_raster`'s metrics and the bubble's pixels
    (:func:`bubble_mask`), read together: a caller that needs both labels the gas once."""
    threshold = check_threshold(threshold)
    if not isinstance(r, Raster):
        raise ValueError(f"r: must be a Raster, got {type(r).__name__}")
    a = r.geom.a
    oil, gas = r.oil(threshold), r.gas(threshold)
    rim = r.rim
    gas_regions = ndimage.label(gas, structure=_FOUR)
    outer, enclosed = _outer_air(*gas_regions)
    bubble = _bubble_mask(r, *gas_regions)
    flooded = _flooded(oil, rim)
    outer_rim = outer & rim
    xx = np.broadcast_to(r.x, r.island.shape)
    inlet_starved = bool((outer_rim & (xx < 0.0)).any())
    wake_open = bool((outer_rim & (xx > 0.0)).any())
    state = "II" if outer_rim.any() else "I"

    # the meniscus bounds the outer air: the walk upstream passes over the air bubbles that
    # the oil encloses (carried in by the supply drops that merge into the inlet)
    held = ~outer & ~r.island
    inlet_x, inlet_at_rim = _upstream_meniscus(r, r.axis_row, held, threshold)
    inlet = None if inlet_x is None else max(0.0, float((-a - inlet_x) / a))
    shape, c2 = _meniscus_shape(r, held, threshold)

    length = width = x_lo = x_hi = clearance = nearest = None
    if flooded.any():
        alpha = r.alpha             # read on the region and the gas only: no NaN
        x_lo, x_hi = _extent(flooded, alpha, gas, r.x, threshold)
        y_lo, y_hi = _extent(flooded, alpha, gas, r.y, threshold, axis=0)
        length, width = float((x_hi - x_lo) / a), float((y_hi - y_lo) / a)
        # the flooded region's distance to each open boundary (the raster is the full,
        # mirrored domain: the side edges are at -y_max and y_max)
        gaps = {"upstream": x_lo - r.geom.x_min, "outlet": r.geom.x_max - x_hi,
                "side": r.geom.y_max - max(y_hi, -y_lo)}
        least = min(gaps.values())
        # ties within a pixel named in a fixed order, so that sampling cannot flip the name
        nearest = next(k for k in ("outlet", "side", "upstream") if gaps[k] <= least + r.dx)
        clearance = max(0.0, float(least / a))
        x_lo, x_hi = x_lo / a, x_hi / a

    wake_end = _wake_gas_end(r, gas, oil, threshold)
    wake = 0.0 if wake_end is None else max(0.0, (wake_end - a) / a)
    free = ~r.island
    return ({
        "state": state,
        "inlet_meniscus_distance_over_a": inlet,
        "inlet_meniscus_at_rim": bool(inlet_at_rim),
        "inlet_meniscus_shape": shape,
        "inlet_meniscus_c2": c2,
        "flooded_length_over_a": length,
        "flooded_width_over_a": width,
        "flooded_x_min_over_a": x_lo,
        "flooded_x_max_over_a": x_hi,
        "flooded_clearance_over_a": clearance,
        "flooded_nearest_boundary": nearest,
        "wake_gas_length_over_a": float(wake),
        "wake_open": wake_open,
        "inlet_starved": inlet_starved,
        "enclosed_bubbles": enclosed,
        **_bubble(r, outer, bubble, oil, threshold),
        "oil_area_fraction": float(oil.sum() / free.sum()),
        "mean_alpha": _mean(r.alpha[free]),
    }, bubble)


def _mean(values: np.ndarray) -> float:
    """The mean of ``values`` leaving NaN out: :func:`numpy.nanmean`'s, bitwise, at a fifth of
    its cost where there is no NaN (the pixels off the island of a raster)."""
    mean = float(values.mean())
    return float(np.nanmean(values)) if math.isnan(mean) else mean


def flow_pattern(x: Any, y: Any, alpha: Any, geom: Geometry, threshold: float = 0.5,
                 cell: float | None = None) -> dict[str, Any]:
    """Flow-pattern metrics from alpha at the mid-gap cell centres.

    ``x``, ``y`` [m], ``alpha`` (clipped to [0, 1]) are equal-length 1D
    arrays; ``cell`` is the raster size (default ``a/20``, see :func:`raster`).
    Lengths are ratios to ``a``; undefined values are None (never NaN).

    Keys:

    ``state``
        "I" (no outer air touches the island rim) or "II" (it does).
    ``inlet_meniscus_distance_over_a``
        on ``y = 0``, from ``x = -a`` upstream to the first crossing of
        ``alpha = threshold`` into the outer air (gas connected to the domain
        edge) upstream of the island rim (>= 0): air bubbles the oil encloses
        are passed over. When outer air touches the rim on the inlet side the
        meniscus is at or inside the rim: ``(island_radius - a)/a`` (and
        ``inlet_meniscus_at_rim``). None when oil reaches the inlet edge
        ``x_min``.
    ``inlet_meniscus_at_rim``
        the axis meniscus is at (or hidden inside) the island rim.
    ``inlet_meniscus_shape``, ``inlet_meniscus_c2``
        fit ``x_m/a = c0 + c2 (y/a)^2`` of the upstream meniscus (as above)
        over the rows ``|y| <= island_radius`` (rows where outer air touches
        the rim count at the rim): "convex" (``c2 > 0``, bulging
        upstream) or "concave" (``c2 < 0``, the butterfly of a starved
        inlet); None when undefined (no meniscus off the rim, oil to the
        inlet, or flat within a tenth of a pixel).
    ``flooded_length_over_a``, ``flooded_width_over_a``,
    ``flooded_x_min_over_a``, ``flooded_x_max_over_a``
        extents of the flooded region (oil connected to the island rim) in
        the full picture, to the interpolated crossings; None without one.
    ``flooded_clearance_over_a``, ``flooded_nearest_boundary``
        the flooded region's distance to the nearest open boundary (>= 0) and
        which: "outlet" (``x_max``), "side" (``|y| = y_max``) or "upstream"
        (``x_min``), the first of these within a pixel of the least; None
        without a flooded region. Near 0 the region is cut short by the domain.
    ``wake_gas_length_over_a``
        if gas follows the island rim downstream on ``y = 0``, from
        ``x = a`` to the end of that gas run (next gas->oil crossing or
        ``x_max``); 0.0 if oil follows the rim.
    ``wake_open``, ``inlet_starved``
        outer air touches the rim at ``x > 0`` / ``x < 0``.
    ``enclosed_bubbles``
        number of gas regions (4-connected) not connected to the edge.
    ``bubble_length_over_a``, ``bubble_width_over_a``, ``bubble_enclosed``
        the cavitation bubble (:func:`bubble_mask`: the gas touching the island rim
        downstream): from the downstream point of the Hertzian circle (``x = a``) to the
        bubble's tip (its largest x, to the interpolated crossing), its full width, and
        whether oil encloses it (False once it joins the outer air: an open wake). 0.0,
        0.0 and False without one.
    ``oil_area_fraction``, ``mean_alpha``
        area fraction with ``alpha >= threshold`` and mean alpha, island
        excluded.
    """
    threshold = check_threshold(threshold)
    return flow_pattern_from_raster(raster(x, y, alpha, geom, cell), threshold)


def meniscus_contours(r: Raster, threshold: float = 0.5) -> list[np.ndarray]:
    """The ``alpha = threshold`` lines of a raster as (k, 2) arrays of (x, y) [m].

    The island is masked out: lines stop at it rather than cross it.
    """
    import contourpy

    threshold = check_threshold(threshold)
    if not isinstance(r, Raster):
        raise ValueError(f"r: must be a Raster, got {type(r).__name__}")
    z = np.ma.masked_array(np.nan_to_num(r.alpha, nan=0.0), mask=r.island)
    gen = contourpy.contour_generator(x=r.x, y=r.y, z=z, line_type=contourpy.LineType.Separate)
    return [np.asarray(line, dtype=float) for line in gen.lines(threshold) if len(line) >= 2]


def flooded_widths_at(r: Raster, x_stations: Any, threshold: float = 0.5) -> list[float | None]:
    """The flooded region's width [m] across y at each x of ``x_stations`` [m]: on the
    raster column nearest each x, from its lowest to its highest pixel of the region, each
    end at the interpolated ``alpha = threshold`` crossing (as ``flooded_width_over_a``,
    which is their largest over all x); None where the region does not reach that column.
    The outline behind the widest point (the rear shoulders) moves with the mesh where the
    widest point does not
    (docs/models/interface.md#the-contact-line-model-and-what-converges)."""
    threshold = check_threshold(threshold)
    if not isinstance(r, Raster):
        raise ValueError(f"r: must be a Raster, got {type(r).__name__}")
    oil, gas = r.oil(threshold), r.gas(threshold)
    flooded = _flooded(oil, r.rim)
    alpha = r.alpha             # read on the region and the gas only: no NaN
    widths: list[float | None] = []
    for x in np.atleast_1d(np.asarray(x_stations, float)):
        j = int(np.argmin(np.abs(r.x - x)))
        column = flooded[:, j][None, :]
        if not column.any():
            widths.append(None)
            continue
        lo, hi = _extent(column, alpha[:, j][None, :], gas[:, j][None, :], r.y, threshold)
        widths.append(float(hi - lo))
    return widths
