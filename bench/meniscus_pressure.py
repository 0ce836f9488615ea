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
    python bench/meniscus_pressure.py --plot FILE.png --records NAME.json ... [--only TEXT ...]
        [--rays 60 75 90]

``--plot`` draws the recorded runs' apparent angles on the given rays against the in-plane cell
at the meniscus there (``--only``: the runs whose case path ends with one of the texts).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np
from foamlib import FoamFieldFile
from scipy.spatial import cKDTree

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.common import RESULTS, save  # noqa: E402
from ehlfoam.gap.field import GapField
from ehlfoam.case.geometry import load_geometry, load_spec_of
from ehlfoam.run.fields import Structure, mid_gap_alpha, time_folders


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
    return {"case": str(case), "time_s": float(folder.name),
            "wall_angle_deg": float(physics.contact_angle), "rays": rays}


def names_run(case: str, name: str) -> bool:
    """Whether ``name`` (one or more folders) is the end of the ``case`` path, folder by folder
    (``slip/coarse`` names ``runs/slip/coarse``, not ``runs/noslip/coarse``)."""
    tail = Path(name).parts
    return Path(case).parts[-len(tail):] == tail


def group_series(results: list[dict], specs: list[str]) -> list[tuple[str, list[dict]]]:
    """Runs grouped into series by ``LABEL=SUFFIX,SUFFIX,...`` specs, each run named by the
    last folders of its case path, in the order the suffixes are given. A suffix that names no run is
    an error, so that a series is never drawn short."""
    groups = []
    for spec in specs:
        label, sep, names = spec.rpartition("=")
        if not sep or not label or not names:
            raise ValueError(f"--series {spec!r}: expected LABEL=SUFFIX,SUFFIX,...")
        runs = []
        for name in names.split(","):
            found = [res for res in results if names_run(res["case"], name)]
            if not found:
                raise ValueError(f"--series {label!r}: no run ends with {name!r}")
            runs += found
        groups.append((label, runs))
    return groups


def plot_angles(results: list[dict], out: Path, rays: tuple[float, ...] = (60, 75, 90),
                series: list[str] | None = None) -> None:
    """The apparent angle [deg] of each run's meniscus on ``rays`` [deg] against the in-plane
    cell there [a] (log scale, finer to the right), one colour a run and one marker a ray;
    a jump beyond any angle is drawn as a cross at 0 deg, the wall's angle as a dotted line.
    With ``series`` (``group_series``' specs) one colour a series instead, each ray's points
    of a series joined from coarse to fine, and only the series' runs drawn."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    markers = dict(zip(rays, "os^vD<>p"))
    if series:
        groups = group_series(results, series)
    else:
        groups = [("/".join(Path(res["case"]).parts[-2:]) + f" @ {res['time_s']:.4g} s", [res])
                  for res in results]
    # each group's drawable rays: (ray, cell [a], apparent angle [deg])
    points = [[(ray["angle_deg"], ray["cell_over_a"], ray["apparent_angle_deg"])
               for res in runs for ray in res["rays"]
               if ray["angle_deg"] in markers and ray["meniscus_over_a"] is not None]
              for _, runs in groups]
    if not any(points):
        raise ValueError(f"rays {rays}: no ray of these runs has a meniscus on them")
    fig, ax = plt.subplots(figsize=(8.5, 5.2))
    for i, ((label, _), mine) in enumerate(zip(groups, points)):
        color = plt.cm.tab10(i % 10)
        for deg, cell, angle in mine:
            nan = not math.isfinite(angle)
            ax.plot(cell, 0.0 if nan else angle, "x" if nan else markers[deg], color=color,
                    ms=7, label=label)
            label = None
        for deg in markers if series else ():
            line = sorted((cell, angle) for d, cell, angle in mine
                          if d == deg and math.isfinite(angle))
            if len(line) > 1:
                ax.plot(*zip(*line), "-", color=color, lw=0.8, alpha=0.6)
    for ray, marker in markers.items():
        ax.plot([], [], marker, color="0.4", ls="none", label=f"ray {ray:g} deg")
    walls = sorted({res.get("wall_angle_deg", 15.0) for _, runs in groups for res in runs})
    for wall in walls:
        ax.axhline(wall, color="0.5", ls=":", lw=1)
        ax.text(0.01, wall + 0.7, f"wall {wall:g} deg", fontsize=7, color="0.4",
                transform=ax.get_yaxis_transform())
    ax.set_xscale("log")
    lo, hi = ax.get_xlim()
    ticks = [t for t in (0.0075, 0.015, 0.03, 0.06, 0.12, 0.24, 0.48, 0.96) if lo <= t <= hi]
    ax.set_xticks(ticks, [f"{t:g}" for t in ticks])
    ax.minorticks_off()
    ax.invert_xaxis()
    ax.set_xlabel("in-plane cell at the meniscus / a (finer to the right)")
    ax.set_ylabel("apparent angle from the jump (deg); x: beyond any angle")
    ax.set_title("menisci's apparent angles against their cells")
    ax.legend(fontsize=6.5, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="*", type=Path)
    ap.add_argument("--time", type=float, help="written time [s] (default: the last)")
    ap.add_argument("--angles", nargs="+", type=float, default=[0, 45, 90, 135, 180])
    ap.add_argument("--inside", type=float, default=4.0,
                    help="oil samples this many local cells (and twice) inside the meniscus")
    ap.add_argument("--outside", type=float, default=4.0,
                    help="air sample a gap height and this many local cells outside it")
    ap.add_argument("--save", help="record name under bench/results/")
    ap.add_argument("--note", default="")
    ap.add_argument("--plot", type=Path, help="draw the --records' angles into this image")
    ap.add_argument("--records", nargs="+", default=[], help="records under bench/results/")
    ap.add_argument("--only", nargs="+", default=[],
                    help="runs whose case path ends with one of these folders")
    ap.add_argument("--rays", nargs="+", type=float, default=[60, 75, 90])
    ap.add_argument("--series", nargs="+", default=[],
                    help="LABEL=SUFFIX,SUFFIX,...: draw the runs as series, one colour each")
    args = ap.parse_args(argv)
    if args.plot:
        results = [res for name in args.records
                   for res in json.loads((RESULTS / name).read_text())["results"]
                   if not args.only or any(names_run(res["case"], name) for name in args.only)]
        if not results:
            ap.error(f"--records {args.records} --only {args.only}: no run to draw")
        plot_angles(results, args.plot, tuple(args.rays), args.series)
        print(f"wrote {args.plot} ({len(results)} runs)")
        return 0
    if not args.cases:
        ap.error("give CASE folders, or --plot with --records")
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
