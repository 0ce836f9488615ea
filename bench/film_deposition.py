"""The rear meniscus's films on a strip: the least model of what sets the flooded width.

Behind the contact the flooded region sends its oil out as films that its rear meniscus lays
on the disc and the ball. A receding meniscus between walls moving at u lays, on both walls
together, the fraction LL(Ca) of the gap h where it sits (Landau-Levich, Aussillous and Quere's
fit: ``bench/wall_films.py``). So at balance the meniscus sits where LL h equals the oil
carried in over u: the films decide how far back, in the diverging gap, the region reaches,
and with it its size (docs/cases.md, "The far field decides the width").

This bench asks, in 2D (x, z), what the cases' meshes make of that law. A strip one cell wide
(empty sides) along y = 0 of the nominal case's gap, x from ``--x-in`` to ``--x-out``, both
walls rolling at u, is fed all-oil through x = x_in at q = u ``--film`` (m2/s) and starts as a
bridge of oil up to where LL puts the meniscus. For each in-plane cell size dx (a) and level
(the wall layers and the capillary step of that level, at that dx) it records, at every
write, the rear meniscus (the gap-averaged oil fraction crossing 0.5), the films behind it
(the oil over the gap, a median over x_r + 1 a .. x_out - 0.5 a) and the oil held, and prints
the deposited fraction f = film / h(x_r) against LL, and where the meniscus would balance,
h* = film_in / f.

With ``--width W`` the strip becomes a slab W a wide between two symmetry planes, meshed with
gmsh's free quads (``--aligned``: rows of square cells): the same 2D problem with room across
y, which asks what the third dimension alone does to the films (docs/cases.md, "The films' own
time step"). Strip and slab grow their cells near the supply, where the leaning columns would
turn cells finer than their lean inside out.

    python bench/film_deposition.py [--dx 0.8 0.4 0.2 0.1 0.05] [--levels coarse]
        [--film 4e-6] [--time 1.0] [--x-in 3] [--x-out 16] [--width W [--aligned]]
        [--set KEY=VALUE ...] [--work DIR] [--reuse] [--save NAME.json]
"""
from __future__ import annotations

import argparse
import itertools
import json
import shutil
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from foamlib import FoamFieldFile  # noqa: E402

from bench.common import apply_edits, edit_value_text, foam_edit, save, spec_option  # noqa: E402
from ehlfoam.thinfilm import landau_levich
from ehlfoam.spec.case import CaseSpec, make_case_spec
from ehlfoam.case.dictionaries import edit_physics_dicts, edit_run_control
from ehlfoam.case.timestep import capillary_time_step
from ehlfoam.case.writer import TEMPLATES, extrude_level
from ehlfoam.gap.source import load_gap
from ehlfoam.mesh.gmsh_model import extract_mesh, gmsh_model
from ehlfoam.mesh.topology import edge_topology
from ehlfoam.mesh import BaseMesh, PolyMesh, split_patch, write_polymesh
from ehlfoam.run import fields as case_fields
from ehlfoam.foam.runtime import FoamRuntime


#: the strip's default ends, units of a: the supply well upstream of LL's rear meniscus
#: (10.3 a), the outlet far enough behind it for the films to be measured over 2 a or more
X_IN, X_OUT = 3.0, 16.0
#: the nominal feed [m]: the strip carries u times this in, which LL balances at 10.3 a
FILM = 4e-6


def supply_cell_size(gap, x_in: float) -> float:
    """The smallest in-plane cell (m) at the supply x_in (m): twice the lean h h' / 2 of the
    columns there at the ball (``extrude``'s normal columns lean upstream onto the supply's
    upright ones, and turn the first cells inside out where these are finer than the lean;
    0.075 a at 9 a on the nominal gap)."""
    eps = 1e-3 * x_in
    h = float(gap(np.array([x_in]), np.array([0.0]))[0])
    slope = float(np.diff(gap(np.array([x_in - eps, x_in + eps]), np.zeros(2)))[0]) / (2 * eps)
    return h * abs(slope)


