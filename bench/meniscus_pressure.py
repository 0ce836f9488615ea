"""The pressure jump across a run's meniscus against Young-Laplace's across the gap.

In the thin gap the meniscus is an arc across the gap of radius h / (2 cos theta), and the oil
just inside it sits 2 sigma cos(theta) / h below the air (the in-plane curvature adds sigma /
R, a few per cent at R of several a). The flooded region's shape follows that suction against
the viscous pressure of the flow, so a mesh that gives the arc the wrong suction moves the
menisci. Along rays from the contact centre (0 deg: downstream on y = 0, 90 deg: sideways,
180 deg: upstream) this reads, at one written time of a case, where the mid-gap oil fraction
crosses 0.5 (the meniscus), the gap-averaged pressure of the oil inside it (extrapolated to
the meniscus from ``--inside`` local cells in) and of the air outside it (a gap height, past
the arc's wedges of oil along the walls, and ``--outside`` cells further out), and the jump p_air - p_oil against 2 sigma cos(theta) / h at the meniscus; with the
in-plane cells there in units of a and in units of the arc's radius, and the contact angle
the jump implies (:func:`apparent_angle`, the in-plane curvature left out): where the walls
run along the meniscus, as on the region's sides, no line is driven and it should be the
wall's.

    python bench/meniscus_pressure.py CASE [CASE ...] [--time T] [--angles 0 45 90 135 180]
        [--save NAME.json] [--note TEXT]
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
from foamlib import FoamFieldFile
from scipy.spatial import cKDTree

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.common import save  # noqa: E402
from ehl_precalc.gap import GapField  # noqa: E402
from generator.case_writer import load_geometry, load_spec_of  # noqa: E402
from runs.case_fields import Structure, mid_gap_alpha, time_folders  # noqa: E402


def apparent_angle(p_oil: float, p_air: float, gap: float, sigma: float,
                   outline_curvature: float = 0.0) -> float:
    """The contact angle [deg] a meniscus across a gap ``gap`` [m] holds between the oil's
    pressure ``p_oil`` and the air's ``p_air`` [Pa] (Young-Laplace, p_oil - p_air =
    -2 sigma cos(theta) / h + sigma kappa), with surface tension ``sigma`` [N/m] and the
    outline's in-plane curvature kappa [1/m] (positive where the region bulges out); NaN where
    the jump is beyond any angle."""
    c = (p_air - p_oil + sigma * outline_curvature) * gap / (2.0 * sigma)
    return float(np.degrees(np.arccos(c))) if -1.0 <= c <= 1.0 else float("nan")


def _folder(case: Path, time: float | None) -> Path:
    folders = time_folders(case)
    if not folders:
        raise SystemExit(f"{case}: no written time folder")
    if time is None:
        return folders[-1][1]
    return min(folders, key=lambda tf: abs(tf[0] - time))[1]


def along_rays(case: Path, time: float | None = None,
               angles: tuple[float, ...] = (0, 45, 90, 135, 180),
               inside: float = 4.0, outside: float = 4.0) -> dict:
    """Per ray: the meniscus radius [a], the gap h there [m], the in-plane cell [a], the
    jump p_air - p_oil [Pa] and Young-Laplace's 2 sigma cos(theta) / h [Pa]."""
    geom = load_geometry(case)
    physics = load_spec_of(case).physics
    structure = Structure.load(case)
    gap = GapField.load(case / "precalc")
    folder = _folder(case, time)
    a = geom.a
    alpha_mid = mid_gap_alpha(folder, structure, geom)
    p = np.asarray(FoamFieldFile(folder / "p").internal_field, float)
    p_col = structure.gap_mean(p)
    h_base = np.asarray(gap(structure.base_x, structure.base_y), float)
    col_volume = np.bincount(structure.base_cell, structure.cell_volumes,
                             minlength=len(structure.base_x))
    cell = np.sqrt(col_volume / h_base)      # in-plane cell size [m]
    tree = cKDTree(np.column_stack([structure.base_x, structure.base_y]))
    r = np.arange(geom.island_radius / a + 0.05, 25.0, 0.005)        # [a]
    rays = []
    for deg in angles:
        c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
        x, y = r * a * c, r * a * s
        inside_domain = ((x >= geom.x_min) & (x <= geom.x_max) & (y <= geom.y_max)
                         & (y >= (0.0 if geom.symmetric else -geom.y_max)))
        _, idx = tree.query(np.column_stack([x, y]))
        oil = (alpha_mid[idx] > 0.5) & inside_domain
        if not oil[0] or oil[inside_domain].all():
            rays.append({"angle_deg": deg, "meniscus_over_a": None})
            continue
        k = int(np.flatnonzero(oil)[-1]) + 1     # past the outermost oil (enclosed bubbles kept)
        r_m = 0.5 * (r[k - 1] + r[k])
        i_m = idx[k]
        dc = cell[i_m] / a                       # local in-plane cell [a]
        h_m = float(gap(r_m * a * c, r_m * a * s))

        def p_at(rr: float) -> float:
            return float(p_col[tree.query([rr * a * c, rr * a * s])[1]])

        r_in1, r_in2 = r_m - inside * dc, r_m - 2 * inside * dc
        p_oil = p_at(r_in1) + (p_at(r_in1) - p_at(r_in2)) * (r_m - r_in1) / (r_in1 - r_in2)
        # the arc's wedges of oil along the walls reach some h / 2 beyond its apex at mid-gap
        p_air = p_at(r_m + h_m / a + outside * dc)
        laplace = 2 * physics.surface_tension * math.cos(math.radians(physics.contact_angle)) / h_m
        rays.append({"angle_deg": deg, "meniscus_over_a": float(r_m), "gap_m": h_m,
                     "cell_over_a": float(dc),
                     "cells_per_arc_radius": h_m / (2 * math.cos(math.radians(
                         physics.contact_angle))) / cell[i_m],
                     "p_oil_Pa": p_oil, "p_air_Pa": p_air, "jump_Pa": p_air - p_oil,
                     "laplace_Pa": laplace, "jump_over_laplace": (p_air - p_oil) / laplace,
                     "apparent_angle_deg": apparent_angle(p_oil, p_air, h_m,
                                                          physics.surface_tension)})
    return {"case": str(case), "time_s": float(folder.name), "rays": rays}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="+", type=Path)
    ap.add_argument("--time", type=float, help="written time [s] (default: the last)")
    ap.add_argument("--angles", nargs="+", type=float, default=[0, 45, 90, 135, 180])
    ap.add_argument("--inside", type=float, default=4.0,
                    help="oil samples this many local cells (and twice) inside the meniscus")
    ap.add_argument("--outside", type=float, default=4.0,
                    help="air sample a gap height and this many local cells outside it")
    ap.add_argument("--save", help="record name under bench/results/")
    ap.add_argument("--note", default="")
    args = ap.parse_args(argv)
    out = []
    for case in args.cases:
        res = along_rays(case, args.time, tuple(args.angles), args.inside, args.outside)
        out.append(res)
        print(f"{case}  t = {res['time_s']:.4f} s")
        print("  angle  meniscus    gap    cell   arc radius   p_air - p_oil   2 sigma cos / h  ratio"
              "  apparent angle")
        for ray in res["rays"]:
            if ray["meniscus_over_a"] is None:
                print(f"  {ray['angle_deg']:5.0f}  no meniscus on this ray")
                continue
            print(f"  {ray['angle_deg']:5.0f}  {ray['meniscus_over_a']:6.2f} a  "
                  f"{ray['gap_m'] * 1e6:5.1f} um  {ray['cell_over_a']:.3f} a  "
                  f"{ray['cells_per_arc_radius']:5.1f} cells  {ray['jump_Pa']:9.1f} Pa  "
                  f"{ray['laplace_Pa']:9.1f} Pa  {ray['jump_over_laplace']:.3f}  "
                  f"{ray['apparent_angle_deg']:5.1f} deg")
        if args.save:
            save(args.save, {"note": args.note, "results": out})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
