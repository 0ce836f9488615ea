"""Mesh convergence of the flow pattern: the same case on several meshes, compared at the same
simulated times (from each case's history.csv, so that runs stopped at different times compare)
or at their last state (``--final``, the mean over each case's last transit), and, given the
cell size that sets each mesh apart (``--sizes``), the observed order, the Richardson extrapolation and the
grid convergence index of every metric over each three meshes in a row.

    python bench/mesh_convergence.py CASE_COARSE CASE_MEDIUM CASE_FINE [--transits 1 2]
        [--window W] [--final] [--sizes H_COARSE H_MEDIUM H_FINE] [--save NAME.json]
        [--note TEXT]

At equal times each case gives its write nearest the time, or with ``--window W`` its mean over
the writes of the W transits up to it (a resolved meniscus jitters write by write).

The reading is ``ehlfoam.metrics.convergence.observed_order`` (Celik et al. 2008; its docstring has the
formulas). Writes ``bench/results/NAME.json`` (default mesh_convergence.json).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.common import save  # noqa: E402
from ehlfoam.case.geometry import load_geometry
from ehlfoam.metrics.convergence import (METRICS, history_number, jitter, last_transit, observed_order, read_history_rows, window_mean)

KEYS = METRICS


def at_time(case: Path, t: float, window: float | None = None) -> dict | None:
    """The case's write nearest ``t`` [s] (None if none lies within 2 %), with each metric's
    jitter over the writes of the quarter transit up to it; with ``window`` [transits], each
    metric's mean over the writes of the ``window`` transits up to that write instead."""
    rows = read_history_rows(case)
    if not rows:
        return None
    best = min(rows, key=lambda r: abs(float(r["time_s"]) - t))
    tb = float(best["time_s"])
    if abs(tb - t) > 0.02 * t:
        return None
    if window is not None:
        return window_mean(case, tb, window)
    span = 0.25 * load_geometry(case).transit_time
    recent = [r for r in rows if tb - span <= float(r["time_s"]) <= tb]
    return {k: history_number(best[k]) for k in KEYS} | {
        "time_s": tb, "state": best["state"], "jitter": jitter(recent)}


def orders(names: list[str], sizes: list[float], levels: dict) -> dict:
    """observed_order of every metric over each three cases in a row (ordered as given); the
    noise is twice the largest jitter of the three (over the last transit with ``--final``,
    over the window with ``--window``, over the quarter transit up to the write compared
    otherwise)."""
    out = {}
    for i in range(len(names) - 2):
        trio = names[i:i + 3]
        for k in KEYS:
            vals = [levels[n].get(k) for n in trio]
            if None not in vals:
                noise = 2 * max(levels[n].get("jitter", {}).get(k, 0.0) for n in trio)
                out.setdefault(" / ".join(trio), {})[k] = observed_order(
                    tuple(sizes[i:i + 3]), tuple(vals), noise=noise)
    return out


def _fmt(k: str, v: float | None) -> str:
    if v is None:
        return "-"
    return f"{v * 1e12:.1f} nl" if k == "oil_volume_m3" else f"{v:.3f}"


def _print_orders(trios: dict) -> None:
    for trio, per_key in trios.items():
        print(f"  over {trio}:")
        for k, o in per_key.items():
            line = f"    {k:32s} {o['behaviour']:11s}"
            if o.get("R") is not None:
                line += f" R {o['R']:+.2f}"
            if o.get("spread") is not None:
                line += f"  spread {_fmt(k, o['spread'])}"
            if o.get("order") is not None:
                line += (f"  p {o['order']:.2f}  extrapolated {_fmt(k, o['extrapolated'])}"
                         f"  GCI(fine) {100 * o['gci_fine']:.1f} %")
                if not o["asymptotic"]:
                    line += "  (order outside 0.5-3: not asymptotic, not to be trusted)"
            print(line)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="+")
    ap.add_argument("--transits", nargs="+", type=float, default=[1.0, 2.0])
    ap.add_argument("--window", type=float, default=None, metavar="W",
                    help="at equal times, each metric's mean over the W transits up to the "
                         "time, not the one write")
    ap.add_argument("--final", action="store_true",
                    help="compare each case's last transit (mean), not equal times")
    ap.add_argument("--sizes", nargs="+", type=float,
                    help="the cell size that sets each case's mesh apart (one per case, any "
                         "one unit): adds the observed order, extrapolation and GCI")
    ap.add_argument("--save", default="mesh_convergence.json",
                    help="record name under bench/results/")
    ap.add_argument("--note", default="")
    args = ap.parse_args(argv)
    cases = [Path(c) for c in args.cases]
    if args.sizes is not None and (len(args.sizes) != len(cases) or len(cases) < 3):
        ap.error(f"--sizes: need one size per case and at least three cases, got "
                 f"{len(args.sizes)} sizes for {len(cases)} cases")
    names = [f"{c.parent.name}/{c.name}" for c in cases]
    samples = ([("final", None)] if args.final else
               [(f"{n:g} transits", n * load_geometry(cases[0]).transit_time)
                for n in args.transits])
    out = []
    for label, t in samples:
        levels = {}
        for name, case in zip(names, cases):
            vals = last_transit(case) if t is None else (at_time(case, t, args.window) or {})
            levels[name] = {"cells": load_geometry(case).cells} | vals
        row = {"sample": label, "time_s": t, "levels": levels}
        print(label if t is None else f"t = {t:.4f} s ({label})")
        for name, v in levels.items():
            vals = "  ".join(f"{k.removesuffix('_over_a')} {_fmt(k, v.get(k))}" for k in KEYS)
            print(f"  {name:40s} {v['cells']:7d} cells  {v.get('state', '-')}  {vals}")
        if args.sizes is not None:
            row["orders"] = orders(names, args.sizes, levels)
            _print_orders(row["orders"])
        out.append(row)
    path = save(args.save, {"note": args.note, "cases": [str(c) for c in cases],
                            "sizes": args.sizes, "samples": out})
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
