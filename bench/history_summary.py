"""Summarise finished runs from their ``history.csv`` and ``metrics.json`` alone (no fields).

For runs whose time folders are gone or were never brought back (a run made on another
machine, a pruned case): the state at every write, when the wake first opened, and the mean,
min and max over the last transit of the flow-pattern metrics and the oil volume's drift.

    python bench/history_summary.py CASE [CASE ...] [--save NAME.json] [--note TEXT]
"""
from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.common import RESULTS, save  # noqa: E402

#: history.csv columns summarised over the last transit.
TRACKED = ("inlet_meniscus_distance_over_a", "flooded_length_over_a", "flooded_width_over_a",
           "bubble_length_over_a", "oil_volume_m3")


def _rows(case: Path) -> list[dict]:
    with open(case / "history.csv", newline="") as fh:
        return list(csv.DictReader(fh))


def summarise(case: str | Path) -> dict:
    """The summary of one case folder (needs ``history.csv`` and ``metrics.json``)."""
    case = Path(case)
    metrics = json.loads((case / "metrics.json").read_text())
    transit = metrics["transit_time_s"]
    rows = _rows(case)
    t = [float(r["time_s"]) for r in rows]
    states = [r["state"] for r in rows]
    opened = next((ti for ti, r in zip(t, rows) if r["state"] == "II"), None)
    last = [r for ti, r in zip(t, rows) if ti >= t[-1] - transit * (1 + 1e-9)]
    window = {}
    for key in TRACKED:   # an empty value: not found at that write (the meniscus at the edge)
        v = [float(r[key]) for r in last if r[key] != ""]
        window[key] = ({"mean": sum(v) / len(v), "min": min(v), "max": max(v), "n": len(v)}
                       if v else None)
    v0 = float(last[0]["oil_volume_m3"])
    span = (float(last[-1]["time_s"]) - float(last[0]["time_s"])) / transit
    return {
        "case": case.name,
        "cells": metrics.get("cells"),
        "time_steps": metrics.get("time_steps"),
        "wall_s": metrics.get("wall_s"),
        "end_reason": metrics.get("end_reason"),
        "t_first_s": t[0], "t_last_s": t[-1],
        "transits_written": (t[-1] - t[0]) / transit,
        "states_per_write": " ".join(states),
        "state_last": rows[-1]["state"],
        "writes_state_I": states.count("I"),
        "writes": len(rows),
        "first_open_s": opened,
        "first_open_transits": None if opened is None else opened / transit,
        "bubble_enclosed_last_transit": sum(r["state"] == "I" and float(r["bubble_length_over_a"]) > 0
                                            for r in last) / len(last),
        "last_transit": window,
        "oil_volume_drift_per_transit": ((float(last[-1]["oil_volume_m3"]) - v0) / v0 / span
                                         if span > 0 else None),
        "outflow_over_inflow_last": (float(rows[-1]["oil_out_m3_s"]) / float(rows[-1]["oil_in_m3_s"])
                                     if float(rows[-1]["oil_in_m3_s"]) > 0 else None),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="+")
    ap.add_argument("--save", default=None, help=f"file name under {RESULTS}")
    ap.add_argument("--note", default="", help="how and where the runs were made")
    args = ap.parse_args(argv)
    rows = [summarise(c) for c in args.cases]
    for r in rows:
        w = r["last_transit"]
        opened = r["first_open_transits"]
        opened = "never" if opened is None else f"at {opened:.2f} transit"
        print(f"{r['case']}: {r['cells']} cells, {r['transits_written']:.2f} transits written, "
              f"{r['time_steps']} steps, {r['wall_s']:.0f} s wall, end {r['end_reason']}; "
              f"states {r['states_per_write']}; first open {opened}")
        print("   last transit: " + ", ".join(
            f"{k} {v['mean']:.4g} ({v['min']:.4g}-{v['max']:.4g}, {v['n']} writes)" if v
            else f"{k} not found" for k, v in w.items())
            + f"; oil volume drift {r['oil_volume_drift_per_transit']:+.2%}/transit, "
              f"out/in {r['outflow_over_inflow_last']:.3f}")
    if args.save:
        print(save(args.save, {"note": args.note, "rows": rows}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
