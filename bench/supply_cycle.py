"""The supply as an outcome at the reference conditions: cycles of passes (supply.mode =
"rig", docs/models/supply-cycle.md) over oil amounts and speeds, each to its settled state.

    python bench/supply_cycle.py [--speeds 0.008 0.017] [--layers 0.3e-6 0.5e-6 ...]
        [--passes 40] [--courant 0.25] [--work DIR]

Each (speed, layer) is a thin-film case of the reference rig (HVI60, 40 C, 20 N, track radius
39 mm, the ball's 9.525 mm, gas below 90 kPa, the coarse level, 257^2 precalc grids) whose
oil is ``layer`` on each wall, spread over the +-0.3 mm track at the start, and nothing else:
``ehlfoam case`` + ``ehlfoam run`` make passes until the cycle settles (or ``--passes``). The
table gives the end, the passes, the settled state, the inlet meniscus, the bubble, the
supply the inlet took in on the last pass (as a mean layer on each wall over the contact's
rows) and the wall time, one core.
"""

from __future__ import annotations

import argparse
import csv
import json
import time
from pathlib import Path

from ehlfoam.cli.main import main as ehlfoam

BASE = {"scene": "thin-film",
        "contact": {"load": 20.0, "temperature": 40.0, "lubricant": "HVI60", "grid": 257},
        "supply": {"mode": "rig", "track_half_width": 3e-4, "track_radius": 0.039},
        "physics": {"cavitation_pressure": 9e4},
        "mesh": {"resolution": "coarse"},
        "run": {"wall_limit": 3600.0}}


def _set(spec: dict) -> list[str]:
    out = []
    for table, values in spec.items():
        if isinstance(values, dict):
            out += [a for k, v in values.items() for a in ("--set", f"{table}.{k}={json.dumps(v)}")]
        else:
            out += ["--set", f"{table}={json.dumps(values)}"]
    return out


def run_point(work: Path, speed: float, layer: float, passes: int, courant: float) -> dict:
    spec = json.loads(json.dumps(BASE))
    spec["contact"]["speed"] = speed
    spec["supply"] |= {"disc_layer": layer, "ball_layer": layer}
    spec["thin_film"] = {"courant": courant}
    spec["cycle"] = {"passes_max": passes}
    case = work / f"u{speed * 1e3:g}_h{layer * 1e6:g}"
    if not case.exists():
        assert ehlfoam(["case", "--out", str(case), *_set(spec)]) == 0
    t = time.monotonic()
    ehlfoam(["run", str(case), "--quiet"])
    wall = time.monotonic() - t
    m = json.loads((case / "metrics.json").read_text())
    with open(case / "cycle.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    last = rows[-1]
    return {"speed_mm_s": speed * 1e3, "layer_um": layer * 1e6,
            "end": m["cycle_end_reason"], "passes": m["cycle_passes"], "state": m["state"],
            "states": " ".join(r["state"] for r in rows),
            "inlet_a": m.get("inlet_meniscus_distance_over_a"),
            "bubble_a": m.get("bubble_length_over_a"), "width_a": m.get("flooded_width_over_a"),
            "inlet_layer_um": 1e6 * float(last["inlet_disc_layer_mean_m"]),
            "rig_error": m["oil_rig_balance_error"], "wall_s": wall}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--speeds", type=float, nargs="+", default=[0.008, 0.017])
    p.add_argument("--layers", type=float, nargs="+", default=[0.3e-6, 0.5e-6, 0.7e-6, 1e-6])
    p.add_argument("--passes", type=int, default=40)
    p.add_argument("--courant", type=float, default=0.25)
    p.add_argument("--work", type=Path, default=Path("runs/supply_cycle"))
    a = p.parse_args()
    a.work.mkdir(parents=True, exist_ok=True)
    for layer in a.layers:
        for speed in a.speeds:
            r = run_point(a.work, speed, layer, a.passes, a.courant)
            print(json.dumps(r), flush=True)


if __name__ == "__main__":
    main()
