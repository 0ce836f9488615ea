"""The velocity across y around the rear meniscus of finished 3D cases, over u.

The rear meniscus lays the films that carry the flooded region's oil away, and a slab (the
strip's y-invariant flow with room across y, ``bench/film_deposition.py --width``) shows that
currents across y there change those films. In a 3D case some lateral flow is real; this reads
how much there is in the last write, in a box beside the rear meniscus on the axis x_r
(``bench/wall_films.py``'s): |x - x_r| < ``--half-length`` and ``--y-from`` < |y| < ``--y-to``
(a). Per box: the rms of U_y over u, by volume, in the oil (alpha > 0.95), the air
(alpha < 0.05) and the interface cells between, and that of the gap-averaged U_y (the part
that carries oil round the meniscus) by footprint. docs/cases.md, "Lateral currents".

    python bench/rear_currents.py CASE [CASE ...] [--half-length 0.5] [--y-from 0.5]
        [--y-to 1.5] [--save NAME.json]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from foamlib import FoamFieldFile

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.common import save  # noqa: E402
from bench.wall_films import rear_meniscus  # noqa: E402
from generator.case_writer import load_geometry, load_spec_of  # noqa: E402
from runs import case_fields  # noqa: E402

#: the oil and air fractions that bound the interface cells
OIL, AIR = 0.95, 0.05


def _rms(values: np.ndarray, weights: np.ndarray) -> float | None:
    return float(np.sqrt(np.average(values**2, weights=weights))) if len(values) else None


def rear_currents(case: Path, half_length: float = 0.5, y_from: float = 0.5,
                  y_to: float = 1.5) -> dict:
    """In the last write of ``case``: the rear meniscus x_r [a] and, in the box |x - x_r| <
    half_length, y_from <= |y| < y_to [a], the rms velocity across y over u in the oil, the
    air, the interface cells (by volume; None where the box holds no such cell) and gap-averaged
    (by footprint)."""
    geom, spec = load_geometry(case), load_spec_of(case)
    st = case_fields.Structure.load(case)
    t, folder = case_fields.time_folders(case)[-1]
    alpha = np.clip(case_fields.read_alpha(folder / "alpha.oil", st), 0.0, 1.0)
    xb, yb = st.base_x / geom.a, np.abs(st.base_y) / geom.a
    x_r = rear_meniscus(xb, yb, st.mid_gap(alpha, geom.n_layers))
    if x_r is None:
        raise ValueError(f"{case}: no oil at mid-gap on the axis in the write at {t:g} s")
    uy = np.asarray(FoamFieldFile(folder / "U").internal_field, float)[:, 1] / spec.wall_speed
    columns = (np.abs(xb - x_r) < half_length) & (yb >= y_from) & (yb < y_to)
    box = columns[st.base_cell]
    v = st.cell_volumes
    kinds = {"oil": box & (alpha > OIL), "air": box & (alpha < AIR),
             "interface": box & (alpha >= AIR) & (alpha <= OIL)}
    out = {"case": str(case), "time_s": t, "transits": t / geom.transit_time,
           "rear_over_a": x_r, "box_over_a": [half_length, y_from, y_to]}
    for name, sel in kinds.items():
        out[f"{name}_rms_over_u"] = _rms(uy[sel], v[sel])
    gap_mean = st.gap_mean(uy)
    out["gap_averaged_rms_over_u"] = _rms(gap_mean[columns], st.footprint[columns])
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="+", type=Path)
    ap.add_argument("--half-length", type=float, default=0.5, help="box: |x - x_r| < L [a]")
    ap.add_argument("--y-from", type=float, default=0.5, help="box: |y| from [a]")
    ap.add_argument("--y-to", type=float, default=1.5, help="box: |y| below [a]")
    ap.add_argument("--save", help="write the rows to bench/results/NAME.json")
    args = ap.parse_args(argv)
    if not (args.half_length > 0 and 0 <= args.y_from < args.y_to):
        ap.error(f"--half-length {args.half_length}, --y-from {args.y_from}, --y-to {args.y_to}: "
                 "need L > 0 and 0 <= y_from < y_to (a)")
    rows = [rear_currents(c, args.half_length, args.y_from, args.y_to) for c in args.cases]
    print(f"{'case':56s} {'transits':>8s} {'rear (a)':>8s} | U_y rms / u: oil    air  interface"
          "  gap-averaged")
    fmt = lambda v: "     -" if v is None else f"{v:6.3f}"  # noqa: E731
    for r in rows:
        print(f"{r['case'][-56:]:56s} {r['transits']:8.3f} {r['rear_over_a']:8.2f} | "
              f"{fmt(r['oil_rms_over_u'])} {fmt(r['air_rms_over_u'])}     "
              f"{fmt(r['interface_rms_over_u'])}        {fmt(r['gap_averaged_rms_over_u'])}")
    if args.save:
        print(f"wrote {save(args.save, rows)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
