"""Summarise finished runs from their ``history.csv`` and ``metrics.json`` alone (no fields).

For runs whose time folders are gone or were never brought back (a run made on another
machine, a pruned case): the state at every write, when the wake first opened, and the mean,
min and max over the last transit of the flow-pattern metrics and the oil volume's drift, and
the share of the outflow that left anywhere but through the outlet (runs whose history.csv
has the per-boundary columns). Over the last transit also how many writes had the wake open,
the inlet meniscus at the rim, and a concave or convex inlet meniscus (with the median of its
fitted c2): from history.csv where it has those columns (runs since 2026-11-24), else from
the written fields where they are still there.

    python bench/history_summary.py CASE [CASE ...] [--save NAME.json] [--note TEXT]
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.common import RESULTS, save  # noqa: E402
from ehlfoam.case.geometry import load_geometry
from ehlfoam.run import fields as case_fields
from ehlfoam.run.fields import off_outlet_share
from ehlfoam.report.case_data import read_history

#: history.csv columns summarised over the last transit.
TRACKED = ("inlet_meniscus_distance_over_a", "flooded_length_over_a", "flooded_width_over_a",
           "bubble_length_over_a", "oil_volume_m3")
#: ... and these where the run wrote them (the gas scenes; older histories lack some)
TRACKED_IF_WRITTEN = ("bubble_volume_m3", "min_pressure_Pa", "gas_release_m3_s",
                      "gas_dissolution_m3_s", "oil_smeared_fraction")


def summarise(case: str | Path) -> dict:
    """The summary of one case folder (needs ``history.csv`` and ``metrics.json``; a run
    killed before its end has only the monitor's first ``metrics.json``: the transit time
    then comes from the case's geometry)."""
    case = Path(case)
    metrics = json.loads((case / "metrics.json").read_text())
    transit = metrics.get("transit_time_s") or load_geometry(case).transit_time
    h = read_history(case / "history.csv")
    t, states = h["time_s"], [str(x) for x in h["state"]]
    opened = next((float(ti) for ti, st in zip(t, states) if st == "II"), None)
    last = t >= t[-1] - transit * (1 + 1e-9)
    window = {}
    written = [k for k in TRACKED_IF_WRITTEN if k in h and np.isfinite(h[k]).any()]
    for key in (*TRACKED, *written):   # NaN: not found at that write (the meniscus at the edge)
        v = h[key][last]
        v = v[np.isfinite(v)]
        window[key] = ({"mean": float(v.mean()), "min": float(v.min()), "max": float(v.max()),
                        "n": int(v.size)} if v.size else None)
    volume, t_last = h["oil_volume_m3"][last], t[last]
    span = (t_last[-1] - t_last[0]) / transit
    in_last, out_last = h["oil_in_m3_s"][-1], h["oil_out_m3_s"][-1]
    state = np.array(states)
    enclosed = (state[last] == "I") & (h["bubble_length_over_a"][last] > 0)
    before_open = np.cumsum(state == "II") == 0   # the writes before the wake first opened
    bubbles = h["bubble_length_over_a"][before_open & (state == "I")]
    bubbles = bubbles[np.isfinite(bubbles)]
    return {
        "case": case.name,
        "folder": str(case.resolve().relative_to(ROOT)) if case.resolve().is_relative_to(ROOT)
        else str(case),
        "cells": metrics.get("cells"),
        "time_steps": metrics.get("time_steps"),
        "wall_s": metrics.get("wall_s"),
        "end_reason": metrics.get("end_reason"),
        "t_first_s": float(t[0]), "t_last_s": float(t[-1]),
        "transits_written": float(t[-1] - t[0]) / transit,
        "states_per_write": " ".join(states),
        "state_last": states[-1],
        "writes_state_I": states.count("I"),
        "writes": len(states),
        "first_open_s": opened,
        "first_open_transits": None if opened is None else opened / transit,
        "bubble_enclosed_last_transit": float(enclosed.mean()),
        "largest_enclosed_bubble_before_open_over_a": (float(bubbles.max()) if bubbles.size
                                                       else None),
        "oil_mass_balance_error": metrics.get("oil_mass_balance_error"),
        "last_transit": window,
        "oil_volume_drift_per_transit": (float((volume[-1] - volume[0]) / volume[0] / span)
                                         if span > 0 else None),
        "outflow_over_inflow_last": float(out_last / in_last) if in_last > 0 else None,
        "off_outlet_fraction_last_transit": _off_outlet_share(h, last),
        "inlet_last_transit": _inlet_counts(case, h, t[last]),
    }


def _inlet_counts(case: Path, h: dict[str, np.ndarray], times: np.ndarray) -> dict | None:
    """Over the writes at ``times``: how many had the wake open, the inlet meniscus at the rim,
    a concave / convex inlet meniscus, and the median fitted c2. From history.csv's columns,
    else re-read from the written fields (None where neither is there)."""
    if "inlet_meniscus_shape" in h:
        rows = np.isin(h["time_s"], times)
        patterns = [{"wake_open": h["wake_open"][i],
                     "inlet_meniscus_at_rim": h["inlet_meniscus_at_rim"][i],
                     "inlet_meniscus_shape": h["inlet_meniscus_shape"][i] or None,
                     "inlet_meniscus_c2": h["inlet_meniscus_c2"][i]}
                    for i in np.flatnonzero(rows)]
        source = "history.csv"
    else:
        folders = dict(case_fields.time_folders(case))
        picked = [folders[t] for t in folders if np.isclose(times, t, rtol=0, atol=1e-12).any()]
        if not picked:
            return None
        geom, structure = load_geometry(case), case_fields.Structure.load(case)
        patterns = [case_fields.sample(f, structure, geom).pattern for f in picked]
        source = "fields"
    c2 = np.array([np.nan if p["inlet_meniscus_c2"] is None else float(p["inlet_meniscus_c2"])
                   for p in patterns])
    shapes = [p["inlet_meniscus_shape"] for p in patterns]
    return {"writes": len(patterns), "source": source,
            "wake_open": sum(bool(p["wake_open"]) for p in patterns),
            "at_rim": sum(bool(p["inlet_meniscus_at_rim"]) for p in patterns),
            "concave": shapes.count("concave"), "convex": shapes.count("convex"),
            "c2_median": float(np.nanmedian(c2)) if np.isfinite(c2).any() else None}


def _off_outlet_share(h: dict[str, np.ndarray], last: np.ndarray) -> float | None:
    """The share of the oil outflow over the writes ``last`` that left anywhere but through
    the outlet, from the per-boundary columns ``oil_out_<boundary>_m3_s`` of history.csv
    (None for runs made before it had them: bench/outflow_split.py reads those from their
    fields)."""
    prefix, suffix = "oil_out_", "_m3_s"
    out = {key[len(prefix):-len(suffix)]: float(np.nansum(h[key][last])) for key in h
           if key.startswith(prefix) and key.endswith(suffix) and key != "oil_out_m3_s"}
    return off_outlet_share(out) if out else None


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
        largest = r["largest_enclosed_bubble_before_open_over_a"]
        largest = "none" if largest is None else f"{largest:.2f} a"
        balance = r["oil_mass_balance_error"]
        balance = "-" if balance is None else f"{balance:.2%}"
        wall = "-" if r["wall_s"] is None else f"{r['wall_s']:.0f} s"   # None: killed
        print(f"{r['case']}: {r['cells']} cells, {r['transits_written']:.2f} transits written, "
              f"{r['time_steps']} steps, {wall} wall, end {r['end_reason']}; "
              f"states {r['states_per_write']}; first open {opened}; largest enclosed "
              f"bubble before it {largest}; oil balance {balance}")
        print("   last transit: " + ", ".join(
            f"{k} {v['mean']:.4g} ({v['min']:.4g}-{v['max']:.4g}, {v['n']} writes)" if v
            else f"{k} not found" for k, v in w.items())
            + f"; oil volume drift {r['oil_volume_drift_per_transit']:+.2%}/transit, "
              f"out/in {r['outflow_over_inflow_last']:.3f}"
            + ("" if r["off_outlet_fraction_last_transit"] is None else
               f", off the outlet {r['off_outlet_fraction_last_transit']:.1%}"))
        inlet = r["inlet_last_transit"]
        if inlet:
            c2 = "-" if inlet["c2_median"] is None else f"{inlet['c2_median']:+.3f}"
            print(f"   last transit, of {inlet['writes']} writes ({inlet['source']}): wake open "
                  f"{inlet['wake_open']}, inlet meniscus at the rim {inlet['at_rim']}, concave "
                  f"{inlet['concave']}, convex {inlet['convex']}, median c2 {c2}")
    if args.save:
        print(save(args.save, {"note": args.note, "rows": rows}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
