"""What a 3D case costs per mesh level: cells, time steps and wall time to steady state, with
the flow-pattern metrics each level gives.

    python bench/case_cost.py [SPEC] [--levels coarse medium fine] [--set KEY=VALUE ...]
        [--sequence] [--work DIR] [--out FILE.json]
    python bench/case_cost.py --quick

Each level of the case spec (default: the nominal contact at 8 mm/s with 2 um layers on
each wall on a 0.3 mm track, 4 transits at most, one hour of wall time at most) is written
and run to steady state (``ehlfoam case`` + ``ehlfoam run``), one after the other, on the
spec's ``run.n_procs`` ranks. ``--sequence`` starts each level from the previous level's
final fields (interpolated onto its mesh): grid sequencing, the way to a fine level's steady
state without paying for its whole transient. The table gives each level's cells, steps,
simulated time, the solver's CPU time and the wall time, the ratios of cells and wall time to
the previous level, how the run ended, the state, the inlet meniscus and the flooded region;
the metrics' change from level to level is their mesh convergence. ``--quick``: the coarse and
medium levels' in-plane cells on a small domain with 3 layers, 1 ms of flow (seconds).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from common import (add_output_options, print_table, ratios, solver_cpu_s, spec_option,
                    work_folder, write_out)
from ehlfoam.case.geometry import load_geometry
from ehlfoam.run.monitor import run_case
from ehlfoam.seed.follow import write_started_case
from ehlfoam.spec.case import load_case_spec, make_case_spec

#: the default case: the nominal contact with thin layers (docs' cost figures)
BASE = {"contact": {"speed": 0.008},
        "supply": {"mode": "layers", "disc_layer": 2e-6, "ball_layer": 2e-6,
                   "track_half_width": 3e-4},
        "run": {"wall_limit": 3600.0, "transits_max": 4.0}}
#: --quick: a small domain, 3 layers, a cheap precalc, 1 ms of flow
QUICK = {"contact.grid": 129, "contact.tol_residual": 1e-4, "contact.speed": 0.02,
         "mesh.n_layers": 3, "mesh.wall_grading": 3.0, "domain.upstream": 5.0,
         "domain.downstream": 7.0, "domain.side": 5.0, "supply.disc_layer": 3e-6,
         "supply.ball_layer": 3e-6, "supply.track_half_width": 2.5e-4,
         "supply.initial_puddle": 3.0, "run.end_time": 1e-3, "run.writes_per_transit": 1000}
BASE_NAME, QUICK_NAME = "nominal, 2 um layers", "quick: a small domain, 3 layers, 1 ms"
KEYS = ("state", "inlet_meniscus_distance_over_a", "flooded_length_over_a",
        "flooded_width_over_a", "oil_mass_balance_error", "steady", "end_reason", "cells",
        "time_steps", "simulated_time_s", "wall_s", "wall_s_per_simulated_ms")


def run_level(spec_path: str | None, overrides: dict, level: str, case: Path,
              previous: Path | None) -> dict:
    """Write the level's case (started from ``previous``'s final fields if given), run it,
    and return its row: build and run times, the solver's CPU time, the largest step and
    the metrics of :data:`KEYS`."""
    overrides = {**overrides, "mesh.resolution": level}
    spec = (load_case_spec(spec_path, **overrides) if spec_path
            else make_case_spec(BASE, **overrides))
    t0 = time.perf_counter()
    write_started_case(spec, case, previous, overwrite=True)
    build_s = time.perf_counter() - t0
    m = run_case(case)
    return {"level": level, "started_from": None if previous is None else previous.name,
            "build_s": build_s, "solver_cpu_s": solver_cpu_s(case),
            "max_delta_t_s": load_geometry(case).max_delta_t,
            "transits": m.get("simulated_time_s", 0.0) / load_geometry(case).transit_time,
            **{k: m.get(k) for k in KEYS}}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("spec", nargs="?", default=None,
                    help="case spec TOML (default: the nominal contact with 2 um layers)")
    ap.add_argument("--levels", nargs="+", default=["coarse", "medium", "fine"],
                    choices=["coarse", "medium", "fine"])
    ap.add_argument("--set", action="append", default=[], type=spec_option,
                    metavar="KEY=VALUE", help="a spec option for every level (repeatable)")
    ap.add_argument("--sequence", action="store_true",
                    help="each level starts from the previous level's final fields")
    add_output_options(ap, work=True)
    args = ap.parse_args(argv)
    overrides = dict(args.set)
    if args.quick:
        args.levels, overrides = ["coarse", "medium"], {**QUICK, **overrides}
    rows = []
    with work_folder(args.work) as work:
        for i, level in enumerate(args.levels):
            previous = work / args.levels[i - 1] if i and args.sequence else None
            rows.append(run_level(args.spec, overrides, level, work / level, previous))
            print(f"{level}: {rows[-1]['cells']} cells, {rows[-1]['time_steps']} steps, "
                  f"{rows[-1]['wall_s']:.1f} s, {rows[-1]['end_reason']}", flush=True)
    ratios(rows, "cells", "cells_ratio")
    ratios(rows, "wall_s", "wall_ratio")
    print_table(rows, [
        ("level", "level", ""), ("started_from", "from", ""), ("cells", "cells", "d"),
        ("cells_ratio", "x cells", ".2f"), ("time_steps", "steps", "d"),
        ("transits", "transits", ".2f"), ("solver_cpu_s", "CPU [s]", ".1f"),
        ("wall_s", "wall [s]", ".1f"), ("wall_ratio", "x wall", ".2f"),
        ("end_reason", "end", ""), ("state", "state", ""),
        ("inlet_meniscus_distance_over_a", "inlet [a]", ".3f"),
        ("flooded_width_over_a", "width [a]", ".3f"),
        ("flooded_length_over_a", "length [a]", ".3f")],
        f"case cost per level ({args.spec or (QUICK_NAME if args.quick else BASE_NAME)})")
    write_out(args.out, {"spec": args.spec, "set": overrides, "sequence": args.sequence,
                         "rows": rows})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
