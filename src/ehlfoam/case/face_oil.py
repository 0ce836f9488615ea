"""The oil on a boundary face of the inlet: the exact share of its area inside the supply.

The supply is an oil layer on the disc (0 <= z <= d), one on the ball (H(y) - b <= z <=
H(y), above the disc's), on the track (w_in <= |y| <= w). A face of the inlet is a quad
between two columns of the extruded mesh; projected on the (y, z) plane it is the area
that the rolling speed carries through it. Clipping that quad by the layers' half-planes
gives its oil area exactly, however steeply the ball slopes across the face (by more than
the face's own height, next to the ball under thin wall cells) and however the columns lean.
"""

from __future__ import annotations

import numpy as np

#: A half-plane a y + b z <= c, as (a, b, c).
HalfPlane = tuple[float, float, float]


def clip(poly: np.ndarray, plane: HalfPlane) -> np.ndarray:
    """The part of polygon ``poly`` ((n, 2) points (y, z), in order) where a y + b z <= c
    (Sutherland-Hodgman against one half-plane); (0, 2) when nothing is left."""
    if len(poly) == 0:
        return poly
    a, b, c = plane
    side = poly @ np.array([a, b]) - c          # <= 0 inside
    out = []
    for i in range(len(poly)):
        j = (i + 1) % len(poly)
        if side[i] <= 0.0:
            out.append(poly[i])
        if (side[i] < 0.0 < side[j]) or (side[j] < 0.0 < side[i]):
            t = side[i] / (side[i] - side[j])
            out.append(poly[i] + t * (poly[j] - poly[i]))
    return np.array(out).reshape(-1, 2)


def area(poly: np.ndarray) -> float:
    """Area of polygon ``poly`` ((n, 2) points in order; shoelace)."""
    if len(poly) < 3:
        return 0.0
    y, z = poly[:, 0], poly[:, 1]
    return 0.5 * abs(float(np.dot(y, np.roll(z, -1)) - np.dot(z, np.roll(y, -1))))


def clipped_area(poly: np.ndarray, planes: list[HalfPlane]) -> float:
    """Area of the part of ``poly`` inside all of ``planes``."""
    for plane in planes:
        poly = clip(poly, plane)
    return area(poly)


def oil_fraction(poly: np.ndarray, ball: tuple[np.ndarray, np.ndarray], disc_layer: float,
                 ball_layer: float, track: tuple[float, float],
                 flooded: bool = False) -> float:
    """Oil share (0-1) of the area of a face projected on (y, z) as ``poly`` [m].

    ``ball`` is two points (y, z) of the ball above the face's two columns, the line between
    them the ball's edge H(y); ``track`` (w_in, w) the track's dry middle and outer half
    widths. The oil is the layers, d on the disc and b under the ball above it, or the whole
    height when ``flooded``, on w_in <= |y| <= w.
    """
    total = area(poly)
    if total == 0.0:
        return 0.0
    (y0, z0), (y1, z1) = ball
    slope = (z1 - z0) / (y1 - y0) if y1 != y0 else 0.0
    offset = slope * y0 - z0                    # the ball: slope y - z = offset
    if flooded:
        layers = [[]]
    else:
        layers = [[(0.0, 1.0, disc_layer), (-slope, 1.0, -offset)],          # z <= d, <= H
                  [(slope, -1.0, offset + ball_layer), (0.0, -1.0, -disc_layer)]]  # z >= H - b, d
    w_in, w = track
    oil = 0.0
    for planes in layers:
        oil += clipped_area(poly, planes + [(1.0, 0.0, w), (-1.0, 0.0, w)])
        if w_in > 0.0:
            oil -= clipped_area(poly, planes + [(1.0, 0.0, w_in), (-1.0, 0.0, w_in)])
    return min(max(oil / total, 0.0), 1.0)
