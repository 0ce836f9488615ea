"""Where the oil leaves a run: the oil outflow through each open boundary, averaged over the
last written times, read from the fields (for runs made before ``history.csv`` had the split).

    python bench/outflow_split.py CASE [CASE ...] [--writes 11] [--save NAME.json]

Reads each of the last ``--writes`` time folders as the run monitor does
(:func:`ehlfoam.run.fields.sample`: the solver's own oil flux alphaPhi0 where it is written,
else phi x face alpha) and prints the mean outflow through the outlet, the side and the
upstream boundary, and the share that leaves anywhere but through the outlet. That share
should be near 0: oil leaving sideways means the flooded region or a wall film reached the
edge of the domain (docs/cases.md, "Wall cells and in-plane cells, one at a time").
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


def outflow_split(case: str | Path, writes: int = 11) -> dict:
    """Mean oil outflow [m3/s, whole contact] per open boundary over the last ``writes``
    written times of ``case``, the supply inflow, and the share off the outlet."""
    case = Path(case)
    geom, structure = load_geometry(case), case_fields.Structure.load(case)
    folders = case_fields.time_folders(case)[-writes:]
    if not folders:
        raise FileNotFoundError(f"{case} has no written time folders")
    samples = [case_fields.sample(folder, structure, geom) for _, folder in folders]
    names = sorted(samples[-1].oil_out_by_boundary)
    out = {name: float(np.mean([s.oil_out_by_boundary[name] for s in samples]))
           for name in names}
    return {"case": str(case), "writes": len(samples),
            "t_s": [samples[0].time, samples[-1].time],
            "exact_flux": all(s.oil_flux_exact for s in samples),
            "oil_in_m3_s": float(np.mean([s.oil_in for s in samples])),
            "oil_out_by_boundary_m3_s": out,
            "off_outlet_fraction": case_fields.off_outlet_share(out)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("cases", nargs="+", type=Path)
    ap.add_argument("--writes", type=int, default=11, help="last written times to average")
    ap.add_argument("--save", default=None, help="bench/results/NAME.json")
    args = ap.parse_args()
    if args.writes < 1:
        ap.error(f"--writes must be >= 1, got {args.writes}")
    rows = [outflow_split(c, args.writes) for c in args.cases]
    for r in rows:
        parts = ", ".join(f"{k} {v * 1e12:.2f}" for k, v in r["oil_out_by_boundary_m3_s"].items())
        off = r["off_outlet_fraction"]
        print(f"{r['case']}: in {r['oil_in_m3_s'] * 1e12:.2f} nl/s; out {parts} nl/s; "
              f"off the outlet {'-' if off is None else f'{100 * off:.1f} %'} "
              f"({r['writes']} writes, {'alphaPhi0' if r['exact_flux'] else 'phi x face alpha'})")
    if args.save:
        print("wrote", save(args.save, {"args": {k: str(v) for k, v in vars(args).items()},
                                        "rows": rows}))


if __name__ == "__main__":
    main()
