"""The 2D strips: the films a receding meniscus lays against Landau-Levich, and the apparent
angle of a contact line that dry walls advance, per in-plane cell size and level.

    python bench/strips.py [films|contact-line|both] [--levels L ...] [--dx DX ...]
        [--time T] [--writes N] [--set KEY=VALUE ...] [--work DIR] [--out FILE.json]
    python bench/strips.py --quick

Both run the strip of ``ehlfoam.case.strip`` (one cell wide, along y = 0 of the nominal gap,
the level's wall layers and capillary step at the strip's cells dx [a]) in interFoam:

- **films** (default dx 0.8 .. 0.05 a, coarse level, 1 s, 50 writes): both walls at u away
  from the contact, fed all-oil at x = 3 a at u * 4 um, a bridge up to where Landau-Levich's
  films balance that feed (10.3 a). The table gives the films the rear meniscus lays over the
  gap there, f (median over the last 40 % of the run), f / LL, and where the meniscus would
  balance with them (x*, beside LL's);
- **contact-line** (default dx 0.2 .. 0.025 a, fine level, 0.3 s, 30 writes): the walls
  turned round (-u), coming in dry at x = 10 a and advancing into a bridge up to 6.3 a that a
  reservoir at ambient pressure feeds at 4 a. Where the meniscus comes to rest gives the
  apparent angle that balances the walls' drag (``ehlfoam.thinfilm.bridge``), beside the
  static angle's position and Cox-Voinov's angle with the cell as the slip length; the wall
  cells' stall, air and pressure at the end (``ehlfoam.metrics.strip.wall_rows``).

``--quick``: each on the coarse level's walls, one cell size, a few ms (seconds).
"""

from __future__ import annotations

import argparse
import itertools
import time
from pathlib import Path

import numpy as np

from common import add_output_options, print_table, spec_option, work_folder, write_out
from ehlfoam.case.strip import reverse_walls, strip_mesh, write_strip_case
from ehlfoam.foam.runtime import FoamRuntime
from ehlfoam.gap.source import load_gap
from ehlfoam.metrics.strip import film_history, wall_rows
from ehlfoam.run.fields import time_folders
from ehlfoam.spec.case import CaseSpec, make_case_spec
from ehlfoam.thinfilm.bridge import (angle_at_meniscus, bridge_balance, cox_voinov,
                                     meniscus_for_angle, x_at_gap)
from ehlfoam.thinfilm.problem import landau_levich

#: each strip's defaults: cells [a], levels, time [s], writes; and its --quick
DEFAULTS = {"films": dict(dx=[0.8, 0.4, 0.2, 0.1, 0.05], levels=["coarse"], time=1.0,
                          writes=50),
            "contact-line": dict(dx=[0.2, 0.1, 0.05, 0.025], levels=["fine"], time=0.3,
                                 writes=30)}
QUICK = {"films": dict(dx=[0.4], levels=["coarse"], time=0.15, writes=5),
         "contact-line": dict(dx=[0.2], levels=["coarse"], time=0.02, writes=4)}
FILM = 4e-6                    # m: the feed, carried in at u; LL balances it at 10.3 a
FILMS_X, LINE_X, BRIDGE = (3.0, 16.0), (4.0, 10.0), 6.3      # a


def run_strip(case: Path, runtime: FoamRuntime) -> dict:
    """Run a written strip: its status, steps and wall time [s]."""
    t0 = time.perf_counter()
    proc = runtime.run("interFoam", cwd=case, log_path=case / "log.interFoam", check=False)
    return {"status": "ok" if proc.returncode == 0 else "failed",
            "steps": proc.stdout.count("\nTime = "), "wall_s": time.perf_counter() - t0}


def late(rows: list[dict], end: float) -> list[dict]:
    """The writes of the last 40 % of a run that ended at ``end`` [s]."""
    return [r for r in rows if r["t_s"] >= 0.6 * end]


def films(spec: CaseSpec, gap, level: str, dx: float, case: Path, opts: dict,
          runtime: FoamRuntime) -> dict:
    """One film strip: its row of the table."""
    a = spec.a
    x_in, x_out = FILMS_X[0] * a, FILMS_X[1] * a
    ll = landau_levich(spec.oil_viscosity, spec.speed, spec.physics.surface_tension)
    x_ll = x_at_gap(gap, FILM / ll, x_in, x_out)
    mesh = strip_mesh(spec, gap, x_in, x_out, dx * a)
    write_strip_case(spec, case, mesh, x_ll, FILM, dx * a, opts["time"],
                     opts["time"] / opts["writes"])
    run = run_strip(case, runtime)
    rows = film_history(time_folders(case), mesh, a, x_out)
    tail = late(rows, opts["time"])
    f = float(np.median([r["deposited_fraction"] for r in tail])) if tail else float("nan")
    return {"level": level, "dx_over_a": dx, "cells": mesh.n_cells, **run,
            "landau_levich": ll, "deposited_fraction": f, "over_landau_levich": f / ll,
            "x_rear_last_over_a": rows[-1]["x_rear_over_a"] if rows else None,
            "x_balance_over_a": x_at_gap(gap, FILM / f if f > 0 else float("nan"), x_in,
                                         3 * x_out) / a,
            "x_landau_levich_over_a": x_ll / a, "writes": rows}


