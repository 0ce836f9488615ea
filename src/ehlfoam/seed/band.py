"""Bands of finer cells along a run's meniscus, for the next run's mesh (``ehlfoam band``).

A meniscus in the thin gap holds its capillary suction only in in-plane cells within about 15
wall cells where dry walls run into it, and lays its films right only in cells of 0.05-0.1 a at
the rear (docs/models/interface.md#the-contact-line-model-and-what-converges). Hand-placed
boxes (``mesh.refine``) covered it piece by piece; this module reads the meniscus itself off a
written time, the ``alpha = 0.5`` lines of the mid-gap oil fraction, and turns each line into a
:class:`~ehlfoam.spec.mesh.RefineBand` of a chosen size and half-width in the half domain
y >= 0. A run continued from that write (``--start-from``) on a mesh with the bands then has
its whole meniscus in the band's cells, as long as the meniscus stays within the band.

    ehlfoam band CASE --size 0.06 --half-width 1.0 [--time last|start|T] [--spacing 0.25]
        [--min-length 1.0]

prints the bands as TOML inline tables, ready for ``--set 'mesh.refine=[...]'`` or a spec's
``[mesh] refine = [...]``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ehlfoam.spec.mesh import RefineBand, SideBox
from ehlfoam.case.geometry import load_geometry

from ehlfoam.run import fields as case_fields
from ehlfoam.metrics import pattern as metrics


def meniscus_lines(case: str | Path, at: str = "last",
                   threshold: float = 0.5) -> tuple[float, list[np.ndarray]]:
    """(time [s], lines): the ``alpha = threshold`` lines of the mid-gap oil fraction at the
    write nearest ``at`` transits ("last": the last write; "start": the case's initial
    field, ``0.orig/``, e.g. the oil of the thin-film state it starts from), each a (k, 2)
    array of (x, y) in units of a, cut to y >= 0 (the half domain: a full domain's lines
    below y = 0 are the mirror of those above, within its asymmetry). Raises ValueError
    without such a write."""
    geom = load_geometry(case)
    st = case_fields.Structure.load(case)
    if at == "start":
        time, folder = 0.0, Path(case) / "0.orig"
    else:
        time, folder = case_fields.write_near(case, at, geom.transit_time)
    alpha = case_fields.mid_gap_alpha(folder, st, geom)
    r = case_fields.column_raster(alpha, st, geom)
    lines = []
    for line in metrics.meniscus_contours(r, threshold):
        xy = line / geom.a
        upper = xy[:, 1] >= 0.0
        # split where a line crosses y = 0: runs of consecutive points above it
        edges = np.flatnonzero(np.diff(np.concatenate([[0], upper.astype(int), [0]])))
        lines += [xy[i:j] for i, j in zip(edges[::2], edges[1::2]) if j - i >= 2]
    return time, lines


def resample(line: np.ndarray, spacing: float) -> np.ndarray:
    """A polyline's points every ``spacing`` (same units) along it, both ends kept."""
    if spacing <= 0.0:
        raise ValueError(f"spacing = {spacing!r} must be positive")
    seg = np.hypot(*np.diff(line, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    n = max(int(np.ceil(s[-1] / spacing)), 1)
    t = np.linspace(0.0, s[-1], n + 1)
    return np.column_stack([np.interp(t, s, line[:, 0]), np.interp(t, s, line[:, 1])])


def line_length(line: np.ndarray) -> float:
    return float(np.hypot(*np.diff(line, axis=0).T).sum())


def meniscus_bands(lines: list[np.ndarray], size: float, half_width: float,
                   spacing: float | None = None,
                   min_length: float | None = None) -> list[RefineBand]:
    """One band per line (units of a) of cells of ``size`` within ``half_width`` of it, its
    points every ``spacing`` (default half_width / 4, so that the band's edge follows the
    line within a thirtieth of its width); lines shorter than ``min_length`` (default
    half_width: the small enclosed pockets a band around the rest mostly covers) are left
    out."""
    spacing = 0.25 * half_width if spacing is None else spacing
    min_length = half_width if min_length is None else min_length
    bands = []
    for line in lines:
        if line_length(line) < min_length:
            continue
        pts = np.round(resample(line, spacing), 3)
        pts[:, 1] = np.maximum(pts[:, 1], 0.0)
        bands.append(RefineBand(points=tuple(map(tuple, pts.tolist())),
                                half_width=half_width, size=size))
    return bands


def side_bands(bands: list[RefineBand], sides: SideBox) -> list[RefineBand]:
    """A band of half the size and half the half-width (or the sizes ``sides`` gives) along
    each run of consecutive points of ``bands`` that lies in ``sides`` (the region's sides,
    where the meniscus sets the width; :class:`~ehlfoam.spec.mesh.SideBox`). Runs of a
    single point are left out."""
    out = []
    for band in bands:
        pts = np.asarray(band.points, float)
        held = sides.holds(pts).astype(int)
        edges = np.flatnonzero(np.diff(np.concatenate([[0], held, [0]])))
        for i, j in zip(edges[::2], edges[1::2]):
            if j - i >= 2:
                out.append(RefineBand(points=tuple(map(tuple, pts[i:j].tolist())),
                                      half_width=sides.half_width or 0.5 * band.half_width,
                                      size=sides.size or 0.5 * band.size))
    return out


def bands_toml(bands: list[RefineBand]) -> str:
    """The bands as a TOML array of inline tables (``mesh.refine = [...]``)."""
    def one(b: RefineBand) -> str:
        pts = ",".join(f"[{x:g},{y:g}]" for x, y in b.points)
        return f"{{half_width={b.half_width:g},size={b.size:g},points=[{pts}]}}"
    return "[" + ",\n".join(one(b) for b in bands) + "]"

