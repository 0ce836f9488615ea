"""Where a metric comes to rest on one mesh, from runs that approach it before they get there:
say one run of the mesh from above (started from a wider region) and one from below
(started from a coarser mesh's rest). Each run's history.csv gives the metric write by
write; ``ehlfoam.metrics.convergence.rest_value`` fits one rest value and one relaxation time to all of
them and brackets the rest between a run that ends rising and one that ends falling; each
run fitted alone says whether one relaxation fits them all.

    python bench/rest_value.py CASE[@T0] [CASE[@T0] ...] [--metrics KEY ...]
        [--rate-window W] [--save NAME.json] [--note TEXT]

``CASE@T0`` reads that run from T0 transits on (to leave out the start, where a mapped state
settles on its new mesh). Times are each run's own, in transits. A CASE may also be a case
snapshot (``ehlfoam snapshot``): the run's history up to it, so that a run whose folder is
gone, or which another case continues from the snapshot, still counts. Writes
``bench/results/NAME.json`` (default rest_value.json).
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
from ehlfoam.seed.snapshot import is_snapshot, snapshot_history
from ehlfoam.metrics.convergence import METRICS, rest_value
from ehlfoam.report.case_data import read_history


def series(case: Path, key: str, t0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(times [transits], values) of ``key`` in the case's history.csv (or in the history a
    case snapshot kept, ``ehlfoam snapshot``) from ``t0`` transits on, leaving out writes
    where the metric is undefined."""
    if is_snapshot(case):
        history, transit = snapshot_history(case)
    else:
        history, transit = read_history(case / "history.csv"), load_geometry(case).transit_time
    t, f = history["time_s"] / transit, history[key]
    keep = np.isfinite(f) & (t >= t0 - 1e-9)
    return t[keep], f[keep]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="+", help="CASE or CASE@T0 (read from T0 transits on)")
    ap.add_argument("--metrics", nargs="+", default=["flooded_width_over_a"], choices=METRICS)
    ap.add_argument("--rate-window", type=float, default=0.036, metavar="W",
                    help="transits at the end of each run its rate is read over")
    ap.add_argument("--save", default="rest_value.json", help="record name under bench/results/")
    ap.add_argument("--note", default="")
    args = ap.parse_args(argv)
    cases = [(case, t0 or 0.0) for case, t0 in map(_pick, args.cases)]
    for case, _ in cases:
        if not ((case / "history.csv").is_file() or is_snapshot(case)):
            ap.error(f"cases: {case} has no history.csv (run it first) and is no case snapshot")
    out = {}
    for key in args.metrics:
        try:   # a snapshot that kept no history, too few writes
            r = rest_value([series(case, key, t0) for case, t0 in cases],
                           rate_window=args.rate_window)
        except ValueError as err:
            ap.error(f"{key}: {err}")
        out[key] = r
        print(key)
        for (case, t0), s in zip(cases, r["runs"]):
            label = case.stem if is_snapshot(case) else case.parent.name
            print(f"  {label:42s} from {s['t_first']:.3f} to {s['t_last']:.3f} "
                  f"transits ({s['writes']} writes): {s['first']:.3f} -> {s['last']:.3f}, "
                  f"{s['rate']:+.3f} a transit at the end")
            if s["alone"] is not None:
                a = s["alone"]
                print(f"  {'':42s} alone: " + (
                    f"rest {a['rest']:.3f} +- {a['rest_sd']:.3f}, relaxation time "
                    f"{a['tau']:.3f} +- {a['tau_sd']:.3f} transits" if a["fixed"] else
                    "fixes no rest of its own (its relaxation time is not determined)"))
        bracket = ("none (no run ends rising below one that ends falling)"
                   if r["bracket"] is None else f"{r['bracket'][0]:.3f} - {r['bracket'][1]:.3f}")
        print(f"  rest {r['rest']:.3f} +- {r['rest_sd']:.3f}, relaxation time {r['tau']:.3f} "
              f"+- {r['tau_sd']:.3f} transits, fit rms {r['rms']:.4f}; bracket {bracket}")
        if len(cases) > 1:
            print("  " + {True: "the runs' own rests agree: one relaxation fits them all",
                          False: "the runs' own rests disagree: one relaxation does not fit "
                                 "them all",
                          None: "fewer than two runs fix a rest of their own: the joint rest "
                                "stands on the model"}[r["consistent"]])
    path = save(args.save, {"note": args.note, "cases": args.cases,
                            "rate_window": args.rate_window, "metrics": out})
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
