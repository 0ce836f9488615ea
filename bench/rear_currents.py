"""The velocity across y around the rear meniscus of finished 3D cases, over u.

The rear meniscus lays the films that carry the flooded region's oil away, and a slab (the
strip's y-invariant flow with room across y, ``bench/film_deposition.py --width``) shows that
currents across y there change those films. In a 3D case some lateral flow is real; this reads
how much there is in the last write, in a box beside the rear meniscus on the axis x_r
(``bench/wall_films.py``'s): |x - x_r| < ``--half-length`` and ``--y-from`` < |y| < ``--y-to``
(a). Per box: the rms of U_y over u, by volume, in the oil (alpha > 0.95), the air
(alpha < 0.05) and the interface cells between, and that of the gap-averaged U_y (the part
that carries oil round the meniscus) by footprint. docs/cases.md, "Lateral currents".

A CASE that is a state of the thin-film model (``bench/thin_film_region.py``'s ``.npz``, which
holds its pressure) gets the same box beside that model's rear meniscus on the axis: the rms of
its gap-averaged U_y = -(h^2 / (12 eta)) dp/dy over u in the flooded cells (the model's
oil; its open cells carry nothing across y), and that of the Poiseuille profile across the gap
which that mean stands for, sqrt(6/5) times it, beside the 3D cases' oil figure. There the
lateral flow is the physics of the gap-averaged model alone: no interface, no parasitic
current. ``--spec`` names the spec whose oil and speed the state was run with.

    python bench/rear_currents.py CASE [CASE ...] [--half-length 0.5] [--y-from 0.5]
        [--y-to 1.5] [--spec runs/nominal.toml] [--save NAME.json]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from foamlib import FoamFieldFile

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.common import save  # noqa: E402
from ehlfoam.thinfilm.state import load_state
from bench.wall_films import rear_meniscus  # noqa: E402
from ehlfoam.spec.case import CaseSpec, load_case_spec
from ehlfoam.case.geometry import load_geometry, load_spec_of
from ehlfoam.run import fields as case_fields

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


def thin_film_currents(state: Path, spec: CaseSpec, half_length: float = 0.5,
                       y_from: float = 0.5, y_to: float = 1.5) -> dict:
    """In a thin-film state (``bench/thin_film_region.py``'s ``.npz`` with its pressure, run
    with ``spec``): the rear meniscus on the axis x_r [a] and, over the flooded
    region's cells in the box |x - x_r| < half_length, y_from <= y < y_to [a], the rms of the
    gap-averaged velocity across y over u, its median size (the bulk's, without the few
    cells where the region's staircase edge turns the flow), and sqrt(6/5) times the rms (the
    rms across the gap of the Poiseuille profile with that mean: the 3D cases' oil figure)."""
    a, u, eta = spec.a, spec.speed, spec.oil_viscosity
    sol = load_state(state)
    if not np.isfinite(sol.p).any():
        raise ValueError(f"{state}: holds no pressure (written before the states kept it); "
                         "run bench/thin_film_region.py again")
    grid, h, p = sol.grid, sol.grid.h, sol.p
    region = sol.region()
    x_r = sol.metrics(a)["rear_meniscus_x_over_a"]
    if x_r is None:
        raise ValueError(f"{state}: no flooded cell behind the island on the axis")
    # U_y on the y faces between two flooded cells with a pressure (a cell that flooded in
    # the march's last step has none yet), then the mean of a cell's faces
    solved = region & np.isfinite(p)
    both = solved[1:] & solved[:-1]
    h_face = 0.5 * (h[1:] + h[:-1])
    v = np.where(both, -h_face**2 / (12.0 * eta) * (p[1:] - p[:-1]) / grid.cell, 0.0)
    total = np.zeros(h.shape)
    count = np.zeros(h.shape)
    for sl in (np.s_[1:], np.s_[:-1]):
        total[sl] += v
        count[sl] += both
    uy = np.where(count > 0, total / np.maximum(count, 1), 0.0) / u
    X, Y = np.meshgrid(grid.x / a, grid.y / a)
    box = region & (np.abs(X - x_r) < half_length) & (Y >= y_from) & (Y < y_to)
    gap_rms = float(np.sqrt(np.mean(uy[box] ** 2))) if box.any() else None
    return {"case": str(state), "model": "thin-film", "rear_over_a": x_r,
            "box_over_a": [half_length, y_from, y_to], "cells": int(box.sum()),
            "cell_over_a": grid.cell / a, "gap_averaged_rms_over_u": gap_rms,
            "gap_averaged_median_abs_over_u": float(np.median(np.abs(uy[box])))
            if box.any() else None,
            "poiseuille_rms_over_u": None if gap_rms is None else gap_rms * np.sqrt(1.2)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="+", type=Path)
    ap.add_argument("--half-length", type=float, default=0.5, help="box: |x - x_r| < L [a]")
    ap.add_argument("--y-from", type=float, default=0.5, help="box: |y| from [a]")
    ap.add_argument("--y-to", type=float, default=1.5, help="box: |y| below [a]")
    ap.add_argument("--spec", type=Path, default=Path("runs/nominal.toml"),
                    help="the spec of thin-film states (.npz)")
    ap.add_argument("--save", help="write the rows to bench/results/NAME.json")
    args = ap.parse_args(argv)
    if not (args.half_length > 0 and 0 <= args.y_from < args.y_to):
        ap.error(f"--half-length {args.half_length}, --y-from {args.y_from}, --y-to {args.y_to}: "
                 "need L > 0 and 0 <= y_from < y_to (a)")
    box = (args.half_length, args.y_from, args.y_to)
    spec = load_case_spec(args.spec) if any(c.suffix == ".npz" for c in args.cases) else None
    rows = [thin_film_currents(c, spec, *box) if c.suffix == ".npz"
            else rear_currents(c, *box) for c in args.cases]
    print(f"{'case':56s} {'transits':>8s} {'rear (a)':>8s} | U_y rms / u: oil    air  interface"
          "  gap-averaged")
    fmt = lambda v: "     -" if v is None else f"{v:6.3f}"  # noqa: E731
    for r in rows:
        oil = r.get("oil_rms_over_u", r.get("poiseuille_rms_over_u"))
        transits = f"{r['transits']:8.3f}" if "transits" in r else "  (model)"
        print(f"{r['case'][-56:]:56s} {transits:>8s} {r['rear_over_a']:8.2f} | "
              f"{fmt(oil)} {fmt(r.get('air_rms_over_u'))}     "
              f"{fmt(r.get('interface_rms_over_u'))}        {fmt(r['gap_averaged_rms_over_u'])}")
    if args.save:
        print(f"wrote {save(args.save, rows)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
