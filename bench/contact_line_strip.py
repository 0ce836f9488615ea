"""An advancing meniscus on dry walls, on a strip: does its contact line converge in the cells?

Outside the supply track the walls come into the flooded region dry: on the front of its
sides they advance into the oil with a moving contact line. With no slip at the wall and a
static contact angle, the viscous stress at a moving contact line is singular, and a volume of
fluid method cuts it off at the cells: the apparent angle a gap away follows Cox-Voinov,
theta_app^3 = theta_s^3 + 9 Ca ln(L / lambda), with a numerical slip lambda (Afkhami, Zaleski
and Bussmann 2009, J. Comput. Phys. 228, 5370). This bench asks what the cases' meshes make of
it, on the least model that has it. With interFoam's compression taken from the face flux
(icAlpha 0, the default) they do far worse than a slip of a cell: the wall cells next to the
line stall over several cells, air the walls carry in collects in the wall cells under the
oil, and the contact angle's curvature on it raises their pressure by up to thousands of Pa;
the apparent angle grows by some 8 deg at every halving of the wall cells, and on in-plane
cells wider than some 15 wall cells the walls drag the oil away. With the compression taken
from the local speed (``--set physics.isotropic_compression=1``) the wall cells move with their
wall up to the line, which then stands at the same place on every cell size, but at an
apparent angle the compression sets more than the wall's angle does (docs/cases.md, "The
advancing contact line and the interface compression"). The bench prints, per run, what the
wall cells do around the meniscus (:func:`wall_rows`).

A strip one cell wide (empty sides) along y = 0 of the nominal gap, x from ``--x-in`` to
``--x-out``, with both walls rolling at -u (towards the narrow end) and an oil reservoir at
ambient pressure at x_in, starts as a bridge of oil up to ``--bridge``. The walls come in dry
from x_out and drag the oil towards the reservoir; the meniscus's suction draws it back. At
rest on the walls' flux the bridge's pressure falls by int 12 eta u / h^2 dx from the reservoir
to the meniscus, where it equals the jump sigma (cos theta + cos(theta + beta)) / h (beta: the
ball's slope there). So where the meniscus stands gives the apparent angle theta_app it has a
gap's size away from the wall; the bench prints both, per in-plane cell size dx (a) and level
(its wall layers), with the static angle's position.

    python bench/contact_line_strip.py [--dx 0.2 0.1 0.05 0.025] [--levels fine]
        [--x-in 4] [--x-out 10] [--bridge 6.3] [--time 0.3] [--set KEY=VALUE ...]
        [--work DIR] [--reuse] [--save NAME.json]
    python bench/contact_line_strip.py --plot FILE.png --plot-records RECORD.json ...
"""
from __future__ import annotations

import argparse
import json
import shutil
import sys
from functools import partial
from pathlib import Path

import numpy as np
from scipy.integrate import cumulative_trapezoid
from scipy.optimize import brentq

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from foamlib import FoamFieldFile  # noqa: E402

from bench.film_deposition import (add_strip_options, measure, options_suffix,  # noqa: E402
                                   run_or_reuse, save_rows, strip_mesh, sweep)
from ehlfoam.spec.case import CaseSpec
from ehlfoam.case.fields import slip_walls, wall_layers_fraction
from ehlfoam.mesh import PolyMesh
from ehlfoam.case.wall_slip import write_slip_walls
from ehlfoam.run import fields as case_fields
from ehlfoam.foam.runtime import FoamRuntime


