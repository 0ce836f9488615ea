"""The cavitation bubble behind the contact: the cavitating scene's runs for docs/cavitation.md.

    python bench/cavitation.py [--only NAME ...] [--jobs 2] [--rerun]

Named runs of the reference contact (HVI60, 20 N) in the cavitating scene (compressibleInterFoam,
air a perfect gas, pMin = the cavitation pressure), each an override set on ``runs/nominal.toml``
(ample oil: 8 um layers on disc and ball): the thesis's two conditions, thin layers that carry
air in, a gas seed where no air reaches the contact exit, the mesh levels, the model's constants,
and the interface scene (incompressible air) beside them. The fine level starts from the coarse
level's final fields (``SEEDED_FROM``); an interrupted run goes on from its last write. Finished
runs are kept (``--rerun``
recomputes). The bubble metrics are read again from the last written fields with the current
metrics code, at
every write of the last transit. Writes ``bench/results/cavitation.json`` and prints a table.
"""

from __future__ import annotations

import argparse
import json
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from common import solver_cpu_s  # noqa: E402

from ehlfoam._io import atomic_write_json
from ehlfoam.spec.case import load_case_spec
from ehlfoam.case.geometry import load_geometry
from ehlfoam.case.writer import write_case
from ehlfoam.run import fields as case_fields
from ehlfoam.seed.previous import seed_from_previous
from ehlfoam.run.monitor import mass_balance, run_case

RESULTS = ROOT / "bench" / "results"
#: every run starts from the 4 a puddle its figures were measured with (runs/nominal.toml has 5 a)
START = {"supply.initial_puddle": 4.0}
CAV = {"scene": "cavitating", "mesh.resolution": "coarse", **START}
U8 = {"contact.speed": 0.008, "contact.temperature": 40.0}
U20 = {"contact.speed": 0.020, "contact.temperature": 25.0}
THIN = {"supply.disc_layer": 2e-6, "supply.ball_layer": 2e-6}
SEED = {"supply.initial_bubble": 1.0}
L3 = {"supply.disc_layer": 3e-6, "supply.ball_layer": 3e-6}
GR = {"scene": "gas-release", "mesh.resolution": "coarse", **START}


def gas_release_air_factor(conditions: dict) -> float:
    """run.air_viscosity_factor that gives another scene the gas-release scene's air."""
    spec = load_case_spec(ROOT / "runs" / "nominal.toml", **GR, **conditions)
    return spec.air_viscosity / spec.physics.air_viscosity


