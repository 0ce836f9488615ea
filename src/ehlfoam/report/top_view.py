"""Top view: the mid-gap oil fraction as the interferometry camera sees the contact.

The picture is the metrics' own raster (:func:`ehlfoam.metrics.pattern.raster`, a/20 pixels, a half
domain mirrored to the full picture) with the metrics' own ``alpha = 0.5`` lines
(:func:`ehlfoam.metrics.pattern.meniscus_contours`), so that what is drawn is what was measured. On
it: the island wall (grey) with the Hertzian circle (dashed), the bubble (gas at the contact
exit, red), a scale bar in mm, the rolling direction, the state label and a caption with the
key numbers. Axes in mm.
"""

from __future__ import annotations

import json
import textwrap
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import ndimage

from ehlfoam.metrics import pattern as flow

from ehlfoam.report import style, units

_FOUR = ndimage.generate_binary_structure(2, 1)
_EIGHT = ndimage.generate_binary_structure(2, 2)


@dataclass
class TopView:
    """What :func:`draw_top_view` drew: the PNG, the raster, the meniscus lines [m], the
    bubble pixels and the map from data (mm) to PNG pixels."""

    path: Path
    raster: flow.Raster
    contours: list[np.ndarray]
    bubble: np.ndarray
    pixel_from_mm: list[float]
    caption: list[str]

    def pixel(self, x_m: float, y_m: float) -> tuple[float, float]:
        """(column, row) in the PNG of the point (x, y) [m]."""
        sx, ox, sy, oy = self.pixel_from_mm
        return ox + sx * x_m * 1e3, oy - sy * y_m * 1e3


def bubble_mask(r: flow.Raster, threshold: float = 0.5) -> np.ndarray:
    """Gas pixels of the bubble: the gas regions (4-connected) that touch the island rim
    downstream (x > 0). :func:`ehlfoam.metrics.pattern.bubble_mask` when the metrics module has it (so
    that the picture is what the metrics measured), else the same rule here."""
    if hasattr(flow, "bubble_mask"):
        return np.asarray(flow.bubble_mask(r, threshold), dtype=bool)
    gas = r.gas(threshold)
    labels, _ = ndimage.label(gas, structure=_FOUR)
    rim = ndimage.binary_dilation(r.island, structure=_EIGHT) & ~r.island
    hit = np.unique(labels[rim & gas & (np.broadcast_to(r.x, gas.shape) > 0.0)])
    return np.isin(labels, hit[hit > 0])


def enclosed_part(mask: np.ndarray) -> np.ndarray:
    """The regions of ``mask`` (4-connected) that do not reach the domain edge."""
    labels, _ = ndimage.label(mask, structure=_FOUR)
    edge = np.zeros_like(mask)
    edge[0, :] = edge[-1, :] = edge[:, 0] = edge[:, -1] = True
    open_labels = np.unique(labels[edge & mask])
    return mask & ~np.isin(labels, open_labels[open_labels > 0])


def bubble_length(metrics: dict) -> tuple[float | None, str]:
    """(l/a, label) of the bubble behind the contact. The bubble metrics
    (``bubble_length_over_a``, from x = a to the bubble's tip) when the bubble is enclosed;
    otherwise (no bubble metrics yet, or an open wake, whose "tip" is the domain edge) the
    gas run behind the contact on y = 0, ``wake_gas_length_over_a``, standing in for it."""
    if metrics.get("bubble_length_over_a") is not None and metrics.get("bubble_enclosed"):
        return float(metrics["bubble_length_over_a"]), "bubble length"
    value = metrics.get("wake_gas_length_over_a")
    label = "gas behind the contact on y = 0" + (" (open wake)" if metrics.get("wake_open")
                                                else " (bubble)")
    return (None if value is None else float(value)), label


def _fmt(value, digits: int = 3) -> str:
    return "-" if value is None else f"{value:.{digits}g}"


