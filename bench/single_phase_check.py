"""Single-phase check: the CFD pressure on y = 0 against the Reynolds solution on the same gap.

Oil everywhere (scene "single-phase"), both walls rolling at u, open boundaries at p = 0, the
island wall in place of the contact. The thin-film limit of that flow is the rigid-gap Reynolds
equation (``ehlfoam.thinfilm.rigid``) on the same gap h(x, y), with no flux through the
island. Prints the pressure error on y = 0 outside the island per resolution level and writes
``bench/results/single_phase_check.{json,png}``.

    python bench/single_phase_check.py [--levels coarse medium fine] [--speed 0.008]
        [--set KEY=VALUE ...] [--tag NAME]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from foamlib import FoamFieldFile  # noqa: E402

from ehlfoam.thinfilm.rigid import solve_rigid_reynolds
from ehlfoam.spec.case import make_case_spec
from ehlfoam.case.geometry import load_geometry
from ehlfoam.case.writer import write_case
from ehlfoam.gap.source import load_gap
from common import spec_option  # noqa: E402
from ehlfoam.run import fields as case_fields
from ehlfoam.run.monitor import run_case

RESULTS = ROOT / "bench" / "results"


def cfd_line(case: Path) -> tuple[np.ndarray, np.ndarray]:
    """Mid-gap pressure of the last written time along the cells nearest to y = 0."""
    geom = load_geometry(case)
    st = case_fields.Structure.load(case)
    last = case_fields.time_folders(case)[-1][1]
    p = np.asarray(FoamFieldFile(last / "p_rgh").internal_field, float)
    mid = st.mid_gap(p, geom.n_layers)
    # interpolate on y = 0 from the cell centres mirrored about the symmetry plane
    from scipy.interpolate import LinearNDInterpolator

    pts = np.column_stack([np.r_[st.base_x, st.base_x], np.r_[st.base_y, -st.base_y]])
    interp = LinearNDInterpolator(pts, np.r_[mid, mid])
    x = np.linspace(geom.x_min, geom.x_max, 800)
    x = x[np.abs(x) > geom.island_radius]
    p_line = interp(x, np.zeros_like(x))
    ok = np.isfinite(p_line)
    return x[ok], p_line[ok]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", nargs="+", default=["coarse", "medium", "fine"])
    ap.add_argument("--speed", type=float, default=0.008)
    ap.add_argument("--work", default=str(ROOT / "runs" / "checks" / "single_phase"))
    ap.add_argument("--set", action="append", default=[], type=spec_option, metavar="KEY=VALUE",
                    help="any other spec option for every case (e.g. "
                         "physics.interface_schemes=balanced)")
    ap.add_argument("--tag", default="", help="results go to single_phase_check[_TAG].*; "
                                              "cases to WORK[_TAG]/LEVEL")
    args = ap.parse_args(argv)
    suffix = f"_{args.tag}" if args.tag else ""
    out = []
    lines = {}
    for level in args.levels:
        spec = make_case_spec({"name": f"single-phase-{level}", "scene": "single-phase",
                               "contact": {"speed": args.speed},
                               "mesh": {"resolution": level},
                               "run": {"end_time": 3e-3, "writes_per_transit": 200}},
                              **dict(args.set))
        case = Path(args.work + suffix) / level
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
        scale = np.max(np.abs(pr[ok]))
        err = np.abs(p_cfd - p_ref)[outside]
        row = {"level": level, "options": dict(args.set), "cells": geom.cells,
               "n_layers": geom.n_layers,
               "p_ref_max_Pa": float(scale), "p_cfd_max_Pa": float(np.max(np.abs(p_cfd))),
               "max_error_over_pmax": float(err.max() / scale),
               "rms_error_over_pmax": float(np.sqrt(np.mean(err**2)) / scale),
               "status": m["status"], "wall_s": time.perf_counter() - t0}
        print(json.dumps(row), flush=True)
        out.append(row)
        lines[level] = (x_cfd, p_cfd)
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / f"single_phase_check{suffix}.json").write_text(json.dumps(out, indent=2) + "\n")
    _plot(lines, (xr, pr), geom, RESULTS / f"single_phase_check{suffix}.png")
    return 0


def _plot(lines, ref, geom, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    xr, pr = ref
    ax.plot(xr / geom.a, pr / 1e3, "k-", lw=2, label="Reynolds, same gap")
    for level, (x, p) in lines.items():
        ax.plot(x / geom.a, p / 1e3, ".", ms=3, label=f"interFoam, {level}")
    ax.axvspan(-geom.island_radius / geom.a, geom.island_radius / geom.a, color="0.85",
               label="island (contact)")
    ax.set_xlabel("x / a (y = 0)")
    ax.set_ylabel("p [kPa]")
    ax.legend(fontsize=8)
    ax.set_title("Single phase: pressure on y = 0, CFD vs Reynolds")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    raise SystemExit(main())