def cell_size(x: float, x_in: float, dx: float, s_in: float) -> float:
    """The in-plane cell size (m) at x (m): dx, grown to s_in (m) at the supply x_in over
    20 s_in where s_in is larger (:func:`supply_cell_size`)."""
    return max(dx, s_in * (1.0 - (x - x_in) / (20.0 * s_in)))


def strip_mesh(spec: CaseSpec, gap, x_in: float, x_out: float, dx: float) -> PolyMesh:
    """The strip x in [x_in, x_out] (m), one cell wide in y, of dx (m), coarser near the supply
    where dx is finer than :func:`supply_cell_size`, extruded across the gap on y = 0 with the
    level's wall layers; patches supply (x_in), outlet, disc, ball and side (both y faces,
    empty: a 2D case)."""
    s_in = supply_cell_size(gap, x_in)
    graded = [x_in]
    while s_in > dx and graded[-1] < x_in + 20.0 * s_in:
        graded.append(graded[-1] + cell_size(graded[-1], x_in, dx, s_in))
    n_uniform = max(int(round((x_out - graded[-1]) / dx)), 1)
    x = np.concatenate([graded[:-1], np.linspace(graded[-1], x_out, n_uniform + 1)])
    n = len(x) - 1
    points = np.concatenate([np.stack([x, np.zeros_like(x)], 1),
                             np.stack([x, np.full_like(x, dx)], 1)])
    i = np.arange(n)
    quads = np.stack([i, i + 1, n + 2 + i, n + 1 + i], 1)          # counter-clockwise
    edges = {"inlet": np.array([[n + 1, 0]]), "outlet": np.array([[n, 2 * n + 1]]),
             "side": np.concatenate([np.stack([i, i + 1], 1),
                                     np.stack([n + 2 + i, n + 1 + i], 1)])}
    mesh = extrude_level(spec, BaseMesh(points, quads, edges),
                         lambda xs, ys: gap(xs, np.zeros_like(xs)))
    mesh = split_patch(mesh, "inlet", np.ones(mesh.patch("inlet").size, bool), "supply")
    mesh.patches = [replace(p, type="empty") if p.name == "side" else p for p in mesh.patches]
    return mesh


def slab_mesh(spec: CaseSpec, gap, x_in: float, x_out: float, dx: float,
              width: float, free: bool = True) -> PolyMesh:
    """The strip as a slab ``width`` (m) wide in y, meshed in (x, y) with gmsh's free quads of
    size dx (m), the generator's own algorithm (``free``), or with rows of square cells along x
    (not ``free``: the strip repeated across y; uniform, so ``dx`` must not be finer than
    half :func:`supply_cell_size`, the columns' lean), and extruded like the strip on the gap of
    y = 0 (the same gap at every y); both y faces are symmetry planes (``symmetry`` at y = 0,
    ``side`` at y = width). Still a 2D problem, now with room across y, which the 3D cases
    have and the strip has not, and on free quads with cells that need not line up with the
    meniscus, as in the 3D cases' bands."""
    import gmsh
    s_in = supply_cell_size(gap, x_in)
    if not free and dx < 0.5 * s_in:
        raise ValueError(f"dx = {dx:.3g} m: aligned slab cells must be at least the columns' "
                         f"lean at x_in = {x_in:.3g} m, {0.5 * s_in:.3g} m")
    with gmsh_model("film-slab"):
        surface = gmsh.model.occ.addRectangle(x_in, 0.0, 0.0, x_out - x_in, width)
        gmsh.model.occ.synchronize()
        if not free:
            for _, curve in gmsh.model.getBoundary([(2, surface)], oriented=False):
                x0, y0, _, x1, y1, _ = gmsh.model.getBoundingBox(1, curve)
                gmsh.model.mesh.setTransfiniteCurve(
                    curve, max(int(round(max(x1 - x0, y1 - y0) / dx)), 1) + 1)
            gmsh.model.mesh.setTransfiniteSurface(surface)
            gmsh.model.mesh.setRecombine(2, surface)
        gmsh.model.mesh.setSizeCallback(
            lambda dim, tag, x, y, z, lc: cell_size(x, x_in, dx, s_in))
        gmsh.model.mesh.generate(2)
        points, quads, _ = extract_mesh({})   # raises on any non-quad
    base = BaseMesh(points, quads)
    quads = np.where((base.quad_areas() < 0)[:, None], quads[:, ::-1], quads)
    topo = edge_topology(quads, len(points))   # boundary edges, quad on the left
    outer = np.stack([topo.bnd_a, topo.bnd_b], axis=1)
    mid = points[outer].mean(axis=1)
    tol = 1e-6 * dx
    names = {"inlet": np.abs(mid[:, 0] - x_in) < tol, "outlet": np.abs(mid[:, 0] - x_out) < tol,
             "symmetry": np.abs(mid[:, 1]) < tol, "side": np.abs(mid[:, 1] - width) < tol}
    mesh = extrude_level(spec, BaseMesh(points, quads, {k: outer[v] for k, v in names.items()}),
                         lambda xs, ys: gap(xs, np.zeros_like(xs)))
    mesh = split_patch(mesh, "inlet", np.ones(mesh.patch("inlet").size, bool), "supply")
    mesh.patches = [replace(p, type="symmetryPlane") if p.name == "side" else p
                    for p in mesh.patches]
    return mesh


