"""Flow pattern against the oil supply at two speeds (state I / II, inlet meniscus shape).

    python bench/supply_sweep.py [--speeds 0.008 0.017] [--layers 0.5e-6 1e-6 2e-6 4e-6]
        [--flooded] [--level coarse] [--jobs 2] [--work DIR] [--tag _SUFFIX]

Each case: the reference contact (HVI60, 40 C, 20 N) at the speed, oil layers of the given
thickness on disc and ball over a track of half-width --track, run to steady state or
--transits transit times. Writes ``bench/results/supply_sweep_<level><tag>.json`` and a table.
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from ehlfoam.spec.case import make_case_spec
from ehlfoam.case.writer import write_case
from ehlfoam.run.monitor import run_case

RESULTS = ROOT / "bench" / "results"
KEYS = ("state", "inlet_meniscus_distance_over_a", "inlet_meniscus_shape",
        "flooded_length_over_a", "flooded_width_over_a", "wake_gas_length_over_a",
        "wake_open", "inlet_starved", "oil_volume_m3", "oil_inflow_m3_s", "oil_outflow_m3_s",
        "oil_mass_balance_error", "contact_flow_over_inflow", "steady", "end_reason",
        "cells", "time_steps", "simulated_time_s", "wall_s")


def one(job) -> dict:
    speed, layer, args = job
    supply = ({"mode": "flooded", "track_half_width": args.track} if layer == "flooded" else
              {"mode": "layers", "disc_layer": layer, "ball_layer": layer,
               "track_half_width": args.track})
    tag = "flooded" if layer == "flooded" else f"{layer * 1e6:g}um"
    spec = make_case_spec({"name": f"u{speed * 1e3:g}_{tag}", "contact": {"speed": speed},
                           "mesh": {"resolution": args.level}, "supply": supply,
                           "run": {"transits_max": args.transits,
                                   "wall_limit": args.wall_limit}})
    case = Path(args.work) / args.level / spec.name
    if (case / "metrics.json").is_file() and not args.rerun:
        m = json.loads((case / "metrics.json").read_text())
        if m.get("status") in ("finished", "failed"):
            return {"speed_m_s": speed, "layer_m": layer, **{k: m.get(k) for k in KEYS}}
    write_case(spec, case, overwrite=True)
    m = run_case(case)
    return {"speed_m_s": speed, "layer_m": layer, **{k: m.get(k) for k in KEYS}}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speeds", nargs="+", type=float, default=[0.008, 0.017])
    ap.add_argument("--layers", nargs="+", type=float, default=[0.5e-6, 1e-6, 2e-6, 4e-6])
    ap.add_argument("--flooded", action="store_true", help="add a flooded-track case per speed")
    ap.add_argument("--track", type=float, default=3e-4, help="track half-width [m]")
    ap.add_argument("--level", default="coarse")
    ap.add_argument("--transits", type=float, default=4.0)
    ap.add_argument("--wall-limit", type=float, default=3600.0)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--rerun", action="store_true", help="recompute finished cases")
    ap.add_argument("--work", default=str(ROOT / "runs" / "bench" / "supply_sweep"))
    ap.add_argument("--tag", default="", help="suffix of the results file (keeps earlier ones)")
    args = ap.parse_args(argv)
    layers = list(args.layers) + (["flooded"] if args.flooded else [])
    jobs = [(s, lay, args) for s, lay in itertools.product(args.speeds, layers)]
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        rows = list(pool.map(one, jobs))
    RESULTS.mkdir(parents=True, exist_ok=True)
    out = RESULTS / f"supply_sweep_{args.level}{args.tag}.json"
    out.write_text(json.dumps({"args": {k: v for k, v in vars(args).items()}, "rows": rows},
                              indent=2, default=str) + "\n")
    head = ("speed_m_s", "layer_m", "state", "inlet_meniscus_distance_over_a",
            "inlet_meniscus_shape", "flooded_width_over_a", "wake_gas_length_over_a",
            "end_reason", "oil_mass_balance_error", "wall_s")
    print(" | ".join(head))
    for r in rows:
        print(" | ".join(f"{r.get(k):.4g}" if isinstance(r.get(k), float) else str(r.get(k))
                         for k in head))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