#: name -> overrides on runs/nominal.toml
RUNS: dict[str, dict] = {
    # 1. 40 C, 8 mm/s
    "u8_8um": {**CAV, **U8},
    "u8_8um_seed1": {**CAV, **U8, **SEED},
    "u8_2um": {**CAV, **U8, **THIN},
    "u8_2um_interface": {**CAV, **U8, **THIN, "scene": "interface"},
    "u8_8um_interface": {**CAV, **U8, "scene": "interface"},
    #    interFoam with the gas-release scene's air (the oil's kinematic viscosity), to set
    #    beside gr_u8_8um, which releases nothing
    "u8_8um_interface_gr_air": {**CAV, **U8, "scene": "interface",
                                "run.air_viscosity_factor": gas_release_air_factor(U8)},
    # 2. 25 C, 20 mm/s: the thesis's bubble (experiment 5 a, Reynolds model 0.9 a)
    "u20_T25_8um": {**CAV, **U20},
    "u20_T25_8um_interface": {**CAV, **U20, "scene": "interface"},
    "u20_T25_8um_seed1": {**CAV, **U20, **SEED},
    "u20_T25_2um": {**CAV, **U20, **THIN},
    "u20_T25_3um": {**CAV, **U20, **L3},
    "u20_T25_4um": {**CAV, **U20, "supply.disc_layer": 4e-6, "supply.ball_layer": 4e-6},
    #    mesh levels and the model's constants, on the 3 um case
    "u20_T25_3um_medium": {**CAV, **U20, **L3, "mesh.resolution": "medium"},
    "u20_T25_3um_fine": {**CAV, **U20, **L3, "mesh.resolution": "fine", "run.transits_max": 2.0},
    "u20_T25_3um_pcav100": {**CAV, **U20, **L3, "physics.cavitation_pressure": 100.0},
    "u20_T25_3um_pcav10k": {**CAV, **U20, **L3, "physics.cavitation_pressure": 1e4},
    "u20_T25_3um_K0.75": {**CAV, **U20, **L3, "physics.oil_bulk_modulus": 0.75e9},
    "u20_T25_3um_K3": {**CAV, **U20, **L3, "physics.oil_bulk_modulus": 3e9},
    "u20_T25_3um_interface": {**CAV, **U20, **L3, "scene": "interface"},
    # the gas-release scene (interPhaseChangeFoam, one-way Kunz): gas where no air reaches
    "gr_u8_8um": {**GR, **U8},
    "gr_u8_8um_pcav30k": {**GR, **U8, "physics.cavitation_pressure": 3e4},
    "gr_u20_T25_8um": {**GR, **U20},
    "gr_u20_T25_8um_medium": {**GR, **U20, "mesh.resolution": "medium", "run.transits_max": 2.0},
    "gr_u20_T25_8um_fine": {**GR, **U20, "mesh.resolution": "fine", "run.transits_max": 1.5},
    "gr_u20_T25_8um_k1e-4": {**GR, **U20, "physics.gas_release_rate": 1e-4},
    "gr_u20_T25_8um_k1e-2": {**GR, **U20, "physics.gas_release_rate": 1e-2},
    "gr_u20_T25_8um_pcav30k": {**GR, **U20, "physics.cavitation_pressure": 3e4},
    #    release where the oil, saturated with air at ambient pressure, falls below it
    "gr_u8_8um_pr90k": {**GR, **U8, "physics.cavitation_pressure": 9e4},
    "gr_u20_T25_8um_pr90k": {**GR, **U20, "physics.cavitation_pressure": 9e4},
    "gr_u8_8um_pr90k_k1e-4": {**GR, **U8, "physics.cavitation_pressure": 9e4,
                              "physics.gas_release_rate": 1e-4},
    "gr_u8_8um_pr90k_k1e-5": {**GR, **U8, "physics.cavitation_pressure": 9e4,
                              "physics.gas_release_rate": 1e-5},
    "gr_u8_8um_pr90k_k1e-2": {**GR, **U8, "physics.cavitation_pressure": 9e4,
                              "physics.gas_release_rate": 1e-2},
    "gr_u8_8um_pr60k": {**GR, **U8, "physics.cavitation_pressure": 6e4},
    "gr_u8_8um_pr90k_medium": {**GR, **U8, "physics.cavitation_pressure": 9e4,
                               "mesh.resolution": "medium", "run.transits_max": 3.0},
}
#: name -> the run whose final fields it starts from (interpolated onto its mesh): the fine level
#: starts from the converged coarse bubble and runs 2 transits (1 to forget the start, the last
#: one measured), which costs half of 4 transits from the standard start.
SEEDED_FROM = {"u20_T25_3um_fine": "u20_T25_3um"}
#: Wall-clock limit of one run [s]: the medium and fine levels need more than the default hour.
WALL_LIMIT = 8 * 3600.0
KEYS = ("state", "gas_mass_balance_error", "bubble_length_over_a", "bubble_width_over_a", "bubble_volume_m3",
        "bubble_enclosed", "min_pressure_Pa", "wake_open", "inlet_meniscus_distance_over_a",
        "inlet_meniscus_shape", "oil_mass_balance_error", "end_reason", "steady",
        "simulated_time_s", "transit_time_s", "time_steps", "cells", "wall_s")


