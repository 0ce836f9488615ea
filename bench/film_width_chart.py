"""The flooded width of 3D runs against the film their mesh lays, and that film against the mesh.

Reads every ``bench/results/film_deposition*.json`` record (``bench/film_deposition.py``: the
deposited fraction f of a rear meniscus on a 2D strip, per in-plane cell size dx and wall
layers) and, for each 3D case folder given, its spec (wall layers, ``size_far``: the cells where
its rear meniscus sits), the width over its last transit and, for a run stopped while still
filling, where it would balance (``bench/fill_extrapolation.py``). Each case is paired with the
strip run of the same wall layers and dx = its size_far. Prints the pairs and draws
OUT.png: left f / LL against dx for each set of wall layers, right the width against the f / LL
of the case's cells.

    python bench/film_width_chart.py OUT.png CASE [CASE ...] [--fit 8]
"""
from __future__ import annotations

import argparse
import json
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.common import RESULTS  # noqa: E402
from bench.fill_extrapolation import analyse  # noqa: E402
from generator.case_spec import Mesh  # noqa: E402
from generator.case_writer import load_spec_of  # noqa: E402


#: a run still filling faster than this (share of the inflow kept) is too far from its balance
#: for the extrapolation: its width is drawn as a lower bound
MAX_FILL_EXTRAPOLATED = 0.1


def strip_table() -> dict[tuple[int, float], dict[float, dict]]:
    """(n_layers, wall_grading) -> dx/a -> the strip row of the nominal case (the longest run
    where repeated; rows with other spec options, e.g. another surface tension, left out)."""
    table: dict[tuple[int, float], dict[float, dict]] = defaultdict(dict)
    for path in sorted(RESULTS.glob("film_deposition*.json")):
        for row in json.loads(path.read_text())["rows"]:
            other = set(row.get("options", {})) - {"mesh.n_layers", "mesh.wall_grading"}
            if row["status"] != "ok" or other:   # the nominal physics only
                continue
            layers = _layers(row)
            old = table[layers].get(row["dx_over_a"])
            if old is None or old["end_time_s"] < row["end_time_s"]:
                table[layers][row["dx_over_a"]] = row
    return table


def _layers(row: dict) -> tuple[int, float]:
    """The strip row's wall layers: its level with the row's n_layers / wall_grading options."""
    overrides = {key.split(".")[-1]: value for key, value in row.get("options", {}).items()}
    level = Mesh(resolution=row["level"], **overrides).level()
    return int(level["n_layers"]), float(level["wall_grading"])


def case_point(case: Path, table: dict, n_fit: int) -> dict:
    """A 3D case's wall layers, size_far, strip f / LL there, and width (last, balance)."""
    level = load_spec_of(case).mesh.level()
    layers = (int(level["n_layers"]), float(level["wall_grading"]))
    dx = level["size_far"]
    rows = table.get(layers, {})
    near = min(rows, key=lambda d: abs(np.log(d / dx)), default=None)
    strip = rows[near] if near is not None and abs(near / dx - 1) < 0.05 else None
    result = analyse(case, n_fit)
    last = result["per_transit"][-1]
    balance = None
    fill = result["balance"]["fill_rate_last"]
    if result["end_reason"] != "steady" and fill < MAX_FILL_EXTRAPOLATED:
        readings = [result["balance"][k] for k in ("linear", "exponential")
                    if result["balance"][k] is not None]
        balance = [r["flooded_width_over_a"] for r in readings] or None
    return {"case": result["folder"], "layers": layers, "size_far": dx,
            "f_over_ll": strip["deposited_over_landau_levich"] if strip else None,
            "width_last": last["flooded_width_over_a"], "width_balance": balance,
            "transits": last["transit"], "end_reason": result["end_reason"],
            "fill_rate_last": fill}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("cases", nargs="+", type=Path)
    ap.add_argument("--fit", type=int, default=8, help="transits fitted for the balance")
    args = ap.parse_args(argv)
    table = strip_table()
    points = [case_point(c, table, args.fit) for c in args.cases]
    for p in points:
        bal = ("" if p["width_balance"] is None
               else " balance " + "-".join(f"{w:.2f}" for w in p["width_balance"]) + " a")
        f = "-" if p["f_over_ll"] is None else f"{p['f_over_ll']:.2f}"
        print(f"{p['case']}: layers {p['layers']}, size_far {p['size_far']:g} a, strip f/LL {f}; "
              f"width {p['width_last']:.2f} a after {p['transits']} transits "
              f"({p['end_reason']}, fill rate {p['fill_rate_last']:.3f}){bal}")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, cost, right) = plt.subplots(1, 3, figsize=(17, 4.8))
    for layers, rows in sorted(table.items()):
        dx = np.array(sorted(rows))
        f = np.array([rows[d]["deposited_over_landau_levich"] for d in dx])
        label = f"{layers[0]} layers, grading {layers[1]:g}"
        left.plot(dx, f, "o-", label=label)
        per_second = [rows[d]["wall_s"] / rows[d]["end_time_s"] for d in dx]
        cost.plot(per_second, np.abs(f - 1.0), "o-", label=label)
    cost.set_xscale("log")
    cost.set_yscale("log")
    cost.set_xlabel("strip wall time per simulated second [s] (1 core, beside other runs)")
    cost.set_ylabel("|films laid / Landau-Levich - 1|")
    cost.set_title("The strip's error against its cost", fontsize=10)
    cost.legend(fontsize=8)
    left.axhline(1.0, color="k", lw=0.8)
    left.set_xscale("log")
    ticks = sorted({d for rows in table.values() for d in rows})
    left.set_xticks(ticks, [f"{d:g}" for d in ticks], fontsize=7)
    left.minorticks_off()
    for p in points:
        left.axvline(p["size_far"], color="0.85", lw=0.8, zorder=0)
    left.set_xlabel("in-plane cell size dx / a on the strip")
    left.set_ylabel("films laid / Landau-Levich")
    left.set_title("Rear meniscus on a 2D strip of the nominal gap\n(grey: the 3D cases' size_far)",
                   fontsize=10)
    left.legend(fontsize=8)
    for p in points:
        if p["f_over_ll"] is None:
            continue
        filling = (p["end_reason"] != "steady"
                   and p["fill_rate_last"] >= MAX_FILL_EXTRAPOLATED)
        right.plot(p["f_over_ll"], p["width_last"], "k^" if filling else "ko")
        if p["width_balance"]:
            right.plot([p["f_over_ll"]] * 2, [min(p["width_balance"]), max(p["width_balance"])],
                       "r_-", ms=10)
        right.annotate(f"{Path(p['case']).name} {p['size_far']:g} a", (p["f_over_ll"],
                       p["width_last"]), fontsize=7, xytext=(4, -10), textcoords="offset points")
    right.axvline(1.0, color="k", lw=0.8)
    right.set_xlabel("films laid by the case's rear cells / Landau-Levich (strip)")
    right.set_ylabel("flooded width / a")
    right.text(0.98, 0.98, "black: last transit (^ still filling fast)\nred: extrapolated balance",
               transform=right.transAxes, ha="right", va="top", fontsize=8)
    right.set_title("3D flooded width against the film its mesh lays", fontsize=10)
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