def columns(mesh: PolyMesh, alpha: np.ndarray, x_edges: np.ndarray | None = None
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per column of the strip, in x order, or per bin of x between ``x_edges`` (m) over the
    columns whose disc face lies in it (a slab): x (m), gap (m) and oil thickness (m, both
    walls together)."""
    disc = mesh.patch_slice("disc")
    base = mesh.base_cell[mesh.owner[disc]]
    n = int(mesh.base_cell.max()) + 1
    area, x_base = np.zeros(n), np.zeros(n)
    area[base] = np.linalg.norm(mesh.face_areas[disc], axis=1)
    x_base[base] = mesh.face_centres[disc, 0]
    volume = np.bincount(mesh.base_cell, mesh.cell_volumes, minlength=n)
    oil = np.bincount(mesh.base_cell, mesh.cell_volumes * np.clip(alpha, 0.0, 1.0), minlength=n)
    if x_edges is None:
        order = np.argsort(x_base)
        return x_base[order], volume[order] / area[order], oil[order] / area[order]
    m = len(x_edges) - 1
    k = np.clip(np.searchsorted(x_edges, x_base) - 1, 0, m - 1)
    footprint = np.bincount(k, area, minlength=m)
    held = footprint > 0           # bins finer than the cells near the supply may hold none
    return (0.5 * (x_edges[:-1] + x_edges[1:]))[held], \
        (np.bincount(k, volume, minlength=m) / np.where(held, footprint, 1.0))[held], \
        (np.bincount(k, oil, minlength=m) / np.where(held, footprint, 1.0))[held]


def write_strip_case(spec: CaseSpec, case: Path, mesh: PolyMesh, x_bridge: float,
                     film: float, dx: float, end_time: float, write_interval: float) -> float:
    """The interface template with the strip mesh, the bridge (oil for x < x_bridge, m), the
    all-oil supply carrying ``film`` * u (m2/s) and the level's capillary step for cells of
    dx (m). Returns that step (s)."""
    if case.exists():
        shutil.rmtree(case)
    for part in ("system", "constant", "0.orig"):
        shutil.copytree(TEMPLATES / "interface" / part, case / part)
    write_polymesh(mesh, case)
    side = mesh.patch("side").type             # empty on the strip, symmetryPlane on a slab
    u = spec.wall_speed
    h_in = mesh.points[mesh.faces[mesh.patch_slice("supply")], 2].max()   # the gap at x_in
    with FoamFieldFile(case / "0.orig" / "U") as f:
        f.boundary_field["disc"]["value"] = np.array([u, 0.0, 0.0])
        f.boundary_field["ball"]["origin"] = np.array([0.0, 0.0, spec.contact.radius])
        f.boundary_field["ball"]["omega"] = -u / spec.contact.radius
        f.boundary_field["supply"]["value"] = np.array([u * film / h_in, 0.0, 0.0])
        f.boundary_field["side"] = {"type": side}
    with FoamFieldFile(case / "0.orig" / "alpha.oil") as f:
        f.internal_field = (mesh.cell_centres[:, 0] < x_bridge).astype(float)
        f.boundary_field['"(disc|ball|island)"']["theta0"] = spec.physics.contact_angle
        f.boundary_field["supply"]["value"] = 1.0
        f.boundary_field["side"] = {"type": side}
    with FoamFieldFile(case / "0.orig" / "p_rgh") as f:
        f.boundary_field["side"] = {"type": side}
    edit_physics_dicts(spec, case)
    dt = capillary_time_step(spec, dx)
    edit_run_control(spec, case, end_time, write_interval, min(dt, write_interval))
    shutil.copytree(case / "0.orig", case / "0")
    return dt


def x_at_gap(gap, h: float, x_lo: float, x_hi: float) -> float:
    """The x (m) on y = 0 between x_lo and x_hi where the gap is h (m); NaN where the gap does
    not pass h there."""
    def g(x: float) -> float:
        return float(gap(np.array([x]), np.array([0.0]))[0]) - h
    if not np.isfinite(h) or not g(x_lo) * g(x_hi) <= 0:    # NaN: no film measured
        return float("nan")
    return brentq(g, x_lo, x_hi, xtol=1e-12)


def lateral_speed(folder: Path, mesh: PolyMesh, x_r: float, a: float, u: float) -> float:
    """The rms velocity across y over the cells within a of the rear meniscus x_r (m), by
    volume, over the wall speed u (m/s): the slab's flow should not vary in y at all, so this
    is its lateral spurious current (0 on the strip, whose sides are empty)."""
    near = np.abs(mesh.cell_centres[:, 0] - x_r) < a
    uy = np.asarray(FoamFieldFile(folder / "U").internal_field, float)[near, 1]
    return float(np.sqrt(np.average(uy**2, weights=mesh.cell_volumes[near]))) / u


def measure(case: Path, mesh: PolyMesh, a: float, x_out: float,
            x_edges: np.ndarray | None = None, u: float | None = None) -> list[dict]:
    """At every write: the rear meniscus x_r/a and the gap there (m), the films behind it (m,
    both walls) and the oil held per metre of width (m2); on a slab, over the bins of x
    between ``x_edges`` (m). Given the wall speed u (m/s), also the lateral current around
    the rear meniscus over u (:func:`lateral_speed`)."""
    x, h, _ = columns(mesh, np.zeros(len(mesh.cell_volumes)), x_edges)
    rows = []
    for t, folder in case_fields.time_folders(case):
        alpha = np.asarray(FoamFieldFile(folder / "alpha.oil").internal_field, float)
        _, _, oil = columns(mesh, alpha, x_edges)
        frac = oil / h
        dry = np.flatnonzero(frac < 0.5)
        if not len(dry) or dry[0] == 0:
            continue
        k = dry[0]
        w = (frac[k - 1] - 0.5) / (frac[k - 1] - frac[k])
        x_r = x[k - 1] + w * (x[k] - x[k - 1])
        h_r = h[k - 1] + w * (h[k] - h[k - 1])
        behind = (x > x_r + a) & (x < x_out - 0.5 * a)
        film = float(np.median(oil[behind])) if behind.any() else float("nan")
        rows.append({"t_s": t, "x_rear_over_a": x_r / a, "gap_rear_m": h_r, "film_m": film,
                     "deposited_fraction": film / h_r,
                     "oil_per_width_m2": float(np.sum(np.clip(alpha, 0.0, 1.0) * mesh.cell_volumes)
                                               / np.ptp(mesh.points[:, 1]))})
        if u is not None:
            rows[-1]["lateral_rms_over_u"] = lateral_speed(folder, mesh, x_r, a, u)
    return rows


def run_or_reuse(runtime: FoamRuntime, spec: CaseSpec, case: Path, mesh: PolyMesh,
                 x_bridge: float, args: argparse.Namespace, dx: float,
                 adjust: Callable[[CaseSpec, Path], None] | None = None) -> dict:
    """Write the strip case (then ``adjust(spec, case)`` it, if given) and run it, or, with
    ``--reuse``, take the run already in ``case`` (its ``run.json``) when it ran the same
    time. Returns the run's step limit (s), status, wall time (s) and steps."""
    record = case / "run.json"
    if args.reuse and record.exists():
        run = json.loads(record.read_text())
        if run["end_time_s"] == args.time and run["status"] == "ok":
            return run
    dt = write_strip_case(spec, case, mesh, x_bridge, args.film, dx, args.time,
                          args.time / args.writes)
    if adjust is not None:
        adjust(spec, case)
    apply_edits(case, getattr(args, "edit", []))
    t0 = time.perf_counter()
    proc = runtime.run("interFoam", cwd=case, log_path=case / "log.interFoam", check=False)
    run = {"max_delta_t_s": dt, "end_time_s": args.time,
           "status": "ok" if proc.returncode == 0 else "failed",
           "wall_s": time.perf_counter() - t0, "steps": proc.stdout.count("\nTime = ")}
    record.write_text(json.dumps(run) + "\n")
    return run


def sweep(args: argparse.Namespace) -> Iterator[tuple[str, float, CaseSpec, Callable, float]]:
    """Each (level, dx in a) of --levels x --dx, with its spec (the level and --set), its gap
    h(x, y) and a [m]."""
    for level, dx_a in itertools.product(args.levels, args.dx):
        spec = make_case_spec({"mesh": {"resolution": level}}, **dict(args.set))
        gap, _ = load_gap(spec.contact)
        yield level, dx_a, spec, gap, spec.a


def save_rows(args: argparse.Namespace, rows: list[dict]) -> None:
    """With --save, write the record of a strip sweep so far (its note, options and rows)."""
    if args.save:
        save(args.save, {"note": args.note, "args": {k: str(v) for k, v in vars(args).items()},
                         "rows": rows})


def options_suffix(args: argparse.Namespace) -> str:
    """The part of a strip case's folder name that its --set and --edit options make."""
    return "".join(f"_{k.split('.')[-1]}{v}" for k, v in args.set) + "".join(
        f"_{keys[-1]}{edit_value_text(value, '')}" for _, keys, value in args.edit)


def add_strip_options(ap: argparse.ArgumentParser, dx: list[float], level: str,
                      time_s: float, writes: int, work: Path) -> None:
    """The options the strip benches share, with their defaults: the cells (--dx, a) and
    levels, the run's length and writes, spec edits, where the cases go, --reuse and the
    record (--save, --note), and --edit of the written case's system/ files."""
    ap.add_argument("--dx", nargs="+", type=float, default=dx, help="in-plane cell sizes [a]")
    ap.add_argument("--levels", nargs="+", default=[level],
                    help="levels whose wall layers and capillary safety are used")
    ap.add_argument("--time", type=float, default=time_s, help="simulated time [s]")
    ap.add_argument("--writes", type=int, default=writes, help="writes over the run")
    ap.add_argument("--set", action="append", default=[], type=spec_option,
                    metavar="KEY=VALUE", help="any other spec option (e.g. mesh.n_layers=20)")
    ap.add_argument("--edit", action="append", default=[], type=foam_edit,
                    metavar="FILE:KEY/SUBKEY=VALUE",
                    help="change an entry of a generated system/ file (what the spec does not "
                         "offer, e.g. fvSchemes:snGradSchemes/default=corrected)")
    ap.add_argument("--work", type=Path, default=work)
    ap.add_argument("--reuse", action="store_true",
                    help="measure a case already run to --time in --work instead of re-running")
    ap.add_argument("--save", help="record name under bench/results/ (written after each case)")
    ap.add_argument("--note", default="")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_strip_options(ap, [0.8, 0.4, 0.2, 0.1, 0.05], "coarse", 1.0, 50,
                      ROOT / "runs" / "bench" / "film_deposition")
    ap.add_argument("--film", type=float, default=FILM,
                    help="oil carried in, as a film thickness at the rolling speed [m]")
    ap.add_argument("--x-in", type=float, default=X_IN, help="supply at x = X a")
    ap.add_argument("--x-out", type=float, default=X_OUT, help="outlet at x = X a")
    ap.add_argument("--width", type=float, default=0.0,
                    help="0: the strip, one cell wide; W > 0: a slab W a wide of free quads "
                         "with symmetry planes on both sides")
    ap.add_argument("--aligned", action="store_true",
                    help="with --width: rows of square cells along x instead of free quads")
    args = ap.parse_args(argv)
    for name, value in (("--film", args.film), ("--time", args.time)):
        if not value > 0:
            ap.error(f"{name}: {value} (valid range > 0)")
    if not 0.0 <= args.width <= 10.0:
        ap.error(f"--width {args.width}: valid range 0 (the strip) to 10 (a)")
    if args.aligned and not args.width:
        ap.error("--aligned: a slab's option, give --width W > 0 (a) with it")
    if not 1.5 <= args.x_in < args.x_out:
        ap.error(f"--x-in {args.x_in}, --x-out {args.x_out}: need 1.5 <= x_in < x_out (a)")
    runtime = FoamRuntime.from_environment()
    results = []
    for level, dx_a, spec, gap, a in sweep(args):
        ll = landau_levich(spec.oil_viscosity, spec.speed, spec.physics.surface_tension)
        x_ll = x_at_gap(gap, args.film / ll, args.x_in * a, args.x_out * a)
        x_edges = None
        if args.width:
            mesh = slab_mesh(spec, gap, args.x_in * a, args.x_out * a, dx_a * a, args.width * a,
                             free=not args.aligned)
            x_edges = np.linspace(args.x_in * a, args.x_out * a,
                                  max(int(round((args.x_out - args.x_in) / dx_a)), 1) + 1)
        else:
            mesh = strip_mesh(spec, gap, args.x_in * a, args.x_out * a, dx_a * a)
        strip = ("" if (args.x_in, args.x_out) == (X_IN, X_OUT)
                 else f"_x{args.x_in:g}-{args.x_out:g}") + (
            f"_w{args.width:g}" + ("_aligned" if args.aligned else "") if args.width else "")
        case = args.work / f"{level}_dx{dx_a:g}{strip}{options_suffix(args)}"
        run = run_or_reuse(runtime, spec, case, mesh, x_ll, args, dx_a * a)
        rows = measure(case, mesh, a, args.x_out * a, x_edges, spec.wall_speed)
        late = [r for r in rows if r["t_s"] >= 0.6 * args.time]
        f = float(np.median([r["deposited_fraction"] for r in late])) if late else float("nan")
        lateral = float(np.median([r["lateral_rms_over_u"] for r in late])) if late else float("nan")
        h_star = args.film / f
        result = {"level": level, "dx_over_a": dx_a, "dx_m": dx_a * a, "cells": mesh.n_cells,
                  **run,
                  "landau_levich": ll, "x_rear_landau_levich_over_a": x_ll / a,
                  "deposited_fraction_late_median": f,
                  "deposited_over_landau_levich": f / ll,
                  "lateral_rms_over_u_late_median": lateral,
                  "x_rear_balance_over_a": x_at_gap(gap, h_star, args.x_in * a,
                                                    3 * args.x_out * a) / a,
                  "x_rear_last_over_a": rows[-1]["x_rear_over_a"] if rows else None,
                  "options": dict(args.set),
                  "edits": [f"{file}:{'/'.join(keys)}={edit_value_text(value)}"
                            for file, keys, value in args.edit], "writes": rows}
        results.append(result)
        print(f"{level:>7} dx {dx_a:5.3g} a ({dx_a * a * 1e6:5.1f} um) {mesh.n_cells:6d} cells "
              f"{result['steps']:6d} steps {result['wall_s']:6.0f} s {result['status']}: deposited "
              f"{f * 100:5.2f} % of the gap (LL {ll * 100:4.2f} %, x{f / ll:5.2f}); rear "
              f"{result['x_rear_last_over_a'] or float('nan'):6.2f} a at the end, balance "
              f"{result['x_rear_balance_over_a']:6.2f} a (LL {x_ll / a:5.2f} a); lateral current "
              f"{lateral:5.3f} u rms", flush=True)
        save_rows(args, results)   # after every case: an interrupted sweep keeps them
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
