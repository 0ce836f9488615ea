"""Charts (matplotlib): a case's history, and a batch's bubble length and flow states.

History: the quantities the monitor's steady-state test tracks
(:func:`ehlfoam.run.steady.steady_test`: oil volume, meniscus positions, flooded size, gas
behind the contact / bubble length), against time, with the last transit window and the
test's tolerance band drawn, so that a reader sees whether the run settled and by how much
it missed.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ehlfoam.report import style, units

#: history.csv length columns and their legend labels (units a).
LENGTHS = {
    "inlet_meniscus_distance_over_a": "inlet meniscus distance",
    "flooded_length_over_a": "flooded length",
    "flooded_width_over_a": "flooded width",
    "bubble_length_over_a": "bubble length",
    "wake_gas_length_over_a": "gas behind contact (bubble)",
}


@dataclass
class Settling:
    """Change of each tracked quantity over the last window (one transit), against the
    monitor's tolerance. ``changes``: key -> (change, tolerance, unit); ``window_s``: the
    window actually covered [s] (None: the history is shorter than one window)."""

    changes: dict[str, tuple[float, float, str]]
    window_s: float | None

    @property
    def settled(self) -> bool:
        return self.window_s is not None and all(abs(c) <= t for c, t, _ in
                                                 self.changes.values())


def settling(history: dict[str, np.ndarray], window: float, tol: float,
             length_scale: float) -> Settling:
    """The monitor's test (oil volume within ``tol`` relative, lengths within
    ``tol * length_scale`` a) evaluated on the last written time against the write nearest
    one ``window`` [s] earlier."""
    t = history["time_s"]
    if len(t) < 2 or t[-1] - t[0] < window * (1 - 1e-9):
        return Settling({}, None)
    k = int(np.argmin(np.abs(t - (t[-1] - window))))
    out: dict[str, tuple[float, float, str]] = {}
    v = history.get("oil_volume_m3")
    if v is not None and v[-1] > 0:
        out["oil_volume_m3"] = (float((v[-1] - v[k]) / v[-1]), tol, "relative")
    for key in LENGTHS:
        col = history.get(key)
        if col is None or not np.isfinite(col[[k, -1]]).all():
            continue
        out[key] = (float(col[-1] - col[k]), tol * length_scale, "a")
    return Settling(out, float(t[-1] - t[k]))


def _time_axis(ax, transit_s: float | None) -> None:
    ax.set_xlabel("t [ms]")
    ax.grid(alpha=0.3)
    if transit_s:
        sec = ax.secondary_xaxis("top", functions=(lambda ms: ms / (transit_s * 1e3),
                                                   lambda tr: tr * transit_s * 1e3))
        sec.set_xlabel("transits", fontsize=8)
        sec.tick_params(labelsize=8)


def _panel_title(ax, text: str) -> None:
    ax.text(0.01, 0.97, text, transform=ax.transAxes, fontsize=8.5, va="top", ha="left",
            bbox=dict(fc="white", ec="none", alpha=0.8, pad=1.0), zorder=10)


def draw_history(history: dict[str, np.ndarray], out: Path, *, title: str,
                 transit_s: float | None, tol: float = 0.01, length_scale: float = 10.0,
                 width_in: float = 9.0, dpi: int = style.DPI) -> tuple[Path, Settling]:
    """Oil volume, oil flows, lengths and state against time (history.csv columns, SI)."""
    t_ms = history["time_s"] * 1e3
    window = transit_s or 0.0
    st = settling(history, window, tol, length_scale) if window else Settling({}, None)
    fig = style.new_figure(width_in, 8.4, dpi)
    axes = [fig.add_axes(r) for r in ((0.08, 0.65, 0.36, 0.23), (0.57, 0.65, 0.36, 0.23),
                                      (0.08, 0.31, 0.64, 0.24), (0.08, 0.07, 0.64, 0.12))]
    # the last transit window, once the history covers one (the monitor's test needs it)
    shade = (t_ms[-1] - window * 1e3, t_ms[-1]) if st.window_s is not None else None

    ax = axes[0]
    vol = units.METRICS["oil_volume_m3"]            # bubble_volume_m3 is shown alike
    v = history.get("oil_volume_m3")
    if v is not None:
        ax.plot(t_ms, v * vol.scale, color="tab:brown", lw=1.4, marker=".", ms=3, label="oil")
        if shade:
            ax.fill_between(shade, v[-1] * vol.scale * (1 - tol), v[-1] * vol.scale * (1 + tol),
                            color="tab:green", alpha=0.2, lw=0, label=f"+-{tol:.0%} of last")
    bv = history.get("bubble_volume_m3")
    if bv is not None and np.isfinite(bv).any():
        ax.plot(t_ms, bv * vol.scale, color=style.BUBBLE_RGB, lw=1.2, label="bubble (gas)")
    ax.set_ylabel(f"volume [{vol.unit}]")
    _panel_title(ax, "oil volume (whole contact)")
    ax.legend(fontsize=7.5, loc="lower right")

    ax = axes[1]
    flow = units.METRICS["oil_inflow_m3_s"]         # history.csv's oil_in_m3_s, oil_out_m3_s
    for key, label, colour in (("oil_in_m3_s", "in", "tab:blue"),
                               ("oil_out_m3_s", "out", "tab:orange")):
        col = history.get(key)
        if col is not None:
            ax.plot(t_ms, col * flow.scale, lw=1.2, color=colour, label=f"oil {label}")
    ax.set_ylabel(f"flow [{flow.unit}]")
    _panel_title(ax, "oil through the open boundaries")
    ax.legend(fontsize=7.5, loc="lower right")

    ax = axes[2]
    colours = iter(("tab:purple", "tab:green", "tab:olive", "tab:red", "tab:red"))
    has_bubble = "bubble_length_over_a" in history and \
        np.isfinite(history["bubble_length_over_a"]).any()
    for key, label in LENGTHS.items():
        colour = next(colours)
        col = history.get(key)
        if col is None or (key == "wake_gas_length_over_a" and has_bubble):
            continue
        ax.plot(t_ms, col, lw=1.3, color=colour, label=label)
        if shade and np.isfinite(col[-1]):
            band = tol * length_scale
            ax.fill_between(shade, col[-1] - band, col[-1] + band, color=colour, alpha=0.15,
                            lw=0)
    ax.set_ylabel("length [a]")
    _panel_title(ax, f"menisci and bubble (bands: +-{tol * length_scale:.2g} a)")
    ax.legend(fontsize=7.5, loc="upper left", bbox_to_anchor=(1.02, 1.0))

    ax = axes[3]
    states = history.get("state")
    if states is not None:
        level = np.array([{"I": 1, "II": 2}.get(str(s), np.nan) for s in states])
        ax.step(t_ms, level, where="post", color="black", lw=1.3)
        ax.set_yticks([1, 2], labels=["I", "II"])
        ax.set_ylim(0.5, 2.5)
        ax.set_ylabel("state")
    eb = history.get("enclosed_bubbles")
    if eb is not None:
        rx = ax.twinx()
        rx.plot(t_ms, eb, color="0.55", lw=0.9, ls="--")
        rx.set_ylabel("enclosed gas\nregions (--)", color="0.45", fontsize=8)
    _panel_title(ax, "flow pattern state")
    for ax in axes:
        _time_axis(ax, transit_s)
        if shade:
            ax.axvspan(*shade, color="0.85", alpha=0.5, lw=0, zorder=0)
    verdict = ("settled: every tracked quantity within its band over the last transit"
               if st.settled else
               "not settled over the last transit" if st.window_s else
               "shorter than one transit: the steady-state test cannot apply yet")
    key = "; grey: last transit window" if shade else ""
    fig.text(0.08, 0.975, f"{title}: history ({verdict}{key})",
             fontsize=10, va="top")
    style.save(fig, out)
    return Path(out), st


# ------------------------------------------------------------------ batch charts
def bubble_relation_x(speed: float, a: float, eta: float, rho: float, sigma: float,
                      dp: float) -> float:
    """X = Re^-1/2 (Ca/2)^-5/4 We^-1/2 of the thesis's bubble-length relation
    l/a = C1 X + C2, with Re = rho u a / eta, Ca = dp / (rho u^2 / 2) (cavitation number),
    We = rho u^2 a / sigma. SI inputs; X is dimensionless (it is proportional to u)."""
    re = rho * speed * a / eta
    ca = dp / (0.5 * rho * speed**2)
    we = rho * speed**2 * a / sigma
    return re**-0.5 * (ca / 2.0) ** -1.25 * we**-0.5


@dataclass
class Fit:
    """Least-squares l/a = C1 X + C2 of one temperature; None constants with a reason."""

    temperature: float
    n: int
    c1: float | None
    c2: float | None
    reason: str = ""


def fit_bubble_relation(xs: np.ndarray, ls: np.ndarray, temperature: float) -> Fit:
    """Fit C1, C2 by linear least squares (needs >= 2 distinct X)."""
    ok = np.isfinite(xs) & np.isfinite(ls)
    xs, ls = xs[ok], ls[ok]
    if len(np.unique(np.round(xs, 15))) < 2:
        return Fit(temperature, int(len(xs)), None, None, "not enough points")
    design = np.column_stack([xs, np.ones_like(xs)])
    (c1, c2), *_ = np.linalg.lstsq(design, ls, rcond=None)
    return Fit(temperature, int(len(xs)), float(c1), float(c2))


def draw_bubble_vs_speed(points: list[dict], out: Path, *, label: str,
                         dpi: int = style.DPI) -> tuple[Path, list[Fit]]:
    """l/a against u (in its display unit), one colour per temperature. Fitted: state I cases
    with a bubble (l > 0), filled; not fitted: state II (open wake, hollow) and state I
    without a bubble (l = 0, crosses). ``points``: dicts with speed [m/s], temperature [C], l_over_a,
    x (the relation's X), state."""
    fig = style.new_figure(9.0, 4.6, dpi)
    ax = fig.add_axes((0.08, 0.12, 0.52, 0.78))
    temps = sorted({p["temperature"] for p in points if p["temperature"] is not None})
    fits = []
    for k, temp in enumerate(temps):
        colour = fig_colour(k)
        pts = [p for p in points if p["temperature"] == temp]
        u = np.array([p["speed"] for p in pts]) * units.SPEC["contact.speed"].scale
        l_a = np.array([p["l_over_a"] for p in pts], float)
        xs = np.array([p["x"] for p in pts], float)
        state_i = np.array([p["state"] == "I" for p in pts])
        fitted = state_i & (l_a > 0)
        ax.plot(u[fitted], l_a[fitted], "o", color=colour, label=f"{temp:g} C, state I")
        if (state_i & ~fitted).any():
            ax.plot(u[state_i & ~fitted], l_a[state_i & ~fitted], "x", color=colour,
                    label=f"{temp:g} C, state I, no bubble (not fitted)")
        if (~state_i).any():
            ax.plot(u[~state_i], l_a[~state_i], "o", mfc="none", color=colour,
                    label=f"{temp:g} C, state II, open (not fitted)")
        fit = fit_bubble_relation(xs[fitted], l_a[fitted], temp)
        fits.append(fit)
        if fit.c1 is not None:
            uu = np.linspace(u[fitted].min(), u[fitted].max(), 50)
            slope = np.polyfit(u[fitted], xs[fitted], 1)   # X is proportional to u
            ax.plot(uu, fit.c1 * np.polyval(slope, uu) + fit.c2, "-", color=colour, lw=1.0,
                    label=f"{temp:g} C: C1 = {fit.c1:.3g}, C2 = {fit.c2:.3g}")
    ax.set_xlabel(f"rolling speed {units.short_label('contact.speed')}")
    ax.set_ylabel("l / a")
    ax.grid(alpha=0.3)
    ax.set_title(f"{label} vs speed;\nfit l/a = C1 Re^-1/2 (Ca/2)^-5/4 We^-1/2 + C2",
                 fontsize=9.5, loc="left")
    if points:
        ax.legend(fontsize=7.5, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    style.save(fig, out)
    return Path(out), fits


def fig_colour(k: int):
    """The k-th colour of the default cycle."""
    import matplotlib

    cycle = matplotlib.rcParams["axes.prop_cycle"].by_key()["color"]
    return cycle[k % len(cycle)]


def draw_state_map(rows: list[dict], x_key: str, y_key: str, out: Path, *,
                   x_label: str, y_label: str, x_scale: float = 1.0, y_scale: float = 1.0,
                   panel_key: str | None = None,
                   panel_title: Callable[[Any], str] | None = None,
                   dpi: int = style.DPI) -> Path:
    """State I / II (and failed, other) of each case over two parameters, one panel per
    value of ``panel_key`` (e.g. temperature, titled ``panel_title(value)``); an axis
    spanning a factor 4 or more is logarithmic (base 2: supply layers double). The values
    are drawn times ``x_scale`` and ``y_scale`` (SI to the labels' display units)."""
    import matplotlib
    import matplotlib.ticker  # noqa: F401

    panels = sorted({r.get(panel_key) for r in rows}, key=lambda v: (v is None, v)) \
        if panel_key else [None]
    n = max(1, len(panels))
    width = min(4.0 * n + 2.4, 15)
    strip = all(r.get(y_key) == rows[0].get(y_key) for r in rows)   # one parameter only
    fig = style.new_figure(width, 2.0 if strip else 4.0, dpi)
    markers = {"I": ("o", style.STATE_RGB["I"], "state I"),
               "II": ("s", style.STATE_RGB["II"], "state II"),
               "failed": ("x", "black", "failed"), "running": ("^", "tab:orange", "running"),
               None: ("o", "0.75", "no result yet")}
    for k, value in enumerate(panels):
        span = (width - 2.4) / width      # the legend's column on the right
        ax = fig.add_axes((0.9 / width + k * span / n, 0.28 if strip else 0.14,
                           span / n - 1.0 / width, 0.5 if strip else 0.72))
        seen = set()
        for r in rows:
            if panel_key and r.get(panel_key) != value:
                continue
            xv, yv = r.get(x_key), r.get(y_key)
            if xv is None or yv is None:
                continue
            status = r.get("status")
            kind = ("failed" if status == "failed" else
                    r.get("state") if status == "finished" and r.get("state") in ("I", "II")
                    else "running" if status == "running" else None)
            m, c, lab = markers[kind]
            ax.scatter(float(xv) * x_scale, float(yv) * y_scale, marker=m, color=c, s=55,
                       label=None if kind in seen else lab, zorder=3)
            seen.add(kind)
        ax.set_xlabel(x_label)
        for axis, key, scale in ((ax.xaxis, x_key, x_scale), (ax.yaxis, y_key, y_scale)):
            values = sorted({float(r[key]) * scale for r in rows
                             if isinstance(r.get(key), (int, float))})
            if values and min(values) > 0 and max(values) / min(values) >= 4:
                (ax.set_xscale if axis is ax.xaxis else ax.set_yscale)("log", base=2)
            if 0 < len(values) <= 12:              # the batch's own values as ticks
                axis.set_ticks(values, labels=[f"{v:g}" for v in values])
                axis.set_minor_locator(matplotlib.ticker.NullLocator())
        ax.margins(0.12)
        if strip:
            ax.set_yticks([])
        if k == 0:
            ax.set_ylabel(y_label)
        ax.grid(alpha=0.3)
        if panel_key:
            ax.set_title(panel_title(value) if panel_title else f"{panel_key} = {value}",
                         fontsize=9.5)
        if seen and k == n - 1:
            ax.legend(fontsize=7.5, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    style.save(fig, out)
    return Path(out)


def nan_to_none(value):
    """None for NaN/inf or empty text, else the value."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return None
    if isinstance(value, str) and not value.strip():
        return None
    return value
