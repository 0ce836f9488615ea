"""The dissolved-air budget of finished gas-release runs, read again from their written fields.

The gas-release scene releases gas without a budget of dissolved air. Runs made since the
budget check exists report it in metrics.json (``gas_release_over_dissolved_air``); this
script computes it for any finished gas-release case, older ones included (their
geometry.json predates the release constants, which are then taken from the case's spec):
the gas released between the first and the last write against the Bunsen coefficient times
all the oil that was in the gap or came in, and the release rate over the last transit against
the dissolved air the supply carries in (ehlfoam.run.monitor.dissolved_air_budget); and the mean and
largest of that rate ratio over all the writes.

    python bench/release_budget.py CASE [CASE ...] [--solubility B] [--save NAME.json]
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.common import save  # noqa: E402
from ehlfoam.case.dictionaries import release_geometry
from ehlfoam.case.geometry import load_geometry, load_spec_of
from ehlfoam.run import fields as case_fields
from ehlfoam.run.monitor import dissolved_air_budget


def budget(case: Path, solubility: float | None = None) -> dict:
    """The budget of one finished gas-release case (all its written time folders)."""
    spec = load_spec_of(case)
    if spec.scene != "gas-release":
        raise SystemExit(f"release_budget: {case} is a {spec.scene!r} case, not gas-release")
    geom = dataclasses.replace(load_geometry(case), **release_geometry(spec))
    if solubility is not None:
        geom = dataclasses.replace(geom, air_solubility=solubility)
    structure = case_fields.Structure.load(case)
    history = [case_fields.sample(folder, structure, geom)
               for _, folder in case_fields.time_folders(case)]
    rates = np.array([s.pattern["gas_release_m3_s"] for s in history])
    inflow = geom.air_solubility * np.array([s.oil_in for s in history])
    with np.errstate(divide="ignore", invalid="ignore"):
        per_write = np.where(inflow > 0, rates / inflow, np.nan)
    return {"case": str(case), "writes": len(history),
            "transits": history[-1].time / geom.transit_time,
            "gas_release_rate_per_Pa_s": geom.gas_release_rate,
            "release_pressure_Pa": spec.physics.cavitation_pressure,
            "air_solubility": geom.air_solubility,
            **dissolved_air_budget(history, geom.air_solubility, geom.transit_time),
            "release_over_dissolved_inflow_mean": float(np.nanmean(per_write)),
            "release_over_dissolved_inflow_max": float(np.nanmax(per_write))}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="+", type=Path)
    ap.add_argument("--solubility", type=float, default=None,
                    help="Bunsen coefficient (default: the case spec's physics.air_solubility)")
    ap.add_argument("--save", help="write the rows to bench/results/NAME.json")
    args = ap.parse_args(argv)
    rows = [budget(c, args.solubility) for c in args.cases]
    print(f"{'case':40s} {'transits':>8s} {'k':>7s} {'p_r kPa':>7s} {'released nl':>11s} "
          f"{'budget nl':>9s} {'ratio':>6s} {'rate/inflow last':>16s} {'all: mean':>9s} {'max':>6s}")
    for r in rows:
        print(f"{r['case'][-40:]:40s} {r['transits']:8.2f} {r['gas_release_rate_per_Pa_s']:7.0e} "
              f"{r['release_pressure_Pa'] * 1e-3:7.0f} {r['gas_released_m3'] * 1e12:11.3f} "
              f"{r['dissolved_air_m3'] * 1e12:9.2f} {r['gas_release_over_dissolved_air']:6.3f} "
              f"{r['gas_release_over_dissolved_inflow']:16.3f} "
              f"{r['release_over_dissolved_inflow_mean']:9.3f} "
              f"{r['release_over_dissolved_inflow_max']:6.3f}")
    if args.save:
        print(f"wrote {save(args.save, rows)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