def contact_line(spec: CaseSpec, gap, level: str, dx: float, case: Path, opts: dict,
                 runtime: FoamRuntime) -> dict:
    """One contact-line strip: its row of the table."""
    a = spec.a
    x_in, x_out = LINE_X[0] * a, LINE_X[1] * a
    mesh = strip_mesh(spec, gap, x_in, x_out, dx * a)
    write_strip_case(spec, case, mesh, BRIDGE * a, 0.0, dx * a, opts["time"],
                     opts["time"] / opts["writes"])
    reverse_walls(spec, case, mesh=mesh)
    run = run_strip(case, runtime)
    rows = film_history(time_folders(case), mesh, a, x_out)
    balance = bridge_balance(spec, gap, x_in, x_out)
    tail = late(rows, opts["time"])
    x_m = float(np.median([r["x_rear_over_a"] for r in tail])) if tail else float("nan")
    drift = tail[-1]["x_rear_over_a"] - tail[0]["x_rear_over_a"] if tail else float("nan")
    h_m = float(np.interp(x_m * a, balance.x, balance.h))
    ca = spec.oil_viscosity * spec.speed / spec.physics.surface_tension
    walls = wall_rows(time_folders(case)[-1][1], mesh, spec.wall_speed, x_m * a, 0.5 * a)
    return {"level": level, "dx_over_a": dx, "cells": mesh.n_cells, **run,
            "meniscus_over_a": x_m, "drift_over_a": drift, "gap_at_meniscus_m": h_m,
            "apparent_angle_deg": angle_at_meniscus(spec, balance, x_m * a),
            "static_angle_deg": spec.physics.contact_angle,
            "static_meniscus_over_a":
                meniscus_for_angle(spec, balance, spec.physics.contact_angle) / a,
            "cox_voinov_deg": cox_voinov(spec.physics.contact_angle, ca, h_m / (dx * a)),
            **walls, "writes": rows}


def sweep(kind: str, args: argparse.Namespace, work: Path, runtime: FoamRuntime) -> list[dict]:
    """Every level x dx of one strip."""
    opts = {**(QUICK if args.quick else DEFAULTS)[kind],
            **{k: v for k, v in (("dx", args.dx), ("levels", args.levels),
                                 ("time", args.time), ("writes", args.writes)) if v}}
    measure = films if kind == "films" else contact_line
    rows = []
    for level, dx in itertools.product(opts["levels"], opts["dx"]):
        spec = make_case_spec({"mesh": {"resolution": level}}, **dict(args.set))
        gap, _ = load_gap(spec.contact)
        rows.append(measure(spec, gap, level, dx, work / f"{kind}_{level}_dx{dx:g}", opts,
                            runtime))
        print(f"{kind}: {level}, dx {dx:g} a, {rows[-1]['cells']} cells, "
              f"{rows[-1]['steps']} steps, {rows[-1]['wall_s']:.1f} s", flush=True)
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("which", nargs="?", default="both", choices=["films", "contact-line", "both"])
    ap.add_argument("--levels", nargs="+", choices=["coarse", "medium", "fine"],
                    help="levels whose wall layers and capillary step are used")
    ap.add_argument("--dx", nargs="+", type=float, help="in-plane cell sizes [a]")
    ap.add_argument("--time", type=float, help="simulated time [s]")
    ap.add_argument("--writes", type=int, help="writes over the run")
    ap.add_argument("--set", action="append", default=[], type=spec_option,
                    metavar="KEY=VALUE", help="a spec option (e.g. mesh.n_layers=20)")
    add_output_options(ap, work=True)
    args = ap.parse_args(argv)
    for name in ("time", "writes"):
        value = getattr(args, name)
        if value is not None and not value > 0:
            ap.error(f"--{name} {value}: valid range > 0")
    runtime = FoamRuntime.from_environment()
    kinds = ["films", "contact-line"] if args.which == "both" else [args.which]
    out = {}
    with work_folder(args.work) as work:
        for kind in kinds:
            out[kind] = sweep(kind, args, work, runtime)
    if "films" in out:
        print_table(out["films"], [
            ("level", "level", ""), ("dx_over_a", "dx [a]", "g"), ("cells", "cells", "d"),
            ("steps", "steps", "d"), ("wall_s", "wall [s]", ".1f"), ("status", "run", ""),
            ("deposited_fraction", "f", ".4f"), ("over_landau_levich", "f / LL", ".3f"),
            ("x_rear_last_over_a", "rear [a]", ".2f"), ("x_balance_over_a", "x* [a]", ".2f"),
            ("x_landau_levich_over_a", "x LL [a]", ".2f")],
            "films behind a receding meniscus (walls at u, fed u * 4 um)")
    if "contact-line" in out:
        print_table(out["contact-line"], [
            ("level", "level", ""), ("dx_over_a", "dx [a]", "g"), ("cells", "cells", "d"),
            ("steps", "steps", "d"), ("wall_s", "wall [s]", ".1f"), ("status", "run", ""),
            ("meniscus_over_a", "meniscus [a]", ".3f"), ("drift_over_a", "drift [a]", "+.3f"),
            ("apparent_angle_deg", "angle [deg]", ".1f"),
            ("static_meniscus_over_a", "static at [a]", ".3f"),
            ("cox_voinov_deg", "Cox-Voinov [deg]", ".1f"),
            ("stalled_length_m", "stalled [m]", ".2e"), ("wall_air_fraction", "wall air", ".3f"),
            ("wall_pressure_excess_pa", "wall dp [Pa]", ".0f")],
            "advancing contact line on dry walls (walls at -u, reservoir at 4 a)")
    write_out(args.out, {"set": dict(args.set), **out})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
