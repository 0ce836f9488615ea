"""Cost and accuracy of the EHL solver against grid size (nominal case: 20 N, 10 mm/s, 40 C).

    .venv/bin/python bench/ehl_bench.py [--max 2049] [--memory-only 4097]
    .venv/bin/python bench/ehl_bench.py --full 4097

For N = 129 .. --max points a side: wall time (numba compiled beforehand), cycles, peak
memory of the process, hc; the observed order of convergence and the Richardson
extrapolation from the three finest grids; hc error of each grid against that estimate; the
cost ratio per grid doubling. ``--memory-only N`` also runs one grid of N points a side and
reports its peak memory over three cycles (the thesis's scale is 4097). ``--full N`` solves
only that grid to convergence and writes ehl_bench_full_N.json (its wall time, cycles, peak
memory and hc). Otherwise writes
bench/results/ehl_bench.json and ehl_cost_vs_error.png (wall time against hc error).
"""

from __future__ import annotations

import argparse
import math
import os

from common import RESULTS, log, save, solve_in_subprocess

NOMINAL = dict(load=20.0, speed=0.01, temperature=40.0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--max", type=int, default=2049)
    ap.add_argument("--memory-only", type=int, default=None)
    ap.add_argument("--full", type=int, default=None, help="time one full solve on N points")
    args = ap.parse_args()
    if args.full:
        s = solve_in_subprocess({**NOMINAL, "grid": args.full})
        row = dict(N=args.full, wall_s=s["wall_s"], cycles=s["cycles"], peak_GiB=s["peak_rss_GiB"],
                   hc_nm=s["hc_m"] * 1e9, converged=s["converged"], residual=s.get("residual"),
                   load_error=s.get("load_error"), ramp=bool(s["continuation_M"]),
                   cores=os.cpu_count(), load_average=os.getloadavg())
        log(f"N = {args.full}: {row['wall_s']:.0f} s, {row['cycles']} cycles, peak "
            f"{row['peak_GiB']:.2f} GiB, hc = {row['hc_nm']:.4f} nm, converged={row['converged']}")
        save(f"ehl_bench_full_{args.full}.json", {"case": NOMINAL, **row})
        return
    grids = [n for n in (129, 257, 513, 1025, 2049, 4097) if n <= args.max]
    rows = []
    log(f"cores: {os.cpu_count()}")
    log(f"{'N':>6} {'wall [s]':>9} {'cycles':>6} {'peak [GiB]':>10} {'hc [nm]':>9} "
        f"{'converged':>9} {'ramp':>5}")
    for n in grids:
        s = solve_in_subprocess({**NOMINAL, "grid": n})
        rows.append(dict(N=n, wall_s=s["wall_s"], cycles=s["cycles"], peak_GiB=s["peak_rss_GiB"],
                         hc_nm=s["hc_m"] * 1e9, hmin_nm=s["hmin_m"] * 1e9,
                         converged=s["converged"], ramp=bool(s["continuation_M"])))
        r = rows[-1]
        log(f"{n:>6} {r['wall_s']:>9.1f} {r['cycles']:>6} {r['peak_GiB']:>10.2f} "
            f"{r['hc_nm']:>9.4f} {r['converged']!s:>9} {r['ramp']!s:>5}")
    h = [r["hc_nm"] for r in rows]
    out = {"case": NOMINAL, "rows": rows}
    if len(h) >= 3:
        d1, d2 = h[-2] - h[-3], h[-1] - h[-2]
        p = math.log2(abs(d1 / d2)) if d2 else float("nan")
        extrap = h[-1] + d2 / (2**p - 1)
        out.update(observed_order=p, hc_extrapolated_nm=extrap)
        log(f"observed order p = {p:.2f} (grids {rows[-3]['N']}, {rows[-2]['N']}, {rows[-1]['N']}); "
            f"Richardson hc = {extrap:.4f} nm")
        log(f"{'N':>6} {'hc error':>9} {'cost ratio':>10}")
        for k, r in enumerate(rows):
            r["hc_error"] = abs(r["hc_nm"] - extrap) / extrap
            ratio = r["wall_s"] / rows[k - 1]["wall_s"] if k else float("nan")
            r["cost_ratio_per_doubling"] = ratio
            log(f"{r['N']:>6} {100 * r['hc_error']:>8.2f}% {ratio:>10.2f}")
        within = [r["N"] for r in rows if r["hc_error"] <= 0.02]
        log(f"coarsest grid within 2 % of the extrapolated hc: {min(within) if within else None}")
        plot(rows)
    if args.memory_only:
        # the peak is reached in the first cycle: three cycles measure it without the full solve
        s = solve_in_subprocess({**NOMINAL, "grid": args.memory_only, "max_cycles": 3})
        out["memory_run"] = dict(N=args.memory_only, peak_GiB=s["peak_rss_GiB"], wall_s=s["wall_s"],
                                 hc_nm=s["hc_m"] * 1e9, converged=s["converged"], cycles=s["cycles"])
        log(f"N = {args.memory_only} (3 cycles): peak {s['peak_rss_GiB']:.2f} GiB, {s['wall_s']:.0f} s, "
            f"hc = {s['hc_m'] * 1e9:.4f} nm, converged={s['converged']}")
    save("ehl_bench.json", out)


def plot(rows: list[dict]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    err = [max(r["hc_error"], 1e-5) for r in rows]
    ax.loglog([r["wall_s"] for r in rows], err, "o-")
    for r, e in zip(rows, err):
        ax.annotate(f"{r['N']}", (r["wall_s"], e), textcoords="offset points", xytext=(5, 3))
    ax.axhline(0.02, ls="--", c="gray", lw=0.8)
    ax.set_xlabel("wall time on this machine [s]")
    ax.set_ylabel("|hc - hc_Richardson| / hc_Richardson")
    ax.set_title("EHL precalc: cost against error (nominal case)", fontsize=9)
    fig.tight_layout()
    fig.savefig(RESULTS / "ehl_cost_vs_error.png", dpi=120)


if __name__ == "__main__":
    main()