def _balances(case: Path) -> dict:
    """Oil and gas mass balances over the whole run, from every written time (the runs made
    before the monitor followed the gas are measured again here)."""
    geom = load_geometry(case)
    structure = case_fields.Structure.load(case)
    history = [case_fields.sample(f, structure, geom) for _, f in case_fields.time_folders(case)]
    b = mass_balance(history)
    return {k: b.get(k) for k in ("oil_mass_balance_error", "gas_mass_balance_error",
                                  "gas_carried_in_kg", "gas_carried_out_kg")}


def _last_transit(case: Path) -> dict:
    """The flow pattern of the last written time and the bubble over the last transit (mean,
    min, max of its length and volume), measured again with the current metrics code."""
    folders = case_fields.time_folders(case)
    if not folders:
        return {}
    geom = load_geometry(case)
    structure = case_fields.Structure.load(case)
    t_end = folders[-1][0]
    window = [f for t, f in folders if t >= t_end - geom.transit_time * (1 + 1e-9)]
    samples = [case_fields.sample(f, structure, geom).pattern for f in window]
    out = dict(samples[-1])
    for key in ("bubble_length_over_a", "bubble_volume_m3"):
        v = [p[key] for p in samples]
        out[f"{key}_last_transit"] = {"mean": sum(v) / len(v), "min": min(v), "max": max(v),
                                      "n": len(v)}
    out["bubble_enclosed_last_transit"] = sum(p["bubble_enclosed"] for p in samples) / len(samples)
    return out


def one(job: tuple[str, Path, bool]) -> dict:
    name, work, rerun = job
    case = work / name
    done = case / "metrics.json"
    status = json.loads(done.read_text()).get("status") if done.is_file() else None
    if status == "interrupted" and not rerun:       # a stopped run goes on from its last write
        run_case(case, wall_limit=WALL_LIMIT)
    elif rerun or status not in ("finished", "failed"):
        spec = load_case_spec(ROOT / "runs" / "nominal.toml", **RUNS[name], name=name)
        write_case(spec, case, overwrite=True)
        if name in SEEDED_FROM:
            seed_from_previous(case, work / SEEDED_FROM[name])
        run_case(case, wall_limit=WALL_LIMIT)
    m = json.loads(done.read_text())
    m.update(_last_transit(case))
    m.update(_balances(case))
    return {"name": name, "overrides": RUNS[name], "cpu_s": solver_cpu_s(case),
            **{k: m.get(k) for k in KEYS},
            **{k: v for k, v in m.items() if k.endswith("_last_transit")}}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="+", choices=sorted(RUNS), default=None)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--rerun", action="store_true", help="recompute finished runs")
    ap.add_argument("--work", default=str(ROOT / "runs" / "bench" / "cavitation"))
    args = ap.parse_args(argv)
    names = args.only or list(RUNS)
    jobs = [(n, Path(args.work), args.rerun) for n in names]
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        rows = list(pool.map(one, jobs))
    out = RESULTS / "cavitation.json"
    old = json.loads(out.read_text())["rows"] if out.is_file() else []
    merged = {r["name"]: r for r in old} | {r["name"]: r for r in rows}
    # rows in RUNS order, then any this copy of RUNS does not know (another process, started
    # after a run was added, may have written them meanwhile)
    order = [n for n in RUNS if n in merged] + [n for n in merged if n not in RUNS]
    atomic_write_json(out, {"rows": [merged[n] for n in order]})
    fmt = lambda v: f"{v:.4g}" if isinstance(v, float) else str(v)  # noqa: E731
    head = ("name", "state", "bubble_length_over_a", "bubble_enclosed", "min_pressure_Pa",
            "oil_mass_balance_error", "end_reason", "cells", "cpu_s")
    print(" | ".join(head) + " | l/a over the last transit: mean (min-max), enclosed share")
    for r in rows:
        lt = r.get("bubble_length_over_a_last_transit") or {}
        extra = (f"{lt['mean']:.2f} ({lt['min']:.2f}-{lt['max']:.2f}), "
                 f"{r.get('bubble_enclosed_last_transit'):.0%}") if lt else "-"
        print(" | ".join(fmt(r.get(k)) for k in head) + " | " + extra)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
