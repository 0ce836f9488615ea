"""Where a run stopped while still filling would balance, read off its ``history.csv``.

Per transit: the oil held (mean over the transit's writes), the fill rate (the slope of the oil
volume over the transit divided by the mean inflow: 0 when the region sends out what it takes
in, 1 when nothing leaves) and the means of the flow-pattern metrics. Over the last ``--fit``
transits two readings of one model, fill = k (V* - V), that is an exponential approach in time:

- ``linear``: fill against the oil held, a straight line, V* where it reaches zero;
- ``exponential``: ln|fill| against time, a straight line of slope -1/tau; the oil still to
  come (or to go, in a draining run) is the fill rate at the last transit times the inflow
  times tau.

Each metric is then read at V* from a straight line of the metric against the oil held over the
same transits. The two readings differ only in how they weigh the noise of the fill rate; their
spread is the least uncertainty of the estimate. It is an estimate, not a balance: a region that
grows in jumps (a meniscus crossing a cell) or has a second balanced state further on is not seen.

    python bench/fill_extrapolation.py CASE [CASE ...] [--fit 8] [--window 1] [--table]
        [--save NAME.json] [--note TEXT]

``--window 0.5`` takes half-transit rows (``--fit`` then counts rows); ``--table`` prints them
(with the outflow over the inflow and the rear of the region on y = 0).
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.common import save  # noqa: E402
from ehlfoam.case.geometry import load_geometry
from ehlfoam.report.case_data import read_history

#: history.csv columns read at the extrapolated balance.
METRICS = ("flooded_width_over_a", "flooded_length_over_a", "inlet_meniscus_distance_over_a")


def per_transit(history: dict[str, np.ndarray], transit_s: float,
                window: float = 1.0) -> list[dict]:
    """One row per whole window of ``window`` transits of the history (``time_s`` from the
    run's start at 0): its end (in transits and s), the mean oil held (m3), the fill rate (-),
    the outflow over the inflow (where the history has it) and the metrics' means."""
    t, volume, inflow = history["time_s"], history["oil_volume_m3"], history["oil_in_m3_s"]
    span = window * transit_s
    rows = []
    for k in range(int(t[-1] / span + 1e-9)):
        inside = (t > k * span * (1 + 1e-9)) & (t <= (k + 1) * span * (1 + 1e-9))
        if inside.sum() < 3:
            continue
        slope = np.polyfit(t[inside], volume[inside], 1)[0]
        row = {"transit": round((k + 1) * window, 6), "t_end_s": float(t[inside][-1]),
               "oil_volume_m3": float(volume[inside].mean()),
               "fill_rate": float(slope / inflow[inside].mean()),
               "inflow_m3_s": float(inflow[inside].mean())}
        if "oil_out_m3_s" in history:
            row["out_over_in"] = float(history["oil_out_m3_s"][inside].mean()
                                       / inflow[inside].mean())
        for key in METRICS:
            v = history[key][inside]
            row[key] = float(np.nanmean(v)) if np.isfinite(v).any() else None
        rows.append(row)
    return rows


def extrapolate(rows: list[dict], n_fit: int) -> dict:
    """The two readings of the balance from the last ``n_fit`` rows of :func:`per_transit`:
    V* (m3) and each metric there, and the transits still to go (exponential reading only).
    A reading is None where its fit does not point at a balance (the fill rate not shrinking;
    for the exponential reading also a fill rate that changes sign inside the fit)."""
    fit = rows[-n_fit:]
    if len(fit) < 3:
        raise ValueError(f"fit: {len(fit)} transits; at least 3 are needed")
    volume = np.array([r["oil_volume_m3"] for r in fit])
    fill = np.array([r["fill_rate"] for r in fit])
    t = np.array([r["t_end_s"] for r in fit])
    transit_s = float(np.median(np.diff(t)))

    slope, intercept = np.polyfit(volume, fill, 1)
    v_linear = -intercept / slope if slope < 0 else None

    v_exp, transits_left = None, None
    sign = np.sign(fill[-1])
    if (np.sign(fill) == sign).all() and sign != 0:   # filling (or draining) all along
        rate, log0 = np.polyfit(t, np.log(sign * fill), 1)
        if rate < 0:
            tau = -1.0 / rate
            fill_last = float(sign * np.exp(log0 + rate * t[-1]))
            v_exp = float(volume[-1] + fill_last * fit[-1]["inflow_m3_s"] * tau)
            transits_left = 3.0 * tau / transit_s   # to within 5 % of the oil still to come

    def at(v: float | None) -> dict | None:
        if v is None:
            return None
        out = {"oil_volume_m3": float(v)}
        for key in METRICS:
            vals = np.array([np.nan if r[key] is None else r[key] for r in fit])
            ok = np.isfinite(vals)
            out[key] = (float(np.polyval(np.polyfit(volume[ok], vals[ok], 1), v))
                        if ok.sum() >= 2 else None)
        return out

    return {"fit_transits": [fit[0]["transit"], fit[-1]["transit"]],
            "fill_rate_last": float(fill[-1]),
            "linear": at(v_linear), "exponential": at(v_exp),
            "exponential_transits_to_95pc": transits_left}


def analyse(case: str | Path, n_fit: int, window: float = 1.0) -> dict:
    """Rows of ``window`` transits and both readings of one case folder, fitted over the last
    ``n_fit`` rows (no readings, None, before three whole rows)."""
    case = Path(case)
    metrics = json.loads((case / "metrics.json").read_text())
    transit = metrics.get("transit_time_s") or load_geometry(case).transit_time
    history = read_history(case / "history.csv")
    rows = per_transit(history, transit, window)
    return {"case": case.name,
            "folder": str(case.resolve().relative_to(ROOT)) if case.resolve().is_relative_to(ROOT)
            else str(case),
            "end_reason": metrics.get("end_reason"), "per_transit": rows,
            "balance": extrapolate(rows, n_fit) if len(rows) >= 3 else None}


def _print_rows(result: dict) -> None:
    """The rows: where each window ends, the metrics' means, the oil and out / in; the rear
    of the region on y = 0 is its length less the inlet meniscus distance and a."""
    print(f"  {'transits':>9}{'width/a':>9}{'inlet/a':>9}{'rear x/a':>10}{'oil nl':>8}{'out/in':>8}")
    for r in result["per_transit"]:
        length, inlet = r["flooded_length_over_a"], r["inlet_meniscus_distance_over_a"]
        rear = length - inlet - 1.0 if length is not None and inlet is not None else None
        values = [r["flooded_width_over_a"], inlet, rear]
        print(f"  {r['transit']:9.2f}" + "".join(f"{v:9.2f}" if v is not None else f"{'-':>9}"
                                                for v in values)
              + f" {r['oil_volume_m3'] * 1e12:8.1f}"
              + (f"{r['out_over_in']:8.2f}" if r.get("out_over_in") is not None else ""))


def _print(result: dict) -> None:
    b = result["balance"]
    last = result["per_transit"][-1]
    if b is None:
        print(f"{result['folder']}: {last['transit']} transits, too few to extrapolate")
        return
    print(f"{result['folder']}: {last['transit']} transits, oil {last['oil_volume_m3'] * 1e12:.1f}"
          f" nl, fill rate {b['fill_rate_last']:.3f} (fit over transits "
          f"{b['fit_transits'][0]}-{b['fit_transits'][1]})")
    print(f"  {'reading':<12}{'oil nl':>8}{'width/a':>9}{'length/a':>10}{'inlet/a':>9}")
    print(f"  {'last':<12}{last['oil_volume_m3'] * 1e12:8.1f}"
          + "".join(f"{last[k]:9.2f}" if last[k] is not None else f"{'-':>9}" for k in METRICS))
    for name in ("linear", "exponential"):
        r = b[name]
        if r is None:
            print(f"  {name:<12}  no balance ahead (fill rate not shrinking)")
            continue
        print(f"  {name:<12}{r['oil_volume_m3'] * 1e12:8.1f}"
              + "".join(f"{r[k]:9.2f}" if r[k] is not None else f"{'-':>9}" for k in METRICS))
    if b["exponential_transits_to_95pc"] is not None:
        print(f"  transits still to run (exponential, 95 % of the oil to come): "
              f"{b['exponential_transits_to_95pc']:.0f}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="+", type=Path, help="case folders with history.csv")
    ap.add_argument("--fit", type=int, default=8, help="last rows fitted (default 8)")
    ap.add_argument("--window", type=float, default=1.0,
                    help="transits per row (default 1; 0.5 for half-transit means)")
    ap.add_argument("--table", action="store_true", help="print the rows too")
    ap.add_argument("--save", help="record name under bench/results/")
    ap.add_argument("--note", default="", help="what the record is (stored with it)")
    args = ap.parse_args(argv)
    if args.fit < 3:
        ap.error(f"--fit: {args.fit}; at least 3 transits are needed")
    if not 0.0 < args.window <= 100.0:
        ap.error(f"--window: {args.window:g}; must be in (0, 100] transits")
    results = [analyse(c, args.fit, args.window) for c in args.cases]
    for r in results:
        if args.table:
            print(r["folder"])
            _print_rows(r)
        _print(r)
    if args.save:
        save(args.save, {"note": args.note, "fit_rows": args.fit, "window_transits": args.window,
                         "cases": results})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
