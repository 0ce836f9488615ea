"""Top views of the mid-gap oil fraction of finished cases, side by side (a quick look, not the
report of issue 5): oil dark, air light, the island (unmeshed contact) black, the Hertzian
circle red, the metrics in the titles.

    python bench/plot_midgap.py OUT.png [--window X0,X1,Y0,Y1] [--overlay] CASE[@TRANSITS] ...

CASE@2.6 shows the write nearest 2.6 transits (the state and bubble in its title then come from
the case's history.csv at that write); a bare CASE shows the last write and its metrics.json.
``--window -4,6,-3.5,3.5`` shows only x/a in [-4, 6] and y/a in [-3.5, 3.5] (the whole domain
by default). ``--overlay`` draws the menisci (mid-gap oil fraction 0.5) of all the cases on one
top view instead, one colour each, to compare a mesh series at the same time.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from ehlfoam.case.geometry import load_geometry
from ehlfoam.run import fields as case_fields
from ehlfoam.report.case_data import read_history


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) < 2:
        print(__doc__)
        return 2
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out, rest = Path(argv[0]), list(argv[1:])
    window, overlay = None, False
    while rest[:1] in (["--window"], ["--overlay"]):
        if rest[0] == "--overlay":
            overlay, rest = True, rest[1:]
        elif len(rest) > 2:
            window, rest = parse_window(rest[1]), rest[2:]
        else:
            raise SystemExit("plot_midgap: --window needs X0,X1,Y0,Y1 and at least one case")
    picks = [_pick(arg) for arg in rest]
    if overlay:
        return _overlay(out, picks, window)
    fig, axs = plt.subplots(len(picks), 1, figsize=(7, 3.6 * len(picks)), squeeze=False,
                            gridspec_kw={"hspace": 0.45})
    for ax, (case, at) in zip(axs[:, 0], picks):
        g, t, x, y, mid = _mid_gap_at(case, at)
        tc = ax.tricontourf(x, y, mid, levels=np.linspace(0, 1, 11), cmap="Blues")
        m = _metrics_at(case, None if at is None else t)
        if m.get("status") == "running":   # a run in progress: its last sampled write
            m = _metrics_at(case, t)
        spec = json.loads((case / "ehlfoam" / "spec.json").read_text())
        sup = spec["supply"]
        supply = (f"layers {sup['disc_layer'] * 1e6:g}+{sup['ball_layer'] * 1e6:g} um"
                  if sup["mode"] == "layers" else sup["mode"])
        fmt = lambda v: "-" if v is None else f"{v:.2f}"  # noqa: E731
        scene = spec.get("scene", "interface")
        if scene == "gas-release":
            phys = spec["physics"]
            scene += (f" (p_r {phys['cavitation_pressure'] * 1e-3:g} kPa, "
                      f"k {phys['gas_release_rate']:g}/(Pa s))")
        ax.set_title(f"{scene}: u = {g.speed * 1e3:g} mm/s, {supply}, {spec['mesh']['resolution']}, "
                     f"t = {t * 1e3:.0f} ms: "
                     f"state {m.get('state', '?')}, inlet meniscus "
                     f"{fmt(m.get('inlet_meniscus_distance_over_a'))} a "
                     f"({m.get('inlet_meniscus_shape') or '-'})"
                     + (f", bubble {fmt(m.get('bubble_length_over_a'))} a"
                        if m.get("bubble_length_over_a") else ""), fontsize=8)
        dress_top_view(ax, g, window)
    fig.colorbar(tc, ax=axs.ravel().tolist(), label="oil fraction at mid-gap",
                 orientation="horizontal", fraction=0.02 if len(picks) > 1 else 0.05,
                 pad=0.04 if len(picks) > 1 else 0.2)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110, bbox_inches="tight")
    print(f"wrote {out}")
    return 0


def _mid_gap_at(case: Path, at: float | None):
    """(geometry, time [s], x / a, y / a, mid-gap oil fraction) of the write nearest ``at``
    transits (the last write for None), mirrored onto y < 0 in a half domain."""
    g = load_geometry(case)
    st = case_fields.Structure.load(case)
    times = case_fields.time_folders(case)
    t, folder = (times[-1] if at is None
                 else min(times, key=lambda tf: abs(tf[0] - at * g.transit_time)))
    mid = np.clip(case_fields.mid_gap_alpha(folder, st, g), 0.0, 0.9999)  # inside the top level
    x, y = st.base_x / g.a, st.base_y / g.a
    if g.symmetric:
        x, y, mid = np.r_[x, x], np.r_[y, -y], np.r_[mid, mid]
    return g, t, x, y, mid


def _overlay(out: Path, picks: list[tuple[Path, float | None]], window) -> int:
    """The menisci of all ``picks`` on one top view, labelled with their width."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.5))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, (case, at) in enumerate(picks):
        g, t, x, y, mid = _mid_gap_at(case, at)
        m = _metrics_at(case, t)
        width = m.get("flooded_width_over_a")
        c = colours[k % len(colours)]
        ax.tricontour(x, y, mid, levels=[0.5], colors=c, linewidths=1.2)
        ax.plot([], [], color=c, label=f"{case.parent.name}/{case.name}, t = {t * 1e3:.0f} ms"
                + (f", width {width:.2f} a" if width is not None else ""))
    dress_top_view(ax, g, window)
    ax.set_title("menisci at mid-gap (oil fraction 0.5)", fontsize=9)
    ax.legend(fontsize=7, loc="lower left")
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110, bbox_inches="tight")
    print(f"wrote {out}")
    return 0


