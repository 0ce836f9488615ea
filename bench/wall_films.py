"""The oil films on the walls outside the flooded region of finished cases, against
Landau-Levich.

A receding meniscus between two walls moving at u leaves a film on each wall of thickness
t = 1.34 Ca^(2/3) r / (1 + 3.35 Ca^(2/3)) with r = h / 2 (Aussillous and Quere's fit) and
Ca = eta u / sigma. Behind the flooded region the walls carry those films away. This reads,
in the last write, the oil per column (both walls together, as a fraction of the local gap)
where the mid-gap is air (alpha < 0.05): behind the region (x > 8 a, |y| < 4 a) and beside
it (|y| > 6 a), and the oil fraction of the wall cells of the disc and of the ball there
(medians over those columns).

The films keep the thickness they were laid with while the gap behind the meniscus grows, so
the oil over the local gap falls short of LL by h(meniscus) / h(x): read it against LL only
where the region behind is short (the default domains: the rear meniscus 1.4-5 a from the
outlet); with the outlet at 20 a and the rear at 13.7 a the median column sits where the gap
is some 1.5 times the meniscus's (docs/cases.md, "What the films converge to").

    python bench/wall_films.py CASE [CASE ...] [--save NAME.json]

With ``--rear``, the films as the rear meniscus lays them, write by write: the rear meniscus
x_r (the furthest mid-gap oil, alpha > 0.5, on |y| < 0.15 a), the gap h_r there, and the oil per
column over h_r, against LL (medians over the columns with air at mid-gap on |y| < 1 a and
x_r + d0 < x < x_r + d1, for each ``--bins`` pair d0 d1 in a; default 1-2 a, past the wedges of
oil the meniscus leaves along both walls, some h_r / 2 beyond its apex). The walls carry a film
laid at t0 to x_r + u (t - t0): a run that starts from other fields shows its own films in a
bin up to d1 only after d1 a / u (0.1 d1 transits where a transit is 10 a).

    python bench/wall_films.py CASE [CASE ...] --rear [--bins 1 2] [--from T] [--save NAME.json]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.common import save  # noqa: E402
from bench.oil_change import columns  # noqa: E402
from ehlfoam.thinfilm import landau_levich
from ehlfoam.case.geometry import load_geometry, load_spec_of
from ehlfoam.run import fields as case_fields

#: where the films are read, in units of a: (name, x > ..., |y| < ..., |y| > ...)
REGIONS = (("behind", 8.0, 4.0, 0.0), ("beside", -np.inf, np.inf, 6.0))


def films(case: Path) -> dict:
    geom, spec = load_geometry(case), load_spec_of(case)
    st = case_fields.Structure.load(case)
    _, folder = case_fields.time_folders(case)[-1]
    alpha = np.clip(case_fields._read_alpha(folder / "alpha.oil", st)[0], 0.0, 1.0)
    n = len(st.base_x)
    oil = st.gap_mean(alpha)                      # oil over the column's volume (its gap)
    mid = st.mid_gap(alpha, geom.n_layers)
    wall = {}
    for name, layer in (("disc", 0), ("ball", geom.n_layers - 1)):
        sel = st.layer == layer
        wall[name] = np.bincount(st.base_cell[sel], alpha[sel], minlength=n)
    x, y = st.base_x / geom.a, np.abs(st.base_y) / geom.a
    wall_share = st.wall_cell / st.column_gaps()   # the wall cell over the column's gap
    out = {"case": str(case), "cells": geom.cells,
           "wall_cell_over_gap": float(np.median(wall_share)),
           "landau_levich_both_walls_over_gap": landau_levich(
               spec.oil_viscosity, spec.speed, spec.physics.surface_tension)}
    for name, x_min, y_max, y_min in REGIONS:
        sel = (mid < 0.05) & (x > x_min) & (y < y_max) & (y > y_min)
        out[name] = ({"columns": int(sel.sum()),
                      "oil_over_gap_median": float(np.median(oil[sel])),
                      "wall_cell_over_gap_median": float(np.median(wall_share[sel])),
                      "disc_wall_cell_alpha_median": float(np.median(wall["disc"][sel])),
                      "ball_wall_cell_alpha_median": float(np.median(wall["ball"][sel]))}
                     if sel.any() else None)
    return out


#: the half-width [a] of the strip along y = 0 the rear meniscus is found on
AXIS_HALF_WIDTH = 0.15


def rear_meniscus(x: np.ndarray, y: np.ndarray, mid: np.ndarray) -> float | None:
    """The rear meniscus on the axis [a]: the furthest column (x, |y| in a) with oil at
    mid-gap (``mid`` > 0.5) on |y| < AXIS_HALF_WIDTH; None where the axis holds none."""
    wet = (y < AXIS_HALF_WIDTH) & (mid > 0.5)
    return float(x[wet].max()) if wet.any() else None


def rear_films(case: Path, bins: list[tuple[float, float]] = ((1.0, 2.0),),
               from_transits: float = 0.0) -> dict:
    """Per write of ``case`` from ``from_transits`` on: the rear meniscus on the axis x_r [a],
    the gap there [m] and, per bin (d0, d1) [a] behind it, the median oil per column over
    that gap, over Landau-Levich's both films together (module docstring)."""
    geom, spec = load_geometry(case), load_spec_of(case)
    st = case_fields.Structure.load(case)
    gap = st.column_gaps()
    x, y = st.base_x / geom.a, np.abs(st.base_y) / geom.a
    axis = y < AXIS_HALF_WIDTH
    ll = landau_levich(spec.oil_viscosity, spec.speed, spec.physics.surface_tension)
    writes = []
    for t, folder in case_fields.time_folders(case):
        if t < from_transits * geom.transit_time - 1e-12:
            continue
        oil, mid = columns(folder, st, geom.n_layers)
        film = oil / st.footprint
        x_r = rear_meniscus(x, y, mid)
        if x_r is None:
            continue
        h_r = float(np.median(gap[axis & (np.abs(x - x_r) <= 0.1)]))
        row = {"time_s": t, "transits": t / geom.transit_time, "rear_over_a": x_r,
               "gap_at_rear_m": h_r, "film_over_ll": []}
        for d0, d1 in bins:
            sel = (y < 1.0) & (x > x_r + d0) & (x < x_r + d1) & (mid < 0.05)
            row["film_over_ll"].append(float(np.median(film[sel]) / h_r / ll)
                                       if sel.any() else None)
        writes.append(row)
    return {"case": str(case), "landau_levich_both_walls_over_gap": ll,
            "bins_over_a": [list(b) for b in bins], "writes": writes}


