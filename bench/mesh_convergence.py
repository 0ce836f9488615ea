"""Mesh convergence of the flow pattern: the same case on several levels, compared at the same
simulated times (from each case's history.csv, so that runs stopped at different times compare).

    python bench/mesh_convergence.py CASE_COARSE CASE_MEDIUM CASE_FINE [--transits 1 2]

Prints, per time, the inlet meniscus distance, the flooded width and length and the oil volume
of each level, and their change from the previous level; writes
``bench/results/mesh_convergence.json``.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from generator.case_writer import load_geometry  # noqa: E402

RESULTS = ROOT / "bench" / "results"
KEYS = ("inlet_meniscus_distance_over_a", "flooded_width_over_a", "flooded_length_over_a",
        "oil_volume_m3")


def at_time(case: Path, t: float) -> dict | None:
    rows = list(csv.DictReader(open(case / "history.csv")))
    best = min(rows, key=lambda r: abs(float(r["time_s"]) - t))
    if abs(float(best["time_s"]) - t) > 0.02 * t:
        return None
    return {k: (float(best[k]) if best[k] not in ("", "None") else None) for k in KEYS} | {
        "time_s": float(best["time_s"]), "state": best["state"]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="+")
    ap.add_argument("--transits", nargs="+", type=float, default=[1.0, 2.0])
    args = ap.parse_args(argv)
    cases = [Path(c) for c in args.cases]
    out = []
    for n in args.transits:
        t = n * load_geometry(cases[0]).transit_time
        row = {"transits": n, "time_s": t, "levels": {}}
        for case in cases:
            geom = load_geometry(case)
            row["levels"][case.name] = {"cells": geom.cells, **(at_time(case, t) or {})}
        out.append(row)
        print(f"t = {t:.4f} s ({n:g} transits)")
        for name, v in row["levels"].items():
            vals = "  ".join(f"{k[:-7] if k.endswith('_over_a') else k} "
                             f"{v.get(k) if v.get(k) is None else round(v[k] * (1e12 if k == 'oil_volume_m3' else 1), 3)}"
                             for k in KEYS)
            print(f"  {name:8s} {v['cells']:7d} cells  {v.get('state', '-')}  {vals}")
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "mesh_convergence.json").write_text(json.dumps(out, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
