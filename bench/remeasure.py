"""A run's writes measured again with today's flow-pattern metrics, beside what its
history.csv recorded while it ran: for histories written before a metric changed (on
2026-11-27 the inlet meniscus began to pass over the air bubbles the oil encloses; before,
a bubble on the axis ahead of the contact was read as the meniscus).

    python bench/remeasure.py CASE [--from T] [--window W] [--save NAME.json]

Every write the ranks left (``processor0/<time>``) from T transits on is read; one that is
not in the case folder is reconstructed there (``reconstructPar -time``, alpha.oil only) and
removed again after reading, so the case is left as it was. Prints each write's inlet
meniscus and width, as recorded and as measured now, and the means over windows of W
transits; writes ``bench/results/NAME.json`` (default remeasure.json).
"""
from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.common import save  # noqa: E402
from ehlfoam.case.geometry import load_geometry
from ehlfoam.run import fields as case_fields
from ehlfoam.metrics import pattern as metrics
from ehlfoam.metrics.convergence import history_number, read_history_rows
from ehlfoam.foam.runtime import FoamRuntime

KEYS = ("inlet_meniscus_distance_over_a", "inlet_meniscus_shape", "flooded_width_over_a",
        "enclosed_bubbles")


def rank_times(case: Path) -> list[str]:
    """The time folders the ranks wrote (processor0), as named, in time order (the case's
    own time folders where it ran on one rank)."""
    where = case / "processor0" if (case / "processor0").is_dir() else case
    return [folder.name for _, folder in case_fields.time_folders(where)]


def measure(case: Path, name: str, structure: case_fields.Structure, geom,
            runtime: FoamRuntime | None) -> dict:
    """The flow pattern of the write ``name`` by today's metrics, reconstructing its
    alpha.oil into the case folder for the reading if it is not there."""
    folder = case / name
    made = not folder.is_dir()
    if made:
        with tempfile.NamedTemporaryFile(suffix=".log") as log:
            runtime.run("reconstructPar", ["-time", name, "-fields", "(alpha.oil)"], cwd=case,
                        log_path=log.name)
    try:
        mid = case_fields.mid_gap_alpha(folder, structure, geom)
    finally:
        if made:
            shutil.rmtree(folder)
    return metrics.flow_pattern_from_raster(case_fields.column_raster(mid, structure, geom))


def window_means(rows: list[dict], span: float) -> list[dict]:
    """Means of the recorded and re-measured inlet meniscus and width over consecutive
    windows of ``span`` s (from the first row's time), None where a window has no value."""
    t0 = rows[0]["time_s"]
    out = {}
    for row in rows:
        out.setdefault(int((row["time_s"] - t0) / span + 1e-9), []).append(row)
    means = []
    for k, group in sorted(out.items()):
        m = {"from_s": t0 + k * span, "to_s": t0 + (k + 1) * span, "writes": len(group)}
        for key in ("recorded_inlet", "inlet", "recorded_width", "width"):
            vals = [g[key] for g in group if g[key] is not None]
            m[key] = float(np.mean(vals)) if vals else None
        means.append(m)
    return means


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case")
    ap.add_argument("--from", dest="start", type=float, default=0.0, metavar="T",
                    help="first write to read, in transits (default 0: all)")
    ap.add_argument("--window", type=float, default=0.5, metavar="W",
                    help="transits a window of means spans (default 0.5)")
    ap.add_argument("--save", default="remeasure.json")
    args = ap.parse_args(argv)
    case = Path(args.case).absolute()
    if not (case / "history.csv").is_file():
        ap.error(f"case = {args.case}: no history.csv there (not a run case)")
    if not args.window > 0:
        ap.error(f"--window = {args.window}: must be > 0 transits")
    geom = load_geometry(case)
    structure = case_fields.Structure.load(case)
    recorded = {round(float(r["time_s"]), 9): r for r in read_history_rows(case)}
    names = [n for n in rank_times(case) if float(n) >= args.start * geom.transit_time]
    runtime = FoamRuntime.from_environment() if (case / "processor0").is_dir() else None
    rows = []
    print("time_s     transits  inlet: recorded -> now      width: recorded -> now   bubbles")
    for name in names:
        now = measure(case, name, structure, geom, runtime)
        old = recorded.get(round(float(name), 9), {})
        row = {"time_s": float(name), "transits": float(name) / geom.transit_time,
               "recorded_inlet": history_number(old.get("inlet_meniscus_distance_over_a")),
               "inlet": now["inlet_meniscus_distance_over_a"],
               "recorded_shape": old.get("inlet_meniscus_shape") or None,
               "shape": now["inlet_meniscus_shape"],
               "recorded_width": history_number(old.get("flooded_width_over_a")),
               "width": now["flooded_width_over_a"],
               "enclosed_bubbles": now["enclosed_bubbles"]}
        rows.append(row)
        print(f"{row['time_s']:.6f}  {row['transits']:7.3f}  "
              f"{_fmt(row['recorded_inlet'])} -> {_fmt(row['inlet'])} {row['shape'] or '-':8s}"
              f"  {_fmt(row['recorded_width'])} -> {_fmt(row['width'])}"
              f"  {row['enclosed_bubbles']}")
    if not rows:
        ap.error(f"--from = {args.start}: no write of {args.case} from there on")
    means = window_means(rows, args.window * geom.transit_time)
    print(f"means over {args.window:g} transits: inlet recorded -> now, width recorded -> now")
    for m in means:
        print(f"  {m['from_s'] / geom.transit_time:6.2f}-{m['to_s'] / geom.transit_time:.2f}"
              f" ({m['writes']:3d} writes)  {_fmt(m['recorded_inlet'])} -> {_fmt(m['inlet'])}"
              f"   {_fmt(m['recorded_width'])} -> {_fmt(m['width'])}")
    path = save(args.save, {"case": str(case), "window_transits": args.window,
                            "writes": rows, "means": means})
    print(f"wrote {path}")
    return 0


def _fmt(v: float | None) -> str:
    return "   -  " if v is None else f"{v:6.3f}"


if __name__ == "__main__":
    raise SystemExit(main())
