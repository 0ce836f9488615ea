"""The flooded width of 3D runs against the film their mesh lays, and that film against the mesh.

Reads every ``bench/results/film_deposition*.json`` record (``bench/film_deposition.py``: the
deposited fraction f of a rear meniscus on a 2D strip, per in-plane cell size dx, wall layers
and interface schemes) and, for each 3D case folder given, its spec (wall layers, schemes, the
cells where its rear meniscus crosses y = 0: ``size_far`` or a ``mesh.refine`` box's), the
width over its last transit and, for a run stopped while still filling, where it would
balance (``bench/fill_extrapolation.py``). Each case is paired with the strip run of the same
wall layers, schemes and dx = its rear cells. Prints the pairs and draws
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
from bench.film_deposition import FILM  # noqa: E402
from ehlfoam.spec.case import CaseSpec
from ehlfoam.spec.mesh import Mesh
from ehlfoam.case.geometry import load_spec_of
from ehlfoam.run.monitor import rear_meniscus_cell


#: a run still filling (or draining) faster than this (share of the inflow kept) is too far
#: from its balance for the extrapolation: its width is drawn as a bound
MAX_FILL_EXTRAPOLATED = 0.1


#: strip options a row may carry and still be the nominal physics: the wall layers, and the
#: interface schemes with the sub-cycles and capillary safety that go with the balanced set
MESH_OPTIONS = {"mesh.n_layers", "mesh.wall_grading"}
SCHEME_OPTIONS = {"physics.interface_schemes", "run.alpha_subcycles", "run.capillary_safety"}

#: a 3D case takes the strip row whose dx is within this share of its rear cells (the medium
#: level's rear meniscus sits in 0.51 a cells, its strip ran at size_far, 0.55 a)
PAIRING = 0.1

#: a strip series: (n_layers, wall_grading, interface schemes)
Series = tuple[int, float, str]


def strip_table() -> dict[Series, dict[float, dict]]:
    """(n_layers, wall_grading, schemes) -> dx/a -> the strip row of the nominal case (the
    longest run where repeated; rows with other spec options, e.g. another surface tension,
    left out)."""
    table: dict[Series, dict[float, dict]] = defaultdict(dict)
    for path in sorted(RESULTS.glob("film_deposition*.json")):
        record = json.loads(path.read_text())
        if float(record["args"].get("film", FILM)) != FILM:
            continue    # fed at another rate: its meniscus sits at another gap
        for row in record["rows"]:
            other = set(row.get("options", {})) - MESH_OPTIONS - SCHEME_OPTIONS
            if row["status"] != "ok" or other:   # the nominal physics only
                continue
            series = _series(row)
            old = table[series].get(row["dx_over_a"])
            if old is None or old["end_time_s"] < row["end_time_s"]:
                table[series][row["dx_over_a"]] = row
    return table


def _series(row: dict) -> Series:
    """The strip row's wall layers (its level with the row's n_layers / wall_grading options)
    and interface schemes."""
    options = row.get("options", {})
    overrides = {key.split(".")[-1]: value for key, value in options.items()
                 if key in MESH_OPTIONS}
    level = Mesh(resolution=row["level"], **overrides).level()
    schemes = options.get("physics.interface_schemes", "standard")
    return int(level["n_layers"]), float(level["wall_grading"]), schemes


def rear_cell_size(spec: CaseSpec, last: dict) -> float:
    """The in-plane cell size (a) where the case's rear meniscus crosses y = 0 over its last
    transit: size_far, or a refinement box's cells there."""
    x_rear = -1.0 - last["inlet_meniscus_distance_over_a"] + last["flooded_length_over_a"]
    return rear_meniscus_cell(spec, {"state": "I", "flooded_x_max_over_a": x_rear})


def case_point(case: Path, table: dict, n_fit: int) -> dict:
    """A 3D case's wall layers, rear cells, strip f / LL there, and width (last, balance)."""
    spec = load_spec_of(case)
    level = spec.mesh.level()
    layers = (int(level["n_layers"]), level["wall_grading"])  # None under one wall cell
    result = analyse(case, n_fit)
    last = result["per_transit"][-1]
    dx = rear_cell_size(spec, last)
    rows = table.get((*layers, spec.physics.interface_schemes), {})
    near = min(rows, key=lambda d: abs(np.log(d / dx)), default=None)
    strip = rows[near] if near is not None and abs(near / dx - 1) < PAIRING else None
    balance = None
    fill = last["fill_rate"]
    if (result["balance"] is not None and result["end_reason"] != "steady"
            and abs(fill) < MAX_FILL_EXTRAPOLATED):
        readings = [result["balance"][k] for k in ("linear", "exponential")
                    if result["balance"][k] is not None]
        balance = [r["flooded_width_over_a"] for r in readings] or None
    return {"case": result["folder"], "layers": layers, "rear_dx": dx,
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
        print(f"{p['case']}: layers {p['layers']}, rear cells {p['rear_dx']:.2g} a, "
              f"strip f/LL {f}; width {p['width_last']:.2f} a after {p['transits']} transits "
              f"({p['end_reason']}, fill rate {p['fill_rate_last']:.3f}){bal}")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, cost, right) = plt.subplots(1, 3, figsize=(17, 4.8))
    for (n_layers, grading, schemes), rows in sorted(table.items()):
        dx = np.array(sorted(rows))
        f = np.array([rows[d]["deposited_over_landau_levich"] for d in dx])
        label = f"{n_layers} layers, grading {grading:g}, {schemes}"
        style = "o-" if schemes == "standard" else "s--"
        left.plot(dx, f, style, label=label)
        per_second = [rows[d]["wall_s"] / rows[d]["end_time_s"] for d in dx]
        cost.plot(per_second, np.abs(f - 1.0), style, label=label)
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
        left.axvline(p["rear_dx"], color="0.85", lw=0.8, zorder=0)
    left.set_xlabel("in-plane cell size dx / a on the strip")
    left.set_ylabel("films laid / Landau-Levich")
    left.set_title("Rear meniscus on a 2D strip of the nominal gap\n"
                   "(grey: the 3D cases' rear cells)", fontsize=10)
    left.legend(fontsize=8)
    for p in points:
        if p["f_over_ll"] is None:
            continue
        filling = (p["end_reason"] != "steady"
                   and abs(p["fill_rate_last"]) >= MAX_FILL_EXTRAPOLATED)
        right.plot(p["f_over_ll"], p["width_last"], "k^" if filling else "ko")
        if p["width_balance"]:
            right.plot([p["f_over_ll"]] * 2, [min(p["width_balance"]), max(p["width_balance"])],
                       "r_-", ms=10)
        right.annotate(f"{Path(p['case']).name} {p['rear_dx']:.2g} a, {p['layers'][0]} layers",
                       (p["f_over_ll"],
                       p["width_last"]), fontsize=7, xytext=(4, -10), textcoords="offset points")
    right.axvline(1.0, color="k", lw=0.8)
    right.set_xlabel("films laid by the case's rear cells / Landau-Levich (strip)")
    right.set_ylabel("flooded width / a")
    right.text(0.98, 0.98, "black: last transit (^ still filling or draining fast)\n"
               "red: extrapolated balance",
               transform=right.transAxes, ha="right", va="top", fontsize=8)
    right.set_title("3D flooded width against the film its mesh lays", fontsize=10)
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
