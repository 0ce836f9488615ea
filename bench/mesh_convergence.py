"""Mesh convergence of the flow pattern: the same case on several meshes, compared at the same
simulated times (from each case's history.csv, so that runs stopped at different times compare)
or at their last state (``--final``, the mean over each case's last transit), and, given the cell size that
sets each mesh apart (``--sizes``), the observed order, the Richardson extrapolation and the
grid convergence index of every metric over each three meshes in a row.

    python bench/mesh_convergence.py CASE_COARSE CASE_MEDIUM CASE_FINE [--transits 1 2]
        [--final] [--sizes H_COARSE H_MEDIUM H_FINE] [--save NAME.json] [--note TEXT]

The estimate follows Celik et al. 2008 (J. Fluids Eng. 130, 078001; the procedure of the
journal's policy on numerical uncertainty): with h1 < h2 < h3 and the changes e21 = f2 - f1,
e32 = f3 - f2, R = e21 / e32 says how the metric behaves: 0 < R < 1 monotone convergence (the
changes shrink), -1 < R < 0 oscillatory convergence, R >= 1 or R <= -1 divergence (the changes
do not shrink; no extrapolation, no index). For a converging metric the order p solves
p ln r21 = |ln|e32 / e21| + ln((r21^p - s) / (r32^p - s))| (s = sign(e32 / e21)), the
extrapolated value is (r21^p f1 - f2) / (r21^p - 1) and the fine mesh's index GCI = 1.25
|e21 / f1| / (r21^p - 1). Writes ``bench/results/NAME.json`` (default mesh_convergence.json).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.common import save  # noqa: E402
from generator.case_writer import load_geometry  # noqa: E402

KEYS = ("inlet_meniscus_distance_over_a", "flooded_width_over_a", "flooded_length_over_a",
        "oil_volume_m3")
SAFETY = 1.25   # Celik et al.'s factor of safety for three meshes
#: observed orders outside this range say the meshes are not in the asymptotic range (the
#: schemes are of order 1-2): the extrapolation and the index are then not to be trusted
ASYMPTOTIC_ORDER = (0.5, 3.0)


def observed_order(h: tuple[float, float, float], f: tuple[float, float, float],
                   noise: float = 0.0, tol: float = 1e-10, max_iter: int = 200) -> dict:
    """Observed order, Richardson extrapolation and grid convergence index of a metric ``f``
    on three meshes of representative cell sizes ``h`` (any order, any one unit).

    Returns ``behaviour`` ("monotone", "oscillatory", "divergent", "unchanged", or "within
    noise" where both changes are at most ``noise``, the metric's own jitter in the units of
    ``f``: then the changes say nothing about the order) and ``R = e21 / e32``; for a converging metric also ``order`` p, ``extrapolated`` (the
    Richardson value), ``gci_fine`` (the fine mesh's relative uncertainty band, with
    safety factor 1.25), ``error_fine`` (|f1 - f_ext| / |f_ext|) and ``asymptotic`` (p within
    :data:`ASYMPTOTIC_ORDER`: otherwise neither the extrapolation nor the index holds). Index 1 is the finest.
    """
    (h1, f1), (h2, f2), (h3, f3) = sorted(zip(h, f))
    if not (0 < h1 < h2 < h3):
        raise ValueError(f"sizes: need three different positive cell sizes, got {h}")
    r21, r32 = h2 / h1, h3 / h2
    e21, e32 = f2 - f1, f3 - f2
    out: dict = {"sizes": [h1, h2, h3], "values": [f1, f2, f3], "r21": r21, "r32": r32}
    if max(abs(e21), abs(e32)) <= noise:
        return out | {"behaviour": "within noise", "R": e21 / e32 if e32 else None,
                      "spread": max(f) - min(f)}
    if e21 == 0.0 and e32 == 0.0:
        return out | {"behaviour": "unchanged", "R": None, "order": None,
                      "extrapolated": f1, "gci_fine": 0.0, "error_fine": 0.0}
    if e32 == 0.0:
        return out | {"behaviour": "divergent", "R": None}
    R = e21 / e32
    out["R"] = R
    if abs(R) >= 1.0:
        return out | {"behaviour": "divergent"}
    if e21 == 0.0:   # converged on the two finest: no order to read
        return out | {"behaviour": "monotone", "order": None, "extrapolated": f1,
                      "gci_fine": 0.0, "error_fine": 0.0}
    s = math.copysign(1.0, e32 / e21)
    p = abs(math.log(abs(e32 / e21))) / math.log(r21)
    for _ in range(max_iter):
        q = math.log((r21 ** p - s) / (r32 ** p - s))
        p_new = abs(math.log(abs(e32 / e21)) + q) / math.log(r21)
        if abs(p_new - p) < tol:
            p = p_new
            break
        p = p_new
    ext = (r21 ** p * f1 - f2) / (r21 ** p - 1.0)
    lo, hi = ASYMPTOTIC_ORDER
    return out | {"behaviour": "monotone" if R > 0 else "oscillatory", "order": p,
                  "asymptotic": lo <= p <= hi,
                  "extrapolated": ext,
                  "gci_fine": SAFETY * abs(e21 / f1) / (r21 ** p - 1.0),
                  "error_fine": abs((f1 - ext) / ext) if ext else None}


def _jitter(rows: list[dict]) -> dict:
    """Per metric, the standard deviation over ``rows`` (0 for fewer than two values)."""
    out = {}
    for k in KEYS:
        vals = np.array([float(r[k]) for r in rows if r[k] not in ("", "None")])
        out[k] = float(vals.std()) if vals.size > 1 else 0.0
    return out


def at_time(case: Path, t: float) -> dict | None:
    """The case's write nearest ``t`` [s] (None if none lies within 2 %), with each metric's
    jitter over the writes of the quarter transit up to it."""
    rows = list(csv.DictReader(open(case / "history.csv")))
    best = min(rows, key=lambda r: abs(float(r["time_s"]) - t))
    tb = float(best["time_s"])
    if abs(tb - t) > 0.02 * t:
        return None
    window = 0.25 * load_geometry(case).transit_time
    recent = [r for r in rows if tb - window <= float(r["time_s"]) <= tb]
    return {k: (float(best[k]) if best[k] not in ("", "None") else None) for k in KEYS} | {
        "time_s": tb, "state": best["state"], "jitter": _jitter(recent)}


def final(case: Path) -> dict:
    """The case's last state: each metric's mean over the last transit of its history.csv
    (one write alone carries the meniscus's cell-to-cell jitter), and that jitter (the standard
    deviation over the same writes)."""
    rows = list(csv.DictReader(open(case / "history.csv")))
    t_end = float(rows[-1]["time_s"])
    last = [r for r in rows if float(r["time_s"]) >= t_end - load_geometry(case).transit_time]
    means = {}
    for k in KEYS:
        vals = [float(r[k]) for r in last if r[k] not in ("", "None")]
        means[k] = sum(vals) / len(vals) if vals else None
    return means | {"time_s": t_end, "state": rows[-1]["state"], "writes_averaged": len(last),
                    "jitter": _jitter(last)}


def orders(names: list[str], sizes: list[float], levels: dict) -> dict:
    """observed_order of every metric over each three cases in a row (ordered as given); the
    noise is twice the largest jitter of the three (over the last transit with ``--final``,
    over the quarter transit up to the write compared otherwise)."""
    out = {}
    for i in range(len(names) - 2):
        trio = names[i:i + 3]
        for k in KEYS:
            vals = [levels[n].get(k) for n in trio]
            if None not in vals:
                noise = 2 * max(levels[n].get("jitter", {}).get(k, 0.0) for n in trio)
                out.setdefault(" / ".join(trio), {})[k] = observed_order(
                    tuple(sizes[i:i + 3]), tuple(vals), noise=noise)
    return out


def _fmt(k: str, v: float | None) -> str:
    if v is None:
        return "-"
    return f"{v * 1e12:.1f} nl" if k == "oil_volume_m3" else f"{v:.3f}"


def _print_orders(trios: dict) -> None:
    for trio, per_key in trios.items():
        print(f"  over {trio}:")
        for k, o in per_key.items():
            line = f"    {k:32s} {o['behaviour']:11s}"
            if o.get("R") is not None:
                line += f" R {o['R']:+.2f}"
            if o.get("spread") is not None:
                line += f"  spread {_fmt(k, o['spread'])}"
            if o.get("order") is not None:
                line += (f"  p {o['order']:.2f}  extrapolated {_fmt(k, o['extrapolated'])}"
                         f"  GCI(fine) {100 * o['gci_fine']:.1f} %")
                if not o["asymptotic"]:
                    line += "  (order outside 0.5-3: not asymptotic, not to be trusted)"
            print(line)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="+")
    ap.add_argument("--transits", nargs="+", type=float, default=[1.0, 2.0])
    ap.add_argument("--final", action="store_true",
                    help="compare each case's last transit (mean), not equal times")
    ap.add_argument("--sizes", nargs="+", type=float,
                    help="the cell size that sets each case's mesh apart (one per case, any "
                         "one unit): adds the observed order, extrapolation and GCI")
    ap.add_argument("--save", default="mesh_convergence.json",
                    help="record name under bench/results/")
    ap.add_argument("--note", default="")
    args = ap.parse_args(argv)
    cases = [Path(c) for c in args.cases]
    if args.sizes is not None and (len(args.sizes) != len(cases) or len(cases) < 3):
        ap.error(f"--sizes: need one size per case and at least three cases, got "
                 f"{len(args.sizes)} sizes for {len(cases)} cases")
    names = [f"{c.parent.name}/{c.name}" for c in cases]
    samples = ([("final", None)] if args.final else
               [(f"{n:g} transits", n * load_geometry(cases[0]).transit_time)
                for n in args.transits])
    out = []
    for label, t in samples:
        levels = {}
        for name, case in zip(names, cases):
            vals = final(case) if t is None else (at_time(case, t) or {})
            levels[name] = {"cells": load_geometry(case).cells} | vals
        row = {"sample": label, "time_s": t, "levels": levels}
        print(label if t is None else f"t = {t:.4f} s ({label})")
        for name, v in levels.items():
            vals = "  ".join(f"{k.removesuffix('_over_a')} {_fmt(k, v.get(k))}" for k in KEYS)
            print(f"  {name:40s} {v['cells']:7d} cells  {v.get('state', '-')}  {vals}")
        if args.sizes is not None:
            row["orders"] = orders(names, args.sizes, levels)
            _print_orders(row["orders"])
        out.append(row)
    path = save(args.save, {"note": args.note, "cases": [str(c) for c in cases],
                            "sizes": args.sizes, "samples": out})
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
