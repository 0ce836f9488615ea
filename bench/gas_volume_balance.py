"""The gas balance of finished gas-release runs, read from their written fields.

interPhaseChangeFoam's gas is incompressible, so its balance is one of volumes: over the
writes of a window, the change of the gas volume in the gap against what was released,
dissolved back and carried through the open boundaries,

    dV_gas = integral of (release - dissolution + gas in - gas out) dt,

with the release and dissolution read from the written p and alpha (Kunz's terms as the
generator writes them: ehlfoam.run.fields.gas_release and gas_dissolution) and the gas fluxes
as the boundaries' volume flux phi less the oil's (the monitor's oil fluxes). The error is the
residual over the gas released in the window. The rates are sampled at the writes only
(trapezoid), so the balance measures the reading as well as the solver; in a bath (supply mode
"submerged", oil flowing in everywhere) nothing but gas leaves with the oil's reading in doubt.

    python bench/gas_volume_balance.py CASE [CASE ...] [--start-transits T] [--save NAME.json]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.common import save  # noqa: E402
from ehlfoam.case.geometry import load_geometry
from ehlfoam.run import fields as case_fields


def balance(case: Path, start_transits: float = 0.0) -> dict:
    """The gas volume balance of one finished gas-release case from ``start_transits`` on."""
    geom = load_geometry(case)
    if geom.gas_release_rate <= 0:
        raise SystemExit(f"gas_volume_balance: {case} releases no gas")
    structure = case_fields.Structure.load(case)
    total = geom.mirror * float(structure.cell_volumes.sum())
    rows = []
    for t, folder in case_fields.time_folders(case):
        if t < start_transits * geom.transit_time - 1e-12:
            continue
        s = case_fields.sample(folder, structure, geom)
        q_in, q_out = case_fields.volume_flux(folder, structure, geom)
        rows.append((t, total - s.oil_volume, s.pattern["gas_release_m3_s"] or 0.0,
                     s.pattern.get("gas_dissolution_m3_s") or 0.0,
                     q_in - s.oil_in, q_out - s.oil_out))
    t, gas, release, back, gas_in, gas_out = (np.array(c) for c in zip(*rows))
    released = float(np.trapezoid(release, t))
    sources = float(np.trapezoid(release - back + gas_in - gas_out, t))
    change = float(gas[-1] - gas[0])
    return {"case": str(case), "writes": len(t), "from_s": float(t[0]), "to_s": float(t[-1]),
            "gas_volume_change_m3": change, "released_m3": released,
            "dissolved_m3": float(np.trapezoid(back, t)),
            "gas_in_m3": float(np.trapezoid(gas_in, t)),
            "gas_out_m3": float(np.trapezoid(gas_out, t)),
            "residual_m3": change - sources,
            "gas_balance_error": abs(change - sources) / released if released > 0 else None}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="+", type=Path)
    ap.add_argument("--start-transits", type=float, default=0.0)
    ap.add_argument("--save", default=None, help="file name under bench/results")
    args = ap.parse_args(argv)
    rows = [balance(c, args.start_transits) for c in args.cases]
    for r in rows:
        nl = 1e12
        print(f"{Path(r['case']).name}: {r['writes']} writes, {r['from_s']:.4g}-{r['to_s']:.4g} s: "
              f"gas volume change {r['gas_volume_change_m3'] * nl:.3f} nl; released "
              f"{r['released_m3'] * nl:.3f}, dissolved {r['dissolved_m3'] * nl:.3f}, in "
              f"{r['gas_in_m3'] * nl:.3f}, out {r['gas_out_m3'] * nl:.3f} nl; residual "
              f"{r['residual_m3'] * nl:+.3f} nl = {r['gas_balance_error']:.2%} of the release")
    if args.save:
        print(save(args.save, {"rows": rows}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
