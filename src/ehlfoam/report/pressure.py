"""Pressure pictures: the CFD's mid-gap pressure around the contact (sub-ambient region
highlighted) and the EHL precalc's pressure and film inside it.

The CFD pressure is gauge (0 = ambient at the open boundaries); it spans tens of kPa next to
the island and a few hundred Pa of capillary pressure elsewhere, so the colour scale is
symmetric-logarithmic. Sub-ambient is p below minus the noise level (1 % of the largest
|p|, at least 50 Pa): hatched and outlined.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ehlfoam.report import style
from ehlfoam.report.fields import Fields

#: Sub-ambient threshold: this fraction of the largest |p| (and at least NOISE_PA).
NOISE_FRACTION = 0.01
NOISE_PA = 50.0


@dataclass
class PressureView:
    """What :func:`draw_pressure` drew: per base cell (mirrored) x, y [m] and gauge p [Pa];
    the sub-ambient threshold [Pa]; the lowest and highest mid-gap pressure [Pa]."""

    path: Path
    x: np.ndarray
    y: np.ndarray
    p: np.ndarray
    threshold: float
    p_min: float
    p_max: float


def _mirrored(fields: Fields, values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    s = fields.structure
    x, y = s.base_x, s.base_y
    if fields.geom.symmetric:
        up = y > 0.0
        return (np.concatenate([x, x[up]]), np.concatenate([y, -y[up]]),
                np.concatenate([values, values[up]]))
    return x, y, values


def _triangulation(x: np.ndarray, y: np.ndarray, island_radius: float):
    """Delaunay triangles of the base-cell centres [mm], those inside the island masked."""
    import matplotlib.tri as mtri

    tri = mtri.Triangulation(x * 1e3, y * 1e3)
    cx = x[tri.triangles].mean(axis=1)
    cy = y[tri.triangles].mean(axis=1)
    tri.set_mask(np.hypot(cx, cy) < island_radius)
    return tri


def symlog_ticks(linthresh: float, top: float) -> list[float]:
    """Ticks 0, +-10^k for 10^k in [linthresh, top] (a symmetric-log axis without the
    crowded labels around zero)."""
    import math

    lo = math.ceil(math.log10(linthresh))
    hi = math.floor(math.log10(max(top, linthresh)))
    decades = [10.0**k for k in range(lo, hi + 1)] or [top]
    return [-d for d in reversed(decades)] + [0.0] + decades


def draw_pressure(fields: Fields, out: Path, *, title: str, width_in: float = 9.0,
                  dpi: int = style.DPI) -> PressureView | None:
    """Top view of the mid-gap gauge pressure with the sub-ambient region hatched, and the
    pressure along y = 0 below it. None when the case wrote no pressure."""
    from matplotlib.colors import SymLogNorm
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle, Patch

    if fields.pressure is None:
        return None
    g = fields.geom
    x, y, p = _mirrored(fields, fields.mid_gap(fields.pressure))
    _, _, alpha = _mirrored(fields, fields.mid_alpha)
    tri = _triangulation(x, y, g.island_radius)
    pk = p / 1e3
    big = float(np.abs(pk).max()) or 1.0
    thr = max(NOISE_FRACTION * big * 1e3, NOISE_PA)
    x0, x1 = g.x_min * 1e3, g.x_max * 1e3
    y0, y1 = (-g.y_max * 1e3, g.y_max * 1e3)
    left, right, top, mid, line_h, bottom = 0.8, 1.3, 0.45, 0.55, 1.6, 0.6
    ax_w = width_in - left - right
    ax_h = ax_w * (y1 - y0) / (x1 - x0)
    H = top + ax_h + mid + line_h + bottom
    W = width_in
    fig = style.new_figure(W, H, dpi)
    ax = fig.add_axes((left / W, (bottom + line_h + mid) / H, ax_w / W, ax_h / H))
    cax = fig.add_axes(((left + ax_w + 0.15) / W, (bottom + line_h + mid) / H, 0.18 / W,
                        ax_h / H))
    norm = SymLogNorm(linthresh=max(thr / 1e3, 0.05), vmin=-big, vmax=big, base=10)
    art = ax.tripcolor(tri, pk, shading="gouraud", cmap="RdBu_r", norm=norm)
    sub = p < -thr
    if sub.any():
        ax.tricontourf(tri, p, levels=[-np.inf, -thr], colors="none", hatches=["////"])
        ax.tricontour(tri, p, levels=[-thr], colors=["navy"], linewidths=1.0)
    ax.tricontour(tri, alpha, levels=[0.5], colors=["black"], linewidths=0.7, alpha=0.6)
    ax.add_patch(Circle((0, 0), g.island_radius * 1e3, fc=style.ISLAND_RGB, ec="0.25", lw=0.8))
    ax.add_patch(Circle((0, 0), g.a * 1e3, fill=False, ec="black", ls=(0, (4, 2.5)), lw=1.2))
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_ylabel("y [mm]")
    ax.set_title(f"{title}: mid-gap pressure (gauge) at t = {fields.time * 1e3:.4g} ms",
                 fontsize=10.5, loc="left")
    lin = max(thr / 1e3, 0.05)
    ticks = symlog_ticks(lin, big)
    cbar = fig.colorbar(art, cax=cax, label="p - p_ambient [kPa] (symmetric log)")
    cbar.set_ticks(ticks, labels=[f"{t:g}" for t in ticks])
    handles = [Patch(fc="white", ec="navy", hatch="////",
                     label=f"sub-ambient, p < -{thr / 1e3:.2g} kPa"),
               Line2D([], [], color="black", lw=0.7, label="meniscus (alpha = 0.5)"),
               Line2D([], [], color="black", ls=(0, (4, 2.5)), label="Hertzian circle")]
    ax.legend(handles=handles, loc="lower right", fontsize=7.5, framealpha=0.85)
    ax.text(0.01, 0.97, f"min {p.min() / 1e3:.3g} kPa, max {p.max() / 1e3:.3g} kPa",
            transform=ax.transAxes, fontsize=8, va="top",
            bbox=dict(fc="white", ec="none", alpha=0.8, pad=1.5))
    # along y = 0
    lx = fig.add_axes((left / W, bottom / H, ax_w / W, line_h / H))
    xs = np.linspace(g.x_min, g.x_max, 600)
    xs = xs[np.abs(xs) > g.island_radius]
    from matplotlib.tri import LinearTriInterpolator

    on_axis = LinearTriInterpolator(tri, pk)(xs * 1e3, np.zeros_like(xs))
    lx.plot(xs * 1e3, on_axis, color="black", lw=1.0)
    lx.fill_between(xs * 1e3, on_axis, 0, where=np.asarray(on_axis.filled(0)) < -thr / 1e3,
                    color="navy", alpha=0.25, lw=0)
    lx.axhline(0, color="0.5", lw=0.6)
    lx.axvspan(-g.island_radius * 1e3, g.island_radius * 1e3, color=style.ISLAND_RGB, lw=0)
    lx.set_xlim(x0, x1)
    lx.set_yscale("symlog", linthresh=lin)
    lx.set_ylim(-1.3 * big, 1.3 * big)
    lx.set_yticks(ticks, labels=[f"{t:g}" for t in ticks])
    lx.set_xlabel("x [mm]  (rolling direction)")
    lx.set_ylabel("p on y = 0 [kPa]")
    lx.grid(alpha=0.3)
    style.save(fig, out)
    return PressureView(path=Path(out), x=x, y=y, p=p, threshold=thr, p_min=float(p.min()),
                        p_max=float(p.max()))


def load_precalc_solution(case: Path) -> dict | None:
    """precalc/solution.npz as a dict (x, y [m] axes, p [Pa], h [m] on (y, x)), or None."""
    path = Path(case) / "precalc" / "solution.npz"
    try:
        with np.load(path) as d:
            return {k: np.asarray(d[k]) for k in ("x", "y", "p", "h")}
    except (OSError, KeyError, ValueError):
        return None


def draw_precalc(solution: dict, summary: dict | None, out: Path, *, title: str,
                 width_in: float = 9.0, dpi: int = style.DPI) -> Path:
    """The EHL precalc: pressure map [GPa] with film contours [nm], and pressure and film
    along y = 0 (the film on a log scale)."""
    from matplotlib.patches import Circle

    x, y, p, h = solution["x"], solution["y"], solution["p"], solution["h"]
    a = float(summary.get("a_m")) if summary and summary.get("a_m") else None
    step = max(1, len(x) // 400)
    xs, ys = x[::step] * 1e3, y[::step] * 1e3
    ps, hs = p[::step, ::step] / 1e9, h[::step, ::step] * 1e9
    fig = style.new_figure(width_in, 4.2, dpi)
    ax = fig.add_axes((0.09, 0.14, 0.34, 0.74))
    im = ax.imshow(ps, origin="lower", extent=(xs[0], xs[-1], ys[0], ys[-1]), cmap="magma",
                   aspect="equal")
    levels = np.array([1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000]) * \
        (10 ** np.floor(np.log10(max(hs.min(), 1e-3))))
    levels = levels[(levels > hs.min()) & (levels < hs.max())][:8]
    if len(levels):
        cs = ax.contour(xs, ys, hs, levels=levels, colors="white", linewidths=0.6)
        ax.clabel(cs, fmt=lambda v: f"{v:g} nm", fontsize=6)
    if a:
        ax.add_patch(Circle((0, 0), a * 1e3, fill=False, ec="cyan", ls=(0, (4, 2.5)), lw=1.0))
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    fig.colorbar(im, ax=ax, label="p [GPa]", fraction=0.046, pad=0.03)
    ax.set_title(f"{title}: EHL precalc", fontsize=10.5, loc="left")
    j = int(np.argmin(np.abs(y)))
    lx = fig.add_axes((0.58, 0.14, 0.33, 0.74))
    lx.plot(x * 1e3, p[j] / 1e9, color="black", lw=1.2, label="p")
    lx.set_xlabel("x [mm]  (y = 0)")
    lx.set_ylabel("p [GPa]")
    rx = lx.twinx()
    rx.semilogy(x * 1e3, h[j] * 1e9, color="tab:blue", lw=1.2, label="h")
    rx.set_ylabel("film h [nm]", color="tab:blue")
    if summary:
        hc, hmin = summary.get("hc_m"), summary.get("hmin_m")
        text = [f"pH = {summary.get('p_hertz_Pa', 0) / 1e9:.3f} GPa" if summary.get(
            "p_hertz_Pa") else None,
            f"hc = {hc * 1e9:.3g} nm" if hc else None,
            f"hmin = {hmin * 1e9:.3g} nm" if hmin else None,
            f"M = {summary['M']:.0f}, L = {summary['L']:.2f}" if "M" in summary and "L" in
            summary else None]
        lx.text(0.03, 0.97, "\n".join(t for t in text if t), transform=lx.transAxes,
                va="top", fontsize=8, bbox=dict(fc="white", ec="0.7", pad=2))
    if a:
        for s in (-1, 1):
            lx.axvline(s * a * 1e3, color="0.6", ls=":", lw=0.8)
    lx.grid(alpha=0.3)
    style.save(fig, out)
    return Path(out)

