"""The flooded region's outline along x: its width at stations x / a, from one or more runs,
averaged over the writes of a window, to compare meshes where the widest point agrees but
the shoulders behind it may not.

    python bench/region_outline.py CASE[@T] [CASE[@T] ...] [--stations -4 -2 0 2 4 6 8 10]
        [--window W] [--gap-mean] [--save NAME.json]

For each case, the writes within W transits (default 0.1) up to T transits (default: its last
write) are read; at each of them the mid-gap oil is rastered as the run's metrics do and the
region's width at each station measured (:func:`ehlfoam.metrics.pattern.flooded_widths_at`), and at its
widest (the run's ``flooded_width_over_a``); ``--gap-mean`` reads the oil averaged across the
gap instead of at mid-gap. Printed are
the means over the writes and, for more than one case, each case's difference from the first.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.common import save  # noqa: E402
from bench.plot_midgap import _pick  # noqa: E402
from ehlfoam.case.geometry import load_geometry
from ehlfoam.run import fields as case_fields
from ehlfoam.metrics import pattern as metrics


def outline(case: Path, at: float | None, stations_over_a: list[float],
            window: float = 0.1, gap_mean: bool = False) -> dict:
    """Mean widths [a] of the flooded region at ``stations_over_a`` and at its widest over
    the writes within ``window`` transits up to ``at`` transits (the last write for None),
    and their spread; of the oil at mid-gap, as the run's metrics read it, or with
    ``gap_mean`` of the oil averaged across the gap (the oil's own lateral extent, whatever
    shape its meniscus has across the gap)."""
    g = load_geometry(case)
    st = case_fields.Structure.load(case)
    t_end, _ = case_fields.write_near(case, "last" if at is None else str(at), g.transit_time)
    picked = [(t, f) for t, f in case_fields.time_folders(case)
              if t_end - window * g.transit_time - 1e-12 <= t <= t_end]
    rows, widest = [], []
    for _, folder in picked:
        oil = (st.gap_mean(case_fields.read_alpha(folder / "alpha.oil", st)) if gap_mean
               else case_fields.mid_gap_alpha(folder, st, g))
        r = case_fields.column_raster(oil, st, g)
        widths = metrics.flooded_widths_at(r, np.asarray(stations_over_a) * g.a)
        rows.append([np.nan if w is None else w / g.a for w in widths])
        widest.append(metrics.flow_pattern_from_raster(r)["flooded_width_over_a"])
    w = np.array(rows)
    return {"case": str(case), "to_transits": t_end / g.transit_time, "window": window,
            "writes": len(rows), "stations_over_a": stations_over_a,
            "width_over_a": np.nanmean(w, axis=0).tolist(),
            "width_sd_over_a": np.nanstd(w, axis=0).tolist(), "gap_mean": gap_mean,
            "widest_over_a": float(np.mean(widest)), "widest_sd_over_a": float(np.std(widest))}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("cases", nargs="+", help="CASE or CASE@TRANSITS")
    ap.add_argument("--stations", nargs="+", type=float,
                    default=[-4.0, -2.0, 0.0, 2.0, 4.0, 6.0, 8.0, 10.0], help="x / a")
    ap.add_argument("--window", type=float, default=0.1,
                    help="transits up to each case's time averaged over (default 0.1)")
    ap.add_argument("--gap-mean", action="store_true",
                    help="read the oil averaged across the gap, not at mid-gap")
    ap.add_argument("--save", help="write bench/results/NAME.json")
    args = ap.parse_args(argv)
    if args.window < 0.0:
        ap.error(f"--window = {args.window}: must be >= 0 (transits)")
    results = [outline(*_pick(c), args.stations, args.window, args.gap_mean)
               for c in args.cases]
    print("x / a:" + " " * 41 + "".join(f"{x:7.1f}" for x in args.stations) + "  widest")
    first = np.array(results[0]["width_over_a"] + [results[0]["widest_over_a"]])
    for r in results:
        label = f"{r['case'][-30:]:30s} to {r['to_transits']:5.3f} ({r['writes']:2d} writes)"
        row = np.array(r["width_over_a"] + [r["widest_over_a"]])
        print(f"{label:47s}" + "".join(f"{v:7.2f}" for v in row[:-1]) + f"{row[-1]:8.3f}")
        if r is not results[0]:
            diff = row - first
            print(f"{'  - first':47s}" + "".join(f"{v:+7.2f}" for v in diff[:-1])
                  + f"{diff[-1]:+8.3f}")
    if args.save:
        save(args.save, {"command": " ".join(sys.argv), "results": results})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
