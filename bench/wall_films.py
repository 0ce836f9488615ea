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
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.common import save  # noqa: E402
from ehl_precalc.meniscus_reynolds import landau_levich  # noqa: E402
from generator.case_writer import load_geometry, load_spec_of  # noqa: E402
from generator.mesh import layer_fractions  # noqa: E402
from runs import case_fields  # noqa: E402

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
    out = {"case": str(case), "cells": geom.cells,
           "wall_cell_over_gap": float(np.diff(layer_fractions(
               geom.n_layers, spec.mesh.level()["wall_grading"]))[0]),
           "landau_levich_both_walls_over_gap": landau_levich(
               spec.oil_viscosity, spec.speed, spec.physics.surface_tension)}
    for name, x_min, y_max, y_min in REGIONS:
        sel = (mid < 0.05) & (x > x_min) & (y < y_max) & (y > y_min)
        out[name] = ({"columns": int(sel.sum()),
                      "oil_over_gap_median": float(np.median(oil[sel])),
                      "disc_wall_cell_alpha_median": float(np.median(wall["disc"][sel])),
                      "ball_wall_cell_alpha_median": float(np.median(wall["ball"][sel]))}
                     if sel.any() else None)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="+", type=Path)
    ap.add_argument("--save", help="write the rows to bench/results/NAME.json")
    args = ap.parse_args(argv)
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