def reverse_walls(spec: CaseSpec, case: Path, mesh: PolyMesh | None = None,
                  precursor: float = 0.0) -> None:
    """Turn the film strip written by ``write_strip_case`` into the advancing one: both walls
    at -u, and the supply patch an oil reservoir at ambient pressure (oil in, anything out).
    With a ``precursor`` [m] (and the strip's ``mesh``) the walls come in wetted by a layer
    that thick each, instead of dry."""
    u = spec.wall_speed
    with FoamFieldFile(case / "0.orig" / "U") as f:
        f.boundary_field["disc"]["value"] = np.array([-u, 0.0, 0.0])
        f.boundary_field["ball"]["omega"] = u / spec.contact.radius
        f.boundary_field["supply"] = {"type": "pressureInletOutletVelocity",
                                      "value": np.zeros(3)}
    with FoamFieldFile(case / "0.orig" / "p_rgh") as f:
        f.boundary_field["supply"] = {"type": "totalPressure", "p0": 0.0, "value": 0.0}
    with FoamFieldFile(case / "0.orig" / "alpha.oil") as f:
        f.boundary_field["supply"] = {"type": "inletOutlet", "inletValue": 1.0, "value": 1.0}
        if precursor > 0:
            z = mesh.points[mesh.faces[mesh.patch_slice("outlet")], 2]
            frac = wall_layers_fraction(z.min(1), z.max(1), z.max(), precursor, precursor)
            f.boundary_field["outlet"] = {"type": "inletOutlet", "inletValue": frac,
                                          "value": frac}
    if spec.physics.wall_slip_length > 0:
        write_slip_walls(case / "0.orig" / "U", slip_walls(spec, mesh, -u, off_track=False))
    shutil.rmtree(case / "0")
    shutil.copytree(case / "0.orig", case / "0")


def balance(spec: CaseSpec, gap, x_in: float, x_out: float, precursor: float = 0.0):
    """The bridge's balance on y = 0: x (m), gap h (m), its slope, and the pressure the walls'
    drag takes off from the reservoir to each x (Pa, positive), int 12 eta u / h^2 dx; with
    a precursor layer [m] on each wall, whose oil the bridge passes on to the reservoir,
    int 12 eta u (h - 2 precursor) / h^3 dx. With a Navier slip length lambda on both walls
    (physics.wall_slip_length) the walls' drag is a plug that carries no shear, and the
    pressure drives (1 + 6 lambda / h) times the flux it drives between no-slip walls."""
    x = np.linspace(x_in, x_out, 4001)
    h = gap(x, np.zeros_like(x))
    slip = 1.0 + 6.0 * spec.physics.wall_slip_length / h
    drop = cumulative_trapezoid(12.0 * spec.oil_viscosity * spec.speed * (h - 2 * precursor)
                                / (h**3 * slip), x, initial=0.0)
    return x, h, np.gradient(h, x), drop


def meniscus_for_angle(spec: CaseSpec, table, theta_deg: float) -> float:
    """Where (m) the bridge's meniscus stands at rest for the apparent angle theta (deg)."""
    x, h, slope, drop = table
    t = np.radians(theta_deg)
    jump = spec.physics.surface_tension * (np.cos(t) + np.cos(t + np.arctan(slope))) / h
    k = np.flatnonzero(drop >= jump)
    return float(x[k[0]]) if len(k) else float("nan")


def angle_at_meniscus(spec: CaseSpec, table, x_m: float) -> float:
    """The apparent angle (deg) that puts the meniscus at rest at x_m (m); NaN outside 0-90."""
    x, h, slope, drop = table
    hm, beta, dp = (np.interp(x_m, x, v) for v in (h, np.arctan(slope), drop))
    sigma = spec.physics.surface_tension

    def g(t: float) -> float:
        return sigma * (np.cos(t) + np.cos(t + beta)) / hm - dp
    lo, hi = 0.0, np.pi / 2 - beta
    return float(np.degrees(brentq(g, lo, hi))) if g(lo) * g(hi) < 0 else float("nan")


