"""Single phase: the CFD pressure on y = 0 against the Reynolds solution on the same gap.

    python bench/single_phase_check.py [--levels coarse medium fine] [--set KEY=VALUE ...]
        [--work DIR] [--out FILE.json]
    python bench/single_phase_check.py --quick

Oil everywhere (scene "single-phase"), both walls rolling at u (8 mm/s), open boundaries at
p = 0, the island wall in place of the contact, run for 3 ms (the flow is steady within a
fraction of that). The thin-film limit of that flow is the rigid-gap Reynolds equation
(``ehlfoam.thinfilm.rigid``) on the same gap h(x, y) with no flux through the island. The
table gives, per level, the largest and the rms difference of the mid-gap pressure from it on
y = 0 outside r = island + a / 2 (2 a), over the Reynolds peak, with the cells and the wall
time. ``--quick``: the coarse level's cells on a small domain with 3 layers, 1 ms (seconds).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from foamlib import FoamFieldFile
from scipy.interpolate import LinearNDInterpolator

from common import add_output_options, print_table, ratios, spec_option, work_folder, write_out
from ehlfoam.case.geometry import load_geometry
from ehlfoam.case.writer import write_case
from ehlfoam.gap.source import load_gap
from ehlfoam.run import fields as case_fields
from ehlfoam.run.monitor import run_case
from ehlfoam.spec.case import make_case_spec
from ehlfoam.thinfilm.rigid import solve_rigid_reynolds

#: --quick: a small domain, 3 layers, a cheap precalc, 1 ms of flow
QUICK = {"contact.grid": 129, "contact.tol_residual": 1e-4, "mesh.n_layers": 3,
         "mesh.wall_grading": 3.0, "domain.upstream": 5.0, "domain.downstream": 7.0,
         "domain.side": 5.0, "run.end_time": 1e-3}


def cfd_line(case: Path) -> tuple[np.ndarray, np.ndarray]:
    """x [m] and the mid-gap pressure p_rgh [Pa] of the last write on y = 0 outside the island,
    interpolated from the cell centres (mirrored about the symmetry plane)."""
    geom = load_geometry(case)
    st = case_fields.Structure.load(case)
    last = case_fields.time_folders(case)[-1][1]
    p = np.asarray(FoamFieldFile(last / "p_rgh").internal_field, float)
    mid = st.mid_gap(p, geom.n_layers)
    pts = np.column_stack([np.r_[st.base_x, st.base_x], np.r_[st.base_y, -st.base_y]])
    x = np.linspace(geom.x_min, geom.x_max, 800)
    x = x[np.abs(x) > geom.island_radius]
    p_line = LinearNDInterpolator(pts, np.r_[mid, mid])(x, np.zeros_like(x))
    ok = np.isfinite(p_line)
    return x[ok], p_line[ok]


def check(level: str, overrides: dict, case: Path) -> dict:
    """Write and run the level's single-phase case; its row of the table."""
    spec = make_case_spec({"scene": "single-phase", "contact": {"speed": 0.008},
                           "mesh": {"resolution": level},
                           "run": {"end_time": 3e-3, "writes_per_transit": 200}}, **overrides)
    t0 = time.perf_counter()
    geom = write_case(spec, case, overwrite=True)
    m = run_case(case)
    x_cfd, p_cfd = cfd_line(case)
    gap, _ = load_gap(spec.contact)
    ref = solve_rigid_reynolds(gap, (geom.x_min, geom.x_max), (-geom.y_max, geom.y_max),
                               cell=geom.a / 40, viscosity=spec.oil_viscosity,
                               speed=geom.speed, island_radius=geom.island_radius)
    xr, pr = ref.line(0.0)
    ok = np.isfinite(pr)
    p_ref = np.interp(x_cfd, xr[ok], pr[ok])
    outside = np.abs(x_cfd) > geom.island_radius + 0.5 * geom.a
    scale = float(np.max(np.abs(pr[ok])))
    err = np.abs(p_cfd - p_ref)[outside]
    return {"level": level, "cells": geom.cells, "n_layers": geom.n_layers,
            "p_ref_max_Pa": scale, "p_cfd_max_Pa": float(np.max(np.abs(p_cfd))),
            "max_error_over_pmax": float(err.max() / scale),
            "rms_error_over_pmax": float(np.sqrt(np.mean(err**2)) / scale),
            "status": m["status"], "wall_s": time.perf_counter() - t0}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--levels", nargs="+", default=["coarse", "medium", "fine"],
                    choices=["coarse", "medium", "fine"])
    ap.add_argument("--set", action="append", default=[], type=spec_option,
                    metavar="KEY=VALUE", help="a spec option for every level (repeatable), "
                                              "e.g. physics.interface_schemes=balanced")
    add_output_options(ap, work=True)
    args = ap.parse_args(argv)
    overrides = dict(args.set)
    if args.quick:
        args.levels, overrides = ["coarse"], {**QUICK, **overrides}
    with work_folder(args.work) as work:
        rows = [check(level, overrides, work / level) for level in args.levels]
    ratios(rows, "wall_s", "wall_ratio")
    print_table(rows, [("level", "level", ""), ("cells", "cells", "d"),
                       ("n_layers", "layers", "d"), ("p_ref_max_Pa", "Reynolds peak [Pa]", ".1f"),
                       ("p_cfd_max_Pa", "CFD peak [Pa]", ".1f"),
                       ("max_error_over_pmax", "max error / peak", ".2%"),
                       ("rms_error_over_pmax", "rms error / peak", ".2%"),
                       ("status", "status", ""), ("wall_s", "wall [s]", ".1f"),
                       ("wall_ratio", "x wall", ".2f")],
                "single phase: mid-gap pressure on y = 0 outside r = 2 a vs rigid-gap Reynolds")
    write_out(args.out, {"set": overrides, "rows": rows})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
