"""Cost and mesh convergence of a thin-gap case: cells, time steps and wall time to steady
state per resolution level, with the flow-pattern metrics each level gives.

    python bench/case_bench.py [--levels coarse medium fine] [--speed 0.008]
        [--supply layers --layer 2e-6 --track 3e-4] [--jobs 2] [--wall-limit 3600]
        [--sequence] [--start-from LEVEL|CASE|FILE.npz] [--procs N] [--set KEY=VALUE ...]
        [--collect]

Each level runs serially (one core; ``--procs`` ranks with mpirun); ``--jobs`` runs levels side
by side. ``--sequence`` runs the levels one after the other, each starting from the previous
level's final fields (interpolated onto its mesh, runs/field_mapping.py): grid sequencing, the
way to reach a fine level's steady state without paying for its whole transient. Writes
``bench/results/case_bench_<tag>.json`` and prints a table. The metrics' change from level to
level is the mesh-convergence figure of the inlet meniscus distance and the flooded width.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from ehlfoam.spec.case import make_case_spec
from ehlfoam.case.geometry import load_geometry
from common import apply_edits, foam_edit, solver_cpu_s, spec_option  # noqa: E402
from ehlfoam.seed.follow import write_started_case
from ehlfoam.run.monitor import run_case

RESULTS = ROOT / "bench" / "results"
KEYS = ("state", "inlet_meniscus_distance_over_a", "inlet_meniscus_shape",
        "flooded_length_over_a", "flooded_width_over_a", "wake_gas_length_over_a",
        "oil_volume_m3", "oil_mass_balance_error", "steady", "end_reason", "cells",
        "time_steps", "simulated_time_s", "wall_s", "wall_s_per_simulated_ms",
        "ramp_start_method")


def one(level: str, args: argparse.Namespace, previous: str | None = None) -> dict:
    """Build and run ``level``; started from the final fields of the level ``previous`` (a
    sibling case) when given."""
    spec = make_case_spec({
        "name": f"bench-{level}", "contact": {"speed": args.speed},
        "mesh": {"resolution": level},
        "supply": {"mode": args.supply, "disc_layer": args.layer, "ball_layer": args.layer,
                   "track_half_width": args.track},
        "run": {"wall_limit": args.wall_limit, "transits_max": args.transits,
                "n_procs": args.procs}}, **dict(args.set))
    case = Path(args.work) / args.tag / level
    t0 = time.perf_counter()
    write_started_case(spec, case, None if previous is None else case.parent / previous,
                       overwrite=True)   # with mesh.follow, along the source's meniscus
    apply_edits(case, args.edit)
    build_s = time.perf_counter() - t0
    run_case(case)
    return row_of(case, level, previous, build_s)


def start_case(folder: Path, given: str) -> str:
    """What ``--start-from`` names, as :func:`one` joins it to the tag's ``folder``: a level
    already run there (a sibling case) if there is one of that name, else the path ``given``
    (relative to the working directory) of any finished case, case snapshot or thin-film
    state (.npz), made absolute."""
    if (folder / given).is_dir() or not Path(given).exists():
        return given
    return str(Path(given).resolve())


def row_of(case: Path, level: str, previous: str | None, build_s: float | None = None) -> dict:
    """The table row of a run case (its metrics.json and the solver's CPU time)."""
    m = json.loads((case / "metrics.json").read_text())
    return {"level": level, "started_from": previous, "build_s": build_s,
            "max_delta_t_s": load_geometry(case).max_delta_t, "solver_cpu_s": solver_cpu_s(case),
            **{k: m.get(k) for k in KEYS}}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", nargs="+", default=["coarse", "medium", "fine"])
    ap.add_argument("--speed", type=float, default=0.008, help="rolling speed [m/s]")
    ap.add_argument("--supply", choices=["layers", "flooded"], default="layers")
    ap.add_argument("--layer", type=float, default=2e-6, help="oil layer on each surface [m]")
    ap.add_argument("--track", type=float, default=3e-4, help="track half-width [m]")
    ap.add_argument("--transits", type=float, default=4.0, help="time limit in transits")
    ap.add_argument("--wall-limit", type=float, default=3600.0)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--tag", default="nominal")
    ap.add_argument("--sequence", action="store_true",
                    help="each level starts from the previous level's final fields")
    ap.add_argument("--procs", type=int, default=1, help="MPI ranks per case")
    ap.add_argument("--start-from", default=None, metavar="LEVEL|CASE|FILE.npz",
                    help="the first level starts from the final fields of LEVEL, already run "
                         "under --tag (grid sequencing without re-running LEVEL), or of the "
                         "finished case at the path CASE (another tag, another mesh), or "
                         "of a case snapshot FILE.npz (`ehlfoam snapshot`), or the oil of "
                         "the thin-film state FILE.npz")
    ap.add_argument("--collect", action="store_true",
                    help="only tabulate the levels already run under --tag")
    ap.add_argument("--set", action="append", default=[], type=spec_option, metavar="KEY=VALUE",
                    help="a spec option, e.g. run.max_courant=1 or supply.initial_puddle=5 "
                         "(repeatable)")
    ap.add_argument("--edit", action="append", default=[], type=foam_edit,
                    metavar="FILE:KEY/SUBKEY=VALUE",
                    help="change an entry of a system/ file of every case (e.g. "
                         "fvSchemes:snGradSchemes/default=uncorrected): to measure what the "
                         "spec does not offer")
    ap.add_argument("--work", default=str(ROOT / "runs" / "bench"))
    args = ap.parse_args(argv)
    previous = {level: (args.levels[i - 1] if i and args.sequence else None)
                for i, level in enumerate(args.levels)}
    if args.start_from:
        previous[args.levels[0]] = start_case(Path(args.work) / args.tag, args.start_from)
    if args.collect:
        rows = [row_of(Path(args.work) / args.tag / level, level, previous[level])
                for level in args.levels
                if (Path(args.work) / args.tag / level / "metrics.json").is_file()]
    elif args.sequence or args.start_from:
        rows = [one(level, args, previous[level]) for level in args.levels]
    else:
        with ProcessPoolExecutor(max_workers=args.jobs) as pool:
            rows = list(pool.map(one, args.levels, [args] * len(args.levels)))
    RESULTS.mkdir(parents=True, exist_ok=True)
    out = RESULTS / f"case_bench_{args.tag}.json"
    out.write_text(json.dumps({"args": vars(args), "rows": rows}, indent=2) + "\n")
    head = ("level", "started_from", "cells", "time_steps", "simulated_time_s", "solver_cpu_s",
            "wall_s", "end_reason", "state",
            "inlet_meniscus_distance_over_a", "flooded_width_over_a", "flooded_length_over_a")
    print(" | ".join(head))
    for r in rows:
        print(" | ".join(f"{r.get(k):.4g}" if isinstance(r.get(k), float) else str(r.get(k))
                         for k in head))
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