def wall_rows(folder: Path, mesh: PolyMesh, u: float, x_m: float, reach: float) -> dict:
    """What the wall cells (the layers on the disc and on the ball) do at one write of the
    strip, beside its mid-gap layer, around the meniscus at x_m (m):

    - ``stalled_length_m``: the length of strip within ``reach`` (m) of the meniscus over which
      the wall cells, on both walls on average, move at less than half their wall's speed u
      (m/s) along x. Next to a moving contact line a wall's own cells move with it but for
      a slip length; a length of several cells is the numerical contact line's drag;
    - ``wall_air_fraction``: the mean air fraction of the wall cells in the flooded columns
      (above 99 % oil beyond their wall cells): air the walls carried in under the oil;
    - ``wall_pressure_excess_pa``: the median of the wall cells' p_rgh over their mid-gap
      cell's in those columns (Pa): the contact angle's curvature on that air.
    """
    alpha = np.asarray(FoamFieldFile(folder / "alpha.oil").internal_field, float)
    ux = np.asarray(FoamFieldFile(folder / "U").internal_field, float)[:, 0]
    p = np.asarray(FoamFieldFile(folder / "p_rgh").internal_field, float)
    n = int(mesh.layer.max()) + 1
    cols = np.zeros((int(mesh.base_cell.max()) + 1, n), int)
    cols[mesh.base_cell, mesh.layer] = np.arange(mesh.n_cells)
    cols = cols[np.argsort(mesh.cell_centres[cols[:, 0], 0])]
    x = mesh.cell_centres[cols[:, 0], 0]
    walls = cols[:, [0, n - 1]]
    moving = np.abs(ux[walls]).mean(axis=1) / u
    near = np.abs(x - x_m) <= reach
    stalled = float(np.sum(np.gradient(x)[near & (moving < 0.5)]))
    flooded = alpha[cols[:, 1:n - 1]].mean(axis=1) > 0.99
    if not flooded.any():
        return {"stalled_length_m": stalled, "wall_air_fraction": float("nan"),
                "wall_pressure_excess_pa": float("nan")}
    air = 1.0 - np.clip(alpha[walls[flooded]], 0.0, 1.0)
    excess = p[walls[flooded]] - p[cols[flooded, n // 2]][:, None]
    return {"stalled_length_m": stalled, "wall_air_fraction": float(air.mean()),
            "wall_pressure_excess_pa": float(np.median(excess))}


def cox_voinov(theta_s_deg: float, ca: float, ratio: float) -> float:
    """Cox-Voinov's apparent angle (deg) for the static angle theta_s, the capillary number of
    the contact line's speed and the ratio of the macroscopic length to the slip length."""
    t3 = np.radians(theta_s_deg) ** 3 + 9.0 * ca * np.log(ratio)
    return float(np.degrees(np.cbrt(max(t3, 0.0))))


#: the plot's names for spec options
SHORT = {"n_layers": "layers", "wall_grading": "grading", "interface_schemes": "schemes",
         "alpha_subcycles": "sub-cycles", "capillary_safety": "safety",
         "isotropic_compression": "icAlpha", "wall_slip_length": "slip",
         "contact_angle": "wall angle"}


def plot_records(paths: list[Path], out: Path, join: tuple[str, ...] = ()) -> None:
    """Left: each run's meniscus over time (a bridge dragged out ends where the line stops);
    right: the apparent angle of the runs that settle, against dx, per set of wall cells, or
    per set of options but the ``join`` ones (e.g. ``mesh.wall_cell``: the walls refined with
    dx drawn as one series)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [r for path in paths for r in json.loads(Path(path).read_text())["rows"]]

    def series(r: dict) -> tuple[str, str]:
        return r["level"], json.dumps({k: v for k, v in r["options"].items() if k not in join},
                                      sort_keys=True)

    walls = sorted({series(r) for r in rows})
    options = [json.loads(key[1]) for key in walls]
    common = {k: v for k, v in options[0].items() if all(o.get(k) == v for o in options)}

    def text(items) -> str:
        return ", ".join(f"{SHORT.get(k.split('.')[-1], k.split('.')[-1])} {v}" for k, v in items)

    fig, (ax_t, ax_a) = plt.subplots(1, 2, figsize=(12, 5.6))
    if common:
        fig.suptitle(f"all runs: {text(common.items())}", fontsize=8)
    for i, key in enumerate(walls):
        color = plt.cm.tab10(i)
        name = key[0] + "".join(", " + text([(k, v)]) for k, v in json.loads(key[1]).items()
                                if k not in common)
        mine = sorted((r for r in rows if series(r) == key),
                      key=lambda r: -r["dx_over_a"])
        for j, r in enumerate(mine):
            w = r["writes"]
            ax_t.plot([x["t_s"] for x in w], [x["x_rear_over_a"] for x in w], color=color,
                      alpha=0.35 + 0.65 * (j + 1) / len(mine), lw=1.0,
                      label=f"{name}, dx {r['dx_over_a']:g} a" + "".join(
                          f", {text([(k, r['options'][k])])}" for k in join
                          if k in r["options"]))
        settled = [r for r in mine if np.isfinite(r["apparent_angle_deg"])
                   and abs(r["meniscus_late_drift_over_a"]) < 0.05]
        ax_a.plot([r["dx_over_a"] for r in settled], [r["apparent_angle_deg"] for r in settled],
                  "o-", color=color, label=name)
        dragged = [r for r in mine if r not in settled]
        ax_a.plot([r["dx_over_a"] * (1 + 0.06 * i) for r in dragged],
                  [90.0 - 2.5 * i] * len(dragged), "x", color=color, ms=8)
    ax_t.set_xlabel("t (s)")
    ax_t.set_ylabel("meniscus x / a")
    ax_t.set_title("advancing meniscus on dry walls (strip, walls at -u)")
    ax_t.legend(fontsize=6, ncol=2, loc="upper center", bbox_to_anchor=(0.5, -0.14))
    ax_a.set_xscale("log")
    ax_a.set_xticks([0.0125, 0.025, 0.05, 0.1, 0.2], ["0.0125", "0.025", "0.05", "0.1", "0.2"])
    ax_a.minorticks_off()
    ax_a.set_xlabel("in-plane cell dx / a")
    ax_a.set_ylabel("apparent angle (deg)")
    ax_a.set_ylim(0, 95)
    ax_a.axhline(15.0, color="0.5", ls=":", lw=1)
    ax_a.text(0.011, 17, "static angle", fontsize=7, color="0.4")
    ax_a.set_title("settled runs; x at 90: dragged out or still moving")
    ax_a.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14))
    fig.tight_layout()
    fig.savefig(out, dpi=130)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_strip_options(ap, [0.2, 0.1, 0.05, 0.025], "fine", 0.3, 30,
                      ROOT / "runs" / "bench" / "contact_line")
    ap.add_argument("--x-in", type=float, default=4.0, help="oil reservoir at x = X a")
    ap.add_argument("--x-out", type=float, default=10.0, help="dry walls enter at x = X a")
    ap.add_argument("--bridge", type=float, default=6.3, help="oil at t = 0 up to x = X a")
    ap.add_argument("--precursor", type=float, default=0.0,
                    help="a layer on each wall coming in [m]: wetted walls instead of dry")
    ap.add_argument("--plot", default="", help="a PNG of the runs in --plot-records")
    ap.add_argument("--plot-records", nargs="+", default=[], metavar="RECORD.json")
    ap.add_argument("--plot-join", nargs="+", default=[], metavar="KEY",
                    help="options drawn as one series whatever their value (mesh.wall_cell)")
    ap.set_defaults(film=0.0)          # the strip's supply: none, the reservoir feeds it
    args = ap.parse_args(argv)
    if args.plot:
        if not args.plot_records:
            ap.error("--plot needs --plot-records RECORD.json ...")
        plot_records([Path(p) for p in args.plot_records], Path(args.plot),
                     tuple(args.plot_join))
        return 0
    if not args.time > 0:
        ap.error(f"--time: {args.time} (valid range > 0)")
    if not 1.5 <= args.x_in < args.bridge < args.x_out:
        ap.error(f"--x-in {args.x_in}, --bridge {args.bridge}, --x-out {args.x_out}: need "
                 "1.5 <= x_in < bridge < x_out (a)")
    runtime = FoamRuntime.from_environment()
    results = []
    for level, dx_a, spec, gap, a in sweep(args):
        ca = spec.oil_viscosity * spec.speed / spec.physics.surface_tension
        table = balance(spec, gap, args.x_in * a, args.x_out * a, args.precursor)
        mesh = strip_mesh(spec, gap, args.x_in * a, args.x_out * a, dx_a * a)
        case = args.work / (f"{level}_dx{dx_a:g}_x{args.x_in:g}-{args.x_out:g}"
                            + options_suffix(args)
                            + (f"_pre{args.precursor:g}" if args.precursor else ""))
        run = run_or_reuse(runtime, spec, case, mesh, args.bridge * a, args, dx_a * a,
                           adjust=partial(reverse_walls, mesh=mesh, precursor=args.precursor))
        rows = measure(case, mesh, a, args.x_out * a)
        for r in rows:
            r["apparent_angle_deg"] = angle_at_meniscus(spec, table, r["x_rear_over_a"] * a)
        late = [r for r in rows if r["t_s"] >= 0.6 * args.time]
        x_m = float(np.median([r["x_rear_over_a"] for r in late])) if late else float("nan")
        drift = (late[-1]["x_rear_over_a"] - late[0]["x_rear_over_a"]) if late else float("nan")
        theta_app = angle_at_meniscus(spec, table, x_m * a)
        h_m = float(np.interp(x_m * a, table[0], table[1]))
        last = case_fields.time_folders(case)[-1][1]
        rows_at_walls = wall_rows(last, mesh, spec.wall_speed, x_m * a, 0.5 * a)
        result = {"level": level, "dx_over_a": dx_a, "dx_m": dx_a * a, "cells": mesh.n_cells,
                  **run, "capillary_number": ca,
                  "meniscus_late_median_over_a": x_m, "meniscus_late_drift_over_a": drift,
                  "gap_at_meniscus_m": h_m, "apparent_angle_deg": theta_app,
                  "meniscus_static_angle_over_a":
                      meniscus_for_angle(spec, table, spec.physics.contact_angle) / a,
                  "precursor_m": args.precursor, **rows_at_walls,
                  "options": dict(args.set), "writes": rows}
        results.append(result)
        print(f"{level:>7} dx {dx_a:6.4g} a ({dx_a * a * 1e6:5.1f} um) {mesh.n_cells:6d} cells "
              f"{result['steps']:6d} steps {result['wall_s']:6.0f} s {result['status']}: "
              f"meniscus {x_m:6.3f} a (drift {drift:+.3f} a over the last 40 %), gap "
              f"{h_m * 1e6:5.1f} um, apparent angle {theta_app:5.1f} deg (static "
              f"{spec.physics.contact_angle:g} deg: {result['meniscus_static_angle_over_a']:.3f} a;"
              f" Cox-Voinov at L/lambda = h/dx: "
              f"{cox_voinov(spec.physics.contact_angle, ca, h_m / (dx_a * a)):5.1f} deg)",
              flush=True)
        print(f"{'':>7} wall cells at the end: stalled over "
              f"{rows_at_walls['stalled_length_m'] * 1e6:5.1f} um of the meniscus's 1 a; in the "
              f"flooded columns {100 * rows_at_walls['wall_air_fraction']:4.1f} % air, "
              f"{rows_at_walls['wall_pressure_excess_pa']:6.0f} Pa over mid-gap", flush=True)
        save_rows(args, results)   # after every case: an interrupted sweep keeps them
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
