"""Static meniscus: walls at rest, no supply, an oil puddle of radius 3a (or supply.initial_puddle)
around the island.

The puddle is an equilibrium (the gap is axisymmetric) once its meniscus, set up as an upright
cylinder, has curved across the gap (some 40 ms); from then on every velocity is spurious. Prints
the largest speed in the oil (alpha > 0.99), at the interface and in the air, the largest
gap-averaged speed in the oil and the drift of the meniscus on y = 0, against the resolution,
the interface compression cAlpha and the time step (the capillary limit), as ratios to the
nominal rolling speed. Writes ``bench/results/static_meniscus.json``.

    python bench/static_meniscus.py [--speed 0.008] [--time 0.02] [--levels coarse medium]
        [--compression 0 1] [--safety 1 0.25] [--air-viscosity 1.8e-5]
        [--nhat default pointCellsLeastSquares] [--set KEY=VALUE ...] [--tag NAME]
        [--edit FILE:KEY/SUBKEY=VALUE ...] [--solver interIsoFoam] [--reanalyse]

``--edit`` changes an entry of a generated ``system/`` file in every case (e.g.
``fvSchemes:snGradSchemes/default=uncorrected``); ``--solver interIsoFoam`` advects the oil
with isoAdvector (geometric VoF) instead of MULES. Neither is a spec option: both are here to
measure what the generator does not offer.
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from foamlib import FoamFieldFile  # noqa: E402

from ehlfoam.spec.case import make_case_spec
from ehlfoam.case.geometry import load_geometry
from ehlfoam.case.writer import write_case
from common import apply_edits, edit_value_text, foam_edit, spec_option  # noqa: E402
from ehlfoam.run import fields as case_fields
from ehlfoam.run.monitor import run_case

RESULTS = ROOT / "bench" / "results"


def _speeds(folder: Path, st: case_fields.Structure) -> dict:
    """Speeds [m/s] of one written time (see :func:`spurious`)."""
    U = np.asarray(FoamFieldFile(folder / "U").internal_field, float)
    speed = np.linalg.norm(U, axis=1)
    a = np.asarray(FoamFieldFile(folder / "alpha.oil").internal_field, float)
    oil, air = a > 0.99, a < 0.01
    band = ~oil & ~air
    u_col = st.oil_column_speeds(U, a)
    return {"u_oil_max": float(speed[oil].max()),
            "u_oil_p99": float(np.percentile(speed[oil], 99)),
            "u_interface_max": float(speed[band].max()) if band.any() else 0.0,
            "u_air_max": float(speed[air].max()),
            "u_oil_gap_mean_max": float(u_col.max()),
            "u_oil_gap_mean_p99": float(np.percentile(u_col, 99))}


def spurious(case: Path) -> dict:
    """Largest speeds [m/s] in the oil, at the interface and in the air, and the largest
    gap-averaged speed in the oil (the volume-weighted mean velocity of a column of cells
    across the gap, over the columns that are oil from wall to wall: the net in-plane flow
    that can move a meniscus in a thin gap, without the recirculation across it), at the last
    write; as ``*_late``, the largest of each over the writes of the run's second half (the
    currents come in bursts); and as ``*_settled``, over its last quarter: the puddle starts
    as an upright cylinder of oil, not the curved meniscus of equilibrium, and the flow that
    curves it is real and decays over some 40 ms (docs/cases.md, "Sub-cycles and the
    capillary limit")."""
    times = case_fields.time_folders(case)
    st = case_fields.Structure.load(case)
    end = float(times[-1][0])
    late = [(float(t), _speeds(folder, st)) for t, folder in times if float(t) >= 0.5 * end]
    out = dict(late[-1][1])                                   # the last write
    for suffix, start in (("late", 0.5), ("settled", 0.75)):
        rows = [row for t, row in late if t >= start * end]
        out.update({f"{key}_{suffix}": max(row[key] for row in rows) for key in rows[-1]})
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speed", type=float, default=0.008, help="nominal rolling speed [m/s]")
    ap.add_argument("--time", type=float, default=0.02, help="simulated time [s]")
    ap.add_argument("--levels", nargs="+", default=["coarse", "medium"])
    ap.add_argument("--compression", nargs="+", type=float, default=[0.0, 1.0])
    ap.add_argument("--safety", nargs="+", type=float, default=[1.0, 0.25],
                    help="factors on the capillary time-step limit")
    ap.add_argument("--air-viscosity", nargs="+", type=float, default=[1.8e-5],
                    help="air viscosities [Pa s] (the reference assumes 1.8e-5)")
    ap.add_argument("--work", default=str(ROOT / "runs" / "checks" / "static_meniscus"))
    ap.add_argument("--nhat", nargs="+", default=["default"],
                    help="gradient schemes for the interface normal (fvSchemes gradSchemes "
                         "nHat; 'default' keeps the template's Gauss linear)")
    ap.add_argument("--set", action="append", default=[], type=spec_option, metavar="KEY=VALUE",
                    help="any other spec option for every case (e.g. mesh.polar_radius=6.8); "
                         "the cases go to folders with the options in their names")
    ap.add_argument("--edit", action="append", default=[], type=foam_edit,
                    metavar="FILE:KEY/SUBKEY=VALUE",
                    help="change an entry of a system/ file in every case (e.g. "
                         "fvSchemes:snGradSchemes/default=uncorrected)")
    ap.add_argument("--solver", choices=["interFoam", "interIsoFoam"], default="interFoam",
                    help="interIsoFoam: isoAdvector instead of MULES (cAlpha unused)")
    ap.add_argument("--tag", default="", help="results go to static_meniscus[_TAG].json")
    ap.add_argument("--reanalyse", action="store_true",
                    help="measure the cases already run in --work again instead of re-running")
    args = ap.parse_args(argv)
    rows = []
    for level, c_alpha, safety, mu_air, nhat in itertools.product(
            args.levels, args.compression, args.safety, args.air_viscosity, args.nhat):
        spec = make_case_spec({
            "name": "static", "walls_moving": False, "contact": {"speed": args.speed},
            "mesh": {"resolution": level},
            "supply": {"mode": "layers", "disc_layer": 0.0, "ball_layer": 0.0,
                       "initial_puddle": 3.0},
            "physics": {"interface_compression": c_alpha, "air_viscosity": mu_air},
            "run": {"end_time": args.time, "capillary_safety": safety,
                    "writes_per_transit": 200}}, **dict(args.set))
        name = f"{level}_c{c_alpha:g}_s{safety:g}_air{mu_air:g}_t{args.time:g}" + "".join(
            f"_{key.split('.')[-1]}{value}" for key, value in args.set) + "".join(
            f"_{keys[-1]}{edit_value_text(value, '')}" for _, keys, value in args.edit) + (
            "" if args.solver == "interFoam" else f"_{args.solver}")
        case = Path(args.work) / (name if nhat == "default" else f"{name}_{nhat.replace(' ', '')}")
        if args.reanalyse and (case / "metrics.json").exists():
            geom = load_geometry(case)
            m = json.loads((case / "metrics.json").read_text())
        else:
            geom = write_case(spec, case, overwrite=True)
            nhat_edit = [] if nhat == "default" else [
                foam_edit(f"fvSchemes:gradSchemes/nHat={nhat}")]
            apply_edits(case, nhat_edit + args.edit, args.solver)
            m = run_case(case)
        s = spurious(case)
        row = {"level": level, "cAlpha": c_alpha, "capillary_safety": safety, "nHat": nhat,
               "options": dict(args.set), "solver": args.solver,
               "edits": [f"{file}:{'/'.join(keys)}={edit_value_text(value)}"
                         for file, keys, value in args.edit],
               "air_viscosity": mu_air,
               "air_viscosity_in_solver": mu_air * spec.run.air_viscosity_factor,
               "max_delta_t_s": geom.max_delta_t, "cells": geom.cells,
               "status": m["status"], "time_steps": m["time_steps"], "wall_s": m["wall_s"],
               # the inlet meniscus is measured from x = -a, the puddle's radius from the centre
               "meniscus_drift_over_a": abs(m["inlet_meniscus_distance_over_a"] + 1.0
                                            - spec.supply.initial_puddle)
               if m.get("inlet_meniscus_distance_over_a") is not None else None,
               "oil_volume_change": m["oil_volume_m3"] / m["oil_volume_initial_m3"] - 1.0,
               **s, **{k.replace("u_", "ratio_") + "_over_u": v / args.speed
                       for k, v in s.items()}}
        print(json.dumps(row), flush=True)
        rows.append(row)
    RESULTS.mkdir(parents=True, exist_ok=True)
    name = f"static_meniscus_{args.tag}.json" if args.tag else "static_meniscus.json"
    (RESULTS / name).write_text(
        json.dumps({"args": vars(args), "rows": rows}, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
