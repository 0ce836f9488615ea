"""Side view: the cut along the rolling direction at y = 0, gap height exaggerated.

pyvista slices the case's internal mesh just off the symmetry plane (the cells next to it);
the cut shows the gap between the disc (z = 0) and the ball (z = h(x)), the phases, and the
velocity in the cut: arrows in the oil, and the streamwise velocity over the rolling speed
in colour (reverse flow, the recirculation ahead of and behind the contact, in blue). The
z axis is in um and the x axis in mm; the exaggeration of z over x is stated on the plot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ehlfoam.gap.field import GapField

from ehlfoam.report import style
from ehlfoam.report.fields import Fields

#: Longest velocity arrow, in units of the rolling speed u.
MAX_ARROW = 1.5


@dataclass
class Cut:
    """The slice at y ~ 0 as triangles in (x, z) [m] with per-triangle alpha and velocity
    [m/s], and the gap profile h(x) [m] along it."""

    x: np.ndarray
    z: np.ndarray
    triangles: np.ndarray
    alpha: np.ndarray
    ux: np.ndarray
    uz: np.ndarray
    profile_x: np.ndarray
    profile_h: np.ndarray


@dataclass
class SideView:
    """What :func:`draw_side_view` drew."""

    path: Path
    cut: Cut
    exaggeration: tuple[float, float]   # z over x, whole cut and zoom


def cut_at_axis(fields: Fields) -> Cut:
    """Slice the internal mesh with the plane y = y_c, y_c a fifth of the smallest cell off
    the axis (on the symmetry plane itself the cut would run along cell faces)."""
    g = fields.geom
    y_c = 0.2 * g.min_cell_size
    sl = fields.mesh.slice(normal=(0.0, 1.0, 0.0), origin=(0.0, y_c, 0.0)).triangulate()
    tri = np.asarray(sl.regular_faces) if sl.n_cells else np.zeros((0, 3), int)
    pts = np.asarray(sl.points)
    alpha = np.asarray(sl.cell_data["alpha.oil"], float)
    u = np.asarray(sl.cell_data["U"], float) if "U" in sl.cell_data else \
        np.zeros((len(tri), 3))
    # the ball along the cut, from the case's own gap export: the cut's highest points need
    # not lie on the ball where the node columns lean (ehlfoam.mesh.extrude, "normal")
    px = np.unique(pts[:, 0])
    ph = GapField.load(fields.folder.parent / "precalc")(px, np.full_like(px, y_c))
    return Cut(x=pts[:, 0], z=pts[:, 2], triangles=tri, alpha=np.clip(alpha, 0, 1),
               ux=u[:, 0], uz=u[:, 2], profile_x=px, profile_h=ph)


def _exaggeration(x_span_mm: float, z_span_um: float, width_in: float,
                  height_in: float) -> float:
    """A round factor (1, 2 or 5 x 10^k, rounded down) so that z_span drawn E times larger
    than x fits ``height_in`` for ``x_span`` across ``width_in``."""
    raw = (height_in / width_in) * x_span_mm / max(z_span_um * 1e-3, 1e-12)
    k = math.floor(math.log10(raw))
    for m in (5.0, 2.0, 1.0):
        if m * 10**k <= raw:
            return m * 10**k
    return 10**k


def _panel(fig, rect, cut: Cut, lo: float, hi: float, exaggeration: float, *, colour: str,
           speed: float, island_radius: float, a: float, arrows: bool):
    """One panel of the cut over x in [lo, hi] [m]; ``colour``: "alpha" or "ux"."""
    import matplotlib
    import matplotlib.tri as mtri
    from matplotlib.colors import TwoSlopeNorm

    ax = fig.add_axes(rect)
    x_mm, z_um = cut.x * 1e3, cut.z * 1e6
    tri = mtri.Triangulation(x_mm, z_um, cut.triangles)
    if colour == "alpha":
        art = ax.tripcolor(tri, facecolors=cut.alpha, cmap=style.OIL_CMAP, vmin=0, vmax=1,
                           edgecolors="face", linewidth=0.1)
    else:
        ratio = cut.ux / speed if speed else cut.ux
        top = max(1.5, float(np.percentile(ratio[cut.alpha > 0.5], 99)) if
                  (cut.alpha > 0.5).any() else 1.5)
        # the air's (spurious, numerical) currents would hide the oil's: air is left pale
        shown = np.where(cut.alpha > 0.5, np.clip(ratio, -1.0, top), np.nan)
        cmap = matplotlib.colormaps["RdBu_r"].with_extremes(bad=style.AIR_RGB)
        art = ax.tripcolor(tri, facecolors=shown, cmap=cmap,
                           norm=TwoSlopeNorm(vmin=-1.0, vcenter=0.0, vmax=top),
                           edgecolors="face", linewidth=0.1)
        # the phases' boundary on top of the velocity
        node = _node_values(cut)
        try:
            ax.tricontour(tri, node, levels=[0.5], colors="black", linewidths=1.0)
        except ValueError:
            pass
    sel = (cut.profile_x >= lo) & (cut.profile_x <= hi)
    ax.plot(cut.profile_x[sel] * 1e3, cut.profile_h[sel] * 1e6, color="0.2", lw=1.4)
    ax.axhline(0.0, color="0.2", lw=2.2)
    ax.axvspan(-island_radius * 1e3, island_radius * 1e3, color=style.ISLAND_RGB, alpha=0.9,
               lw=0)
    ax.axvspan(-a * 1e3, a * 1e3, color="0.35", alpha=0.9, lw=0)
    if arrows:
        _arrows(ax, cut, lo, hi, speed)
    z_top = float(cut.profile_h[sel].max()) * 1e6 if sel.any() else 1.0
    ax.set_xlim(lo * 1e3, hi * 1e3)
    ax.set_ylim(-0.04 * z_top, 1.04 * z_top)
    ax.set_aspect(exaggeration * 1e-3, adjustable="box")
    ax.set_ylabel(f"z [um]\n(x{exaggeration:g})")
    return ax, art


def _node_values(cut: Cut) -> np.ndarray:
    """Per-point alpha (mean of the triangles around each point), for contouring."""
    s = np.zeros(len(cut.x))
    c = np.zeros(len(cut.x))
    for k in range(3):
        np.add.at(s, cut.triangles[:, k], cut.alpha)
        np.add.at(c, cut.triangles[:, k], 1.0)
    return s / np.maximum(c, 1.0)


def _arrows(ax, cut: Cut, lo: float, hi: float, speed: float, nx: int = 34,
            levels: tuple[float, ...] = (0.15, 0.32, 0.5, 0.68, 0.85)) -> None:
    """Velocity arrows in the oil on a regular grid of x and gap fractions. An arrow is the
    displacement over a fixed time, drawn in the exaggerated frame so that it follows the
    walls; u = rolling speed is one grid spacing long."""
    import matplotlib.tri as mtri

    tri = mtri.Triangulation(cut.x * 1e3, cut.z * 1e6, cut.triangles)
    finder = tri.get_trifinder()
    xs = np.linspace(lo, hi, nx + 2)[1:-1]
    h = np.interp(xs, cut.profile_x, cut.profile_h)
    X = np.repeat(xs, len(levels))
    Z = (h[:, None] * np.asarray(levels)[None, :]).ravel()
    k = finder(X * 1e3, Z * 1e6)
    ok = k >= 0
    ok[ok] = cut.alpha[k[ok]] > 0.5
    if not ok.any():
        return
    step_mm = (hi - lo) * 1e3 / (nx + 1) * 0.85
    ux, uz = cut.ux[k[ok]], cut.uz[k[ok]]
    ref = speed if speed else max(float(np.abs(ux).max()), 1e-12)
    # the spurious currents next to the menisci would cover the picture: arrows longer
    # than MAX_ARROW u are drawn MAX_ARROW u long (direction kept)
    mag = np.hypot(ux, uz) / ref
    shrink = np.minimum(1.0, MAX_ARROW / np.maximum(mag, 1e-30))
    ux, uz = ux * shrink, uz * shrink
    ax.quiver(X[ok] * 1e3, Z[ok] * 1e6, ux / ref * step_mm, uz / ref * step_mm * 1e3,
              angles="xy", scale_units="xy", scale=1.0, width=0.0022, headwidth=3.5,
              color="black", alpha=0.85, zorder=5)


def draw_side_view(fields: Fields, out: Path, *, title: str, width_in: float = 9.0,
                   dpi: int = style.DPI) -> SideView:
    """Draw the y = 0 cut of ``fields`` into ``out`` (PNG): the whole length coloured by
    phase, and a zoom on the contact coloured by u_x / u with arrows."""
    g = fields.geom
    cut = cut_at_axis(fields)
    a = g.a
    left, right = 0.95, 1.2
    ax_w = width_in - left - right
    lo1, hi1 = g.x_min, g.x_max
    lo2, hi2 = max(g.x_min, -6.0 * a), min(g.x_max, 8.0 * a)

    def span(lo, hi):
        sel = (cut.profile_x >= lo) & (cut.profile_x <= hi)
        return float(cut.profile_h[sel].max()) * 1e6 if sel.any() else 1.0

    z1, z2 = span(lo1, hi1), span(lo2, hi2)
    e1 = _exaggeration((hi1 - lo1) * 1e3, z1 * 1.08, ax_w, 1.9)
    e2 = _exaggeration((hi2 - lo2) * 1e3, z2 * 1.08, ax_w, 2.2)
    h1 = ax_w * (z1 * 1.08e-3 * e1) / ((hi1 - lo1) * 1e3)
    h2 = ax_w * (z2 * 1.08e-3 * e2) / ((hi2 - lo2) * 1e3)
    top, gap, bottom = 0.45, 0.75, 0.85
    height_in = top + h1 + gap + h2 + bottom
    fig = style.new_figure(width_in, height_in, dpi)
    W, H = width_in, height_in
    ax1, art1 = _panel(fig, (left / W, (bottom + h2 + gap) / H, ax_w / W, h1 / H), cut, lo1,
                       hi1, e1, colour="alpha", speed=g.speed, island_radius=g.island_radius,
                       a=a, arrows=False)
    ax1.set_title(f"{title}  (z exaggerated x{e1:g} top, x{e2:g} bottom)", fontsize=10.5,
                  loc="left")
    ax1.text(0.99, 0.92, "ball", transform=ax1.transAxes, ha="right", va="top", fontsize=8)
    ax1.text(0.01, 0.06, "disc (glass), moving at u ->", transform=ax1.transAxes, fontsize=8,
             va="bottom")
    ax2, art2 = _panel(fig, (left / W, bottom / H, ax_w / W, h2 / H), cut, lo2, hi2, e2,
                       colour="ux", speed=g.speed, island_radius=g.island_radius, a=a,
                       arrows=True)
    ax2.set_xlabel("x [mm]  (rolling direction ->; grey: island and Hertzian contact)")
    ax1.set_xlabel("")
    for ax, art, label in ((ax1, art1, "oil fraction"), (ax2, art2, "u_x / u")):
        pos = ax.get_position()
        cax = fig.add_axes((pos.x1 + 0.12 / W, pos.y0, 0.15 / W, pos.height))
        fig.colorbar(art, cax=cax, label=label)
    ax2.text(0.01, 0.93, "oil coloured by u_x / u (blue: reverse flow), air pale; "
             "arrows: velocity in the oil "
             f"(u = one spacing, capped at {MAX_ARROW:g} u)",
             transform=ax2.transAxes, fontsize=7.5, va="top",
             bbox=dict(fc="white", ec="none", alpha=0.75, pad=1))
    style.save(fig, out)
    return SideView(path=Path(out), cut=cut, exaggeration=(e1, e2))