def caption_lines(pattern: dict, a: float, time_s: float, transit_s: float | None,
                  symmetric: bool, oil_volume: float | None = None) -> list[str]:
    """The caption: state, inlet meniscus, flooded region, bubble, oil, time."""
    state = pattern.get("state")
    if state == "I":
        what = "flooded region closed around the contact"
    else:
        what = ", ".join(w for w, k in (("open wake: outer air reaches the contact exit",
                                           "wake_open"),
                                          ("starved inlet: outer air reaches the contact inlet",
                                           "inlet_starved")) if pattern.get(k)) or "open"
    mm = a * 1e3
    d = pattern.get("inlet_meniscus_distance_over_a")
    shape = pattern.get("inlet_meniscus_shape")
    at_rim = " (at the island rim)" if pattern.get("inlet_meniscus_at_rim") else ""
    inlet = ("oil reaches the inlet" if d is None else
             f"{d:.2f} a = {d * mm:.3f} mm upstream of x = -a{at_rim}"
             + (f", {shape}" if shape else ""))
    length, width = pattern.get("flooded_length_over_a"), pattern.get("flooded_width_over_a")
    flooded = ("none" if length is None else
               f"{length:.2f} a x {width:.2f} a ({length * mm:.2f} mm x {width * mm:.2f} mm)")
    l_a, l_label = bubble_length(pattern)
    enclosed = pattern.get("enclosed_bubbles")
    bubble = "no gas behind the contact" if l_a == 0 else f"{l_label} {_fmt(l_a)} a"
    vol = units.METRICS["oil_volume_m3"]
    oil = f" | oil {oil_volume * vol.scale:.3g} {vol.unit}" if oil_volume else ""
    transits = f" = {time_s / transit_s:.2f} transits" if transit_s else ""
    mirrored = "half domain mirrored about y = 0, " if symmetric else ""
    return [f"State {state}: {what}.",
            f"Inlet meniscus {inlet} | flooded region {flooded} | {bubble}{oil}.",
            f"t = {time_s * 1e3:.4g} ms{transits}; mid-gap oil fraction, {mirrored}"
            f"{_fmt(enclosed)} enclosed gas region(s); black: alpha = 0.5 meniscus."]