def dress_top_view(ax, g, window) -> None:
    """The island (black), the Hertzian circle (red), equal axes in units of a, the window."""
    import matplotlib.pyplot as plt

    ax.add_patch(plt.Circle((0, 0), g.island_radius / g.a, color="k"))
    ax.add_patch(plt.Circle((0, 0), 1.0, color="r", fill=False, lw=1))
    ax.set_aspect("equal")
    if window is not None:
        ax.set_xlim(*window[:2])
        ax.set_ylim(*window[2:])
    ax.set_xlabel("x / a (rolling ->)")
    ax.set_ylabel("y / a")


def parse_window(arg: str) -> tuple[float, float, float, float]:
    """"X0,X1,Y0,Y1" (in units of a) -> the four limits, checked."""
    try:
        x0, x1, y0, y1 = (float(v) for v in arg.split(","))
    except ValueError:
        raise SystemExit(f"--window {arg!r}: expected four numbers X0,X1,Y0,Y1 (in a)")
    if not (x0 < x1 and y0 < y1):
        raise SystemExit(f"--window {arg!r}: needs X0 < X1 and Y0 < Y1")
    return x0, x1, y0, y1


def _pick(arg: str) -> tuple[Path, float | None]:
    """"CASE" or "CASE@TRANSITS" -> (case folder, transits or None for the last write)."""
    case, sep, at = arg.rpartition("@")
    if not sep:
        return Path(arg), None
    try:
        return Path(case), float(at)
    except ValueError:
        raise SystemExit(f"plot_midgap: {arg!r}: the part after @ must be a number of transits")


def _metrics_at(case: Path, t: float | None) -> dict:
    """metrics.json (t None), or the history.csv row nearest time t [s] (None where empty)."""
    if t is None:
        f = case / "metrics.json"
        return json.loads(f.read_text()) if f.exists() else {}
    h = read_history(case / "history.csv")
    if h is None:
        return {}
    i = int(np.argmin(np.abs(h["time_s"] - t)))
    return {k: (None if isinstance(v[i], float) and np.isnan(v[i]) else v[i])
            for k, v in h.items()}


if __name__ == "__main__":
    raise SystemExit(main())