def _print_rear(result: dict) -> None:
    print(f"\n{result['case']}  (LL both films {result['landau_levich_both_walls_over_gap']:.4f}"
          " of the gap)")
    print("transits  rear (a)  gap (um)  " + "  ".join(
        f"f/LL {d0:g}-{d1:g} a" for d0, d1 in result["bins_over_a"]))
    for w in result["writes"]:
        print(f"{w['transits']:8.3f}  {w['rear_over_a']:8.2f}  {w['gap_at_rear_m'] * 1e6:8.1f}  "
              + "  ".join("        -" if f is None else f"{f:13.3f}"
                          for f in w["film_over_ll"]))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="+", type=Path)
    ap.add_argument("--save", help="write the rows to bench/results/NAME.json")
    ap.add_argument("--rear", action="store_true",
                    help="the films behind the rear meniscus, write by write")
    ap.add_argument("--bins", nargs="+", type=float, default=[1.0, 2.0],
                    help="with --rear: pairs d0 d1 [a] behind the rear meniscus (default 1 2)")
    ap.add_argument("--from", dest="start", type=float, default=0.0,
                    help="with --rear: the first write read [transits]")
    args = ap.parse_args(argv)
    if args.rear:
        if len(args.bins) % 2 or any(d1 <= d0 for d0, d1 in zip(args.bins[::2], args.bins[1::2])):
            ap.error(f"--bins {args.bins}: give pairs d0 d1 with d1 > d0 (a)")
        bins = list(zip(args.bins[::2], args.bins[1::2]))
        results = [rear_films(c, bins, args.start) for c in args.cases]
        for r in results:
            _print_rear(r)
        if args.save:
            print(f"wrote {save(args.save, results)}")
        return 0
    rows = [films(c) for c in args.cases]
    print(f"{'case':44s} {'cells':>6s} {'wall cell':>9s} {'LL':>6s} | behind: oil/gap  disc  ball "
          f"| beside: oil/gap  disc  ball")
    for r in rows:
        line = (f"{r['case'][-44:]:44s} {r['cells']:6d} {r['wall_cell_over_gap'] * 100:8.2f}% "
                f"{r['landau_levich_both_walls_over_gap'] * 100:5.2f}%")
        for name, *_ in REGIONS:
            v = r[name]
            line += (" |        -        -     -" if v is None else
                     f" | {v['oil_over_gap_median'] * 100:13.2f}% {v['disc_wall_cell_alpha_median']:5.2f} "
                     f"{v['ball_wall_cell_alpha_median']:5.2f}")
        print(line)
    if args.save:
        print(f"wrote {save(args.save, rows)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