def draw_top_view(r: flow.Raster, pattern: dict, out: Path, *, title: str,
                  time_s: float, speed: float, transit_s: float | None = None,
                  oil_volume: float | None = None, width_in: float = 9.0,
                  dpi: int = style.DPI) -> TopView:
    """Draw the top view of raster ``r`` with the flow-pattern numbers ``pattern`` (a dict
    as :func:`ehlfoam.metrics.pattern.flow_pattern` returns) into ``out`` (PNG). ``speed`` [m/s],
    ``time_s`` [s]; returns the :class:`TopView` (with the data-to-pixel map, written also
    to ``out`` with suffix .json)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle, Patch
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

    g, a = r.geom, r.geom.a
    mm = 1e3
    x0, x1 = r.x[0] * mm, r.x[-1] * mm
    y0, y1 = r.y[0] * mm, r.y[-1] * mm
    caption = caption_lines(pattern, r.geom.a, time_s, transit_s, r.geom.symmetric,
                            oil_volume)
    wrapped = [w for line in caption for w in textwrap.wrap(line, int(14 * width_in))]
    left, right, top = 0.8, 1.25, 0.45                        # inches
    bottom = 0.75 + 0.19 * len(wrapped)
    ax_w = width_in - left - right
    ax_h = ax_w * (y1 - y0) / (x1 - x0)
    height_in = top + ax_h + bottom
    fig = style.new_figure(width_in, height_in, dpi)
    ax = fig.add_axes((left / width_in, bottom / height_in, ax_w / width_in, ax_h / height_in))
    cax = fig.add_axes(((left + ax_w + 0.15) / width_in, bottom / height_in,
                        0.18 / width_in, ax_h / height_in))

    hx, hy = 0.5 * r.dx * mm, 0.5 * r.dy * mm
    cmap = style.OIL_CMAP.with_extremes(bad=style.ISLAND_RGB)
    im = ax.imshow(np.ma.masked_invalid(r.alpha), origin="lower", cmap=cmap, vmin=0.0,
                   vmax=1.0, extent=(x0 - hx, x1 + hx, y0 - hy, y1 + hy),
                   interpolation="nearest", zorder=1)
    bubble = enclosed_part(bubble_mask(r))
    if bubble.any():
        ax.contourf(r.x * mm, r.y * mm, bubble.astype(float), levels=[0.5, 1.5],
                    colors=[(*style.BUBBLE_RGB, 0.22)], zorder=2)
        ax.contour(r.x * mm, r.y * mm, bubble.astype(float), levels=[0.5],
                   colors=[style.BUBBLE_RGB], linewidths=1.6, zorder=3)
    contours = flow.meniscus_contours(r)
    for line in contours:
        ax.plot(line[:, 0] * mm, line[:, 1] * mm, color=style.MENISCUS_RGB, lw=1.2,
                solid_joinstyle="round", zorder=4)
    ax.add_patch(Circle((0, 0), g.island_radius * mm, fc=style.ISLAND_RGB, ec="0.25",
                        lw=0.8, zorder=5))
    ax.add_patch(Circle((0, 0), a * mm, fill=False, ec="black", ls=(0, (4, 2.5)), lw=1.3,
                        zorder=6))
    l_a, l_label = bubble_length(pattern)
    if l_a:
        x_end = min((1.0 + l_a) * a, g.x_max) * mm
        ax.annotate("", xy=(x_end, 0.0), xytext=(a * mm, 0.0), zorder=7,
                    arrowprops=dict(arrowstyle="|-|,widthA=0.3,widthB=0.3",
                                    color=style.BUBBLE_RGB, lw=1.3, shrinkA=0, shrinkB=0))

    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]  (rolling direction)")
    ax.set_ylabel("y [mm]")
    ax.set_title(title, fontsize=11, loc="left")
    bar = style.nice_length(x1 - x0, 0.15)
    ax.add_artist(AnchoredSizeBar(ax.transData, bar, f"{bar:g} mm", "lower left", pad=0.4,
                                  sep=3, frameon=True, size_vertical=0.008 * (y1 - y0),
                                  color="black", fontproperties={"size": 8}))
    u = units.SPEC["contact.speed"]
    ax.annotate(f"rolling, {u.symbol} = {speed * u.scale:.3g} {u.unit}", xy=(0.30, 0.94),
                xytext=(0.02, 0.94), xycoords="axes fraction", va="center", fontsize=9,
                arrowprops=dict(arrowstyle="-|>", lw=1.6, color="black"),
                bbox=dict(fc="white", ec="none", alpha=0.8, pad=1.5), zorder=8)
    state = pattern.get("state")
    ax.text(0.98, 0.94, f"State {state}", transform=ax.transAxes, ha="right", va="center",
            fontsize=15, fontweight="bold", color=style.STATE_RGB.get(state, "black"),
            bbox=dict(fc="white", ec=style.STATE_RGB.get(state, "black"), lw=1.2, pad=3),
            zorder=8)
    handles = [Line2D([], [], color="black", lw=1.2, label="meniscus (alpha = 0.5)"),
               Line2D([], [], color="black", ls=(0, (4, 2.5)), lw=1.3,
                      label=f"Hertzian circle, a = {a * 1e3:.3f} mm"),
               Patch(fc=style.ISLAND_RGB, ec="0.25", label="island wall (contact, unmeshed)"),
               Patch(fc=(*style.BUBBLE_RGB, 0.22), ec=style.BUBBLE_RGB,
                     label="bubble (enclosed gas at the exit)")]
    if l_a:
        handles.append(Line2D([], [], color=style.BUBBLE_RGB, lw=1.3, marker="|", ms=7,
                              label=f"{l_label.split(' (')[0]}: l = {l_a:.2f} a from x = a"))
    ax.legend(handles=handles, loc="lower right", fontsize=7.5, framealpha=0.85)
    fig.colorbar(im, cax=cax, label="oil volume fraction at mid-gap")
    fig.text(left / width_in, 0.12 / height_in, "\n".join(wrapped), fontsize=8.5,
             va="bottom", ha="left", linespacing=1.5)
    style.save(fig, out)
    pixel = style.data_to_pixel(fig, ax, draw=False)
    Path(out).with_suffix(".json").write_text(json.dumps({
        "pixel_from_mm": pixel, "air_rgb": style.AIR_RGB, "oil_rgb": style.OIL_RGB,
        "state": state, "time_s": time_s, "a_m": a}, indent=1) + "\n")
    return TopView(path=Path(out), raster=r, contours=contours, bubble=bubble,
                   pixel_from_mm=pixel, caption=caption)


def axis_crossing_upstream(contours: list[np.ndarray], island_radius: float) -> float | None:
    """x [m] where the meniscus lines cross y = 0 on the inlet side (x < -island_radius),
    the crossing nearest to the island; None if there is none."""
    best = None
    for line in contours:
        x, y = line[:, 0], line[:, 1]
        for k in np.flatnonzero(np.sign(y[:-1]) * np.sign(y[1:]) <= 0):
            if y[k] == y[k + 1]:
                continue
            xc = x[k] + (x[k + 1] - x[k]) * (0.0 - y[k]) / (y[k + 1] - y[k])
            if xc < -island_radius and (best is None or xc > best):
                best = float(xc)
    return best


def thumbnail(png: Path, out: Path, width: int = 300,
              box: tuple[float, float, float, float] | None = None,
              stamp: str | None = None) -> Path:
    """A small copy of ``png`` (PIL), ``width`` pixels wide, cropped to ``box`` (left, top,
    right, bottom pixels) if given, with ``stamp`` (e.g. "FAILED") written across its top
    in red."""
    from PIL import Image, ImageDraw, ImageFont

    with Image.open(png) as im:
        im = im.convert("RGB")
        if box is not None:
            im = im.crop(tuple(int(round(v)) for v in box))
        h = max(1, int(round(im.height * width / im.width)))
        im = im.resize((width, h), Image.LANCZOS)
    if stamp:
        draw = ImageDraw.Draw(im)
        font = ImageFont.load_default(size=max(12, width // 12))
        draw.rectangle((0, 0, width, width // 9 + 4), fill=(190, 30, 30))
        draw.text((6, 2), stamp, fill=(255, 255, 255), font=font)
    im.save(out, optimize=True)
    return Path(out)


def axes_box(view: "TopView") -> tuple[float, float, float, float]:
    """Pixel box (left, top, right, bottom) of the top view's map, from its data-to-pixel
    map and raster extent, with a few pixels of margin."""
    r = view.raster
    c0, r0 = view.pixel(r.x[0], r.y[-1])
    c1, r1 = view.pixel(r.x[-1], r.y[0])
    return c0 - 4, r0 - 4, c1 + 4, r1 + 4
