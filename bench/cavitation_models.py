"""Which solver for the cavitation bubble: the candidates on the reference case, side by side.

    python bench/cavitation_models.py [--time 0.005] [--speed 0.008] [--layer 2e-6]

One coarse case of the reference contact (HVI60, 40 C, 20 N, oil layers on disc and ball),
run for --time seconds from the same start with each candidate:

- ``interFoam``: incompressible oil and air (the interface scene, no cavitation);
- ``compressibleInterFoam``: the cavitating scene (air a perfect gas, pMin = the cavitation
  pressure);
- ``interPhaseChangeFoam`` with Schnerr-Sauer, Kunz and Merkle: oil and one gas phase that
  is made from and condensed back into the oil at the saturation pressure pSat.

Reported per candidate: whether it ran, time steps and CPU time (the solver's own
ExecutionTime), the oil volume against what the supply carried in and the open boundaries
carried out (mass balance), and the lowest pressure. Writes
``bench/results/cavitation_models.json`` and prints a table.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from common import solver_cpu_s  # noqa: E402

from foamlib import FoamFile  # noqa: E402

from ehlfoam._io import atomic_write_json
from ehlfoam.spec.case import make_case_spec
from ehlfoam.case.geometry import META
from ehlfoam.case.writer import write_case
from ehlfoam.run.monitor import run_case

RESULTS = ROOT / "bench" / "results"

#: interPhaseChangeFoam's mass-transfer models and their constants (the v1912 tutorials'
#: values; UInf and tInf scaled to this flow: u and a/u).
PHASE_CHANGE = {
    "SchnerrSauer": {"n": 1.6e13, "dNuc": 2e-6, "Cc": 1.0, "Cv": 1.0},
    "Kunz": {"UInf": None, "tInf": None, "Cc": 1000.0, "Cv": 1000.0},
    "Merkle": {"UInf": None, "tInf": None, "Cc": 80.0, "Cv": 1e-3},
}


def _spec(args, scene: str):
    return make_case_spec({
        "name": f"cav_models_{scene}", "scene": scene,
        "contact": {"speed": args.speed},
        "supply": {"mode": "layers", "disc_layer": args.layer, "ball_layer": args.layer},
        "mesh": {"resolution": "coarse"},
        "run": {"end_time": args.time, "writes_per_transit": 200, "wall_limit": args.wall_limit},
    })


def _to_phase_change(case: Path, model: str, spec) -> None:
    """Turn an interface (interFoam) case into an interPhaseChangeFoam one."""
    p_sat = spec.physics.cavitation_pressure - spec.physics.ambient_pressure  # gauge
    coeffs = {k: v for k, v in PHASE_CHANGE[model].items()}
    if "UInf" in coeffs:
        coeffs["UInf"], coeffs["tInf"] = spec.speed, spec.a / spec.speed
    with FoamFile(case / "constant" / "transportProperties") as f:
        f["phaseChangeTwoPhaseMixture"] = model
        f["pSat"] = p_sat
        f[f"{model}Coeffs"] = coeffs
    with FoamFile(case / "system" / "controlDict") as f:
        f["application"] = "interPhaseChangeFoam"
    geometry = case / META / "geometry.json"
    g = json.loads(geometry.read_text())
    g["solver"] = "interPhaseChangeFoam"
    atomic_write_json(geometry, g)


def one(args, name: str) -> dict:
    work = Path(args.work)
    case = work / name
    scene = {"interFoam": "interface", "compressibleInterFoam": "cavitating"}.get(name, "interface")
    spec = _spec(args, scene)
    write_case(spec, case, overwrite=True)
    if name not in ("interFoam", "compressibleInterFoam"):
        _to_phase_change(case, name, spec)
    m = run_case(case, wall_limit=args.wall_limit)
    return {"candidate": name, "status": m["status"], "end_reason": m["end_reason"],
            "simulated_time_s": m["simulated_time_s"], "time_steps": m["time_steps"],
            "cpu_s": solver_cpu_s(case), "oil_volume_m3": m["oil_volume_m3"],
            "oil_volume_initial_m3": m["oil_volume_initial_m3"],
            "oil_carried_in_m3": m.get("oil_carried_in_m3"),
            "oil_carried_out_m3": m.get("oil_carried_out_m3"),
            "oil_mass_balance_error": m.get("oil_mass_balance_error"),
            "min_pressure_Pa": m.get("min_pressure_Pa"),
            "log_tail": m.get("log_tail", [])[-6:]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--time", type=float, default=0.005, help="simulated time [s]")
    ap.add_argument("--speed", type=float, default=0.008, help="rolling speed [m/s]")
    ap.add_argument("--layer", type=float, default=2e-6, help="oil layer on each wall [m]")
    ap.add_argument("--wall-limit", type=float, default=1800.0)
    ap.add_argument("--work", default=str(ROOT / "runs" / "bench" / "cavitation_models"))
    ap.add_argument("--only", nargs="*", default=None)
    args = ap.parse_args()
    names = args.only or ["interFoam", "compressibleInterFoam", *PHASE_CHANGE]
    rows = []
    for name in names:
        row = one(args, name)
        rows.append(row)
        print(f"{name:22s} {row['status']:9s} steps {row['time_steps']:7d}  "
              f"CPU {row['cpu_s'] or float('nan'):8.1f} s  "
              f"mass balance {row['oil_mass_balance_error'] or float('nan'):.2%}  "
              f"p_min {row['min_pressure_Pa'] or float('nan'):.4g} Pa", flush=True)
    RESULTS.mkdir(exist_ok=True)
    out = RESULTS / "cavitation_models.json"
    atomic_write_json(out, {"time_s": args.time, "speed_m_s": args.speed,
                            "layer_m": args.layer, "rows": rows})
    print(f"-> {out}")


if __name__ == "__main__":
    main()
