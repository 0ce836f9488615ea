"""Where a case's oil went between two of its writes: the change of the oil held in each
column of cells across the gap, split by what the mid-gap was at the two writes.

Each column (one base cell of the 2D mesh, wall to wall) holds sum(alpha V) of oil. Between
the writes at T1 and T2 transits its change is put in one of four classes by the mid-gap oil
fraction (0.5) at the two writes:

- ``inside``: oil at mid-gap at both (the flooded region's columns; they change only where
  the oil does not fill them wall to wall, e.g. air along a wall or a smeared interface),
- ``flooded``: air, then oil (the region grew over them),
- ``drained``: oil, then air,
- ``outside``: air at both (the meniscus's own columns, with oil along the walls under air at
  mid-gap, and the films on the walls further out; the ``outside`` change is also given by
  the column's distance from the region at T2, in bins of ``DISTANCES`` a),

and, across the classes, by position: ahead of the contact (x < -a), beside it (|x| <= a),
behind it (x > a), and on the track (|y| <= its half-width) or off it. Volumes are of the
whole contact (doubled in a half domain), in nl. Both writes must be on the same mesh.

    python bench/oil_change.py CASE T1 T2 [--plot OUT.png] [--window=X0,X1,Y0,Y1] [--save NAME.json]

T1, T2 in transits (the write nearest each; ``last`` for the last write).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.common import save  # noqa: E402
from bench.plot_midgap import dress_top_view, parse_window  # noqa: E402
from ehlfoam.case.geometry import load_geometry, load_spec_of
from ehlfoam.run import fields as case_fields

NL = 1e-12  # m3 per nanolitre
CLASSES = ("inside", "flooded", "drained", "outside")
#: where a column is, by x / a
POSITIONS = ("ahead (x < -a)", "beside (|x| <= a)", "behind (x > a)")
#: bin edges [a] of the outside columns' distance from the nearest column with oil at mid-gap
DISTANCES = (0.0, 0.5, 1.0, 2.0, 4.0, np.inf)


def columns(folder: Path, st: case_fields.Structure,
            n_layers: int) -> tuple[np.ndarray, np.ndarray]:
    """(oil per column [m3], mid-gap oil fraction) per base cell of the write ``folder``."""
    alpha = np.clip(case_fields.read_alpha(folder / "alpha.oil", st), 0.0, 1.0)
    n_base = len(st.base_x)
    oil = np.bincount(st.base_cell, alpha * st.cell_volumes, minlength=n_base)
    return oil, st.mid_gap(alpha, n_layers)


def oil_change(case: Path, t1: str, t2: str, track_half_width: float | None = None) -> dict:
    """The change of the oil between the writes nearest ``t1`` and ``t2`` transits, by class
    and position (module docstring); also the per-column arrays for a plot (key "_columns")."""
    g = load_geometry(case)
    st = case_fields.Structure.load(case)
    (ta, fa), (tb, fb) = (case_fields.write_near(case, t, g.transit_time) for t in (t1, t2))
    oil_a, mid_a = columns(fa, st, g.n_layers)
    oil_b, mid_b = columns(fb, st, g.n_layers)
    if track_half_width is None:
        track_half_width = load_spec_of(case).supply.track_half_width
    wet_a, wet_b = mid_a > 0.5, mid_b > 0.5
    cls = np.select([wet_a & wet_b, ~wet_a & wet_b, wet_a & ~wet_b], CLASSES[:3], CLASSES[3])
    d = (oil_b - oil_a) * g.mirror / NL
    x, y = st.base_x / g.a, np.abs(st.base_y) / g.a
    where = dict(zip(POSITIONS, (x < -1.0, np.abs(x) <= 1.0, x > 1.0)))
    track = y <= track_half_width / g.a
    table = {}
    for c in CLASSES:
        sel = cls == c
        row = {"total_nl": float(d[sel].sum()),
               "on_track_nl": float(d[sel & track].sum()),
               "off_track_nl": float(d[sel & ~track].sum())}
        row.update({k: float(d[sel & m].sum()) for k, m in where.items()})
        row["columns"] = int(sel.sum())
        table[c] = row
    outside = cls == "outside"
    xy = np.stack([st.base_x, st.base_y], 1) / g.a
    dist = cKDTree(xy[wet_b]).query(xy)[0] if wet_b.any() else np.full(len(d), np.inf)
    profile = []
    for lo, hi in zip(DISTANCES[:-1], DISTANCES[1:]):
        sel = outside & (dist >= lo) & (dist < hi)
        profile.append({"from_over_a": lo, "to_over_a": hi, "columns": int(sel.sum()),
                        "total_nl": float(d[sel].sum()),
                        "behind_nl": float(d[sel & (x > 1.0)].sum())})
    return {
        "case": str(case), "time_1_s": ta, "time_2_s": tb,
        "transits_1": ta / g.transit_time, "transits_2": tb / g.transit_time,
        "oil_1_nl": float(oil_a.sum() * g.mirror / NL),
        "oil_2_nl": float(oil_b.sum() * g.mirror / NL),
        "change_nl": float(d.sum()), "by_class": table,
        "outside_by_distance": profile, "track_half_width_over_a": track_half_width / g.a,
        "_columns": {"x": x, "y": st.base_y / g.a, "d_nl": d, "area": st.footprint,
                     "mid_1": mid_a, "mid_2": mid_b, "mirror": g.mirror, "geometry": g},
    }


def plot(out: Path, r: dict, window) -> None:
    """A top view of the change per column, as a thickness of oil [um] (the change over the
    column's area), with the meniscus (mid-gap 0.5) at both writes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    c = r["_columns"]
    thick = c["d_nl"] * NL / c["mirror"] / c["area"] * 1e6
    x, y = c["x"], c["y"]
    if c["mirror"] == 2:
        x, y, thick = np.r_[x, x], np.r_[y, -y], np.r_[thick, thick]
        m1, m2 = np.r_[c["mid_1"], c["mid_1"]], np.r_[c["mid_2"], c["mid_2"]]
    else:
        m1, m2 = c["mid_1"], c["mid_2"]
    lim = float(np.percentile(np.abs(thick), 99.5)) or 1.0
    fig, ax = plt.subplots(figsize=(9, 5.5))
    sc = ax.tricontourf(x, y, np.clip(thick, -lim, lim), levels=np.linspace(-lim, lim, 21),
                        extend="both", cmap="RdBu_r")
    ax.tricontour(x, y, m1, levels=[0.5], colors="0.4", linewidths=0.8, linestyles="--")
    ax.tricontour(x, y, m2, levels=[0.5], colors="k", linewidths=0.9)
    dress_top_view(ax, c["geometry"], window)
    ax.set_title(f"oil gained per column, transits {r['transits_1']:.1f} -> "
                 f"{r['transits_2']:.1f}: {r['oil_1_nl']:.1f} -> {r['oil_2_nl']:.1f} nl "
                 f"(meniscus dashed before, solid after)", fontsize=9)
    fig.colorbar(sc, ax=ax, label="oil gained, as a thickness [um]", shrink=0.8)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110, bbox_inches="tight")
    print(f"wrote {out}")


def report(r: dict) -> str:
    head = ["class", "columns", "total", "on track", "off track", *POSITIONS]
    lines = [f"{r['case']}: transits {r['transits_1']:.2f} -> {r['transits_2']:.2f}, oil "
             f"{r['oil_1_nl']:.2f} -> {r['oil_2_nl']:.2f} nl ({r['change_nl']:+.2f} nl)",
             " | ".join(head)]
    for c, row in r["by_class"].items():
        vals = [row["total_nl"], row["on_track_nl"], row["off_track_nl"],
                *(row[k] for k in POSITIONS)]
        lines.append(" | ".join([c, str(row["columns"]), *(f"{v:+.2f}" for v in vals)]))
    lines.append("outside, by distance from the region: " + ", ".join(
        f"{b['from_over_a']:g}-{b['to_over_a']:g} a {b['total_nl']:+.2f} nl "
        f"({b['behind_nl']:+.2f} behind)" for b in r["outside_by_distance"]))
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("case", type=Path)
    p.add_argument("t1", help="transits of the first write, or 'last'")
    p.add_argument("t2", help="transits of the second write, or 'last'")
    p.add_argument("--plot", type=Path)
    p.add_argument("--window", help="X0,X1,Y0,Y1 in units of a, for the plot")
    p.add_argument("--save", help="record name under bench/results/")
    args = p.parse_args(argv)
    window = parse_window(args.window) if args.window else None
    try:
        r = oil_change(args.case, args.t1, args.t2)
    except ValueError as err:
        raise SystemExit(f"oil_change: {err}")
    print(report(r))
    if args.plot:
        plot(args.plot, r, window)
    if args.save:
        print(f"wrote {save(args.save, {k: v for k, v in r.items() if k != '_columns'})}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
