"""Cost and accuracy of the EHL precalc against grid size (nominal case: 20 N, 10 mm/s, 40 C).

    .venv/bin/python bench/ehl_bench.py [--max 4097] [--workers 1 2]
    .venv/bin/python bench/ehl_bench.py --reuse

For N = 257 .. --max points a side, each solve in a fresh process (numba compiled before
the clock starts) on each thread count of --workers (the solver's one thread setting): wall
and CPU time, cycles, peak memory of the process, hc; the observed order and the Richardson
value of hc from the three finest grids, each grid's hc error against it, and the cost ratio
per grid doubling (wall time, per thread count). The machine's load average is printed with
each row: timings on a shared machine are noisy. Writes bench/results/ehl_bench.json.

``--reuse`` times the nominal point on its default grid started from a neighbouring solution
(another speed, temperature or load; ehlfoam.contact.solver.Start) against the full
multigrid start, on one thread, and writes bench/results/ehl_bench_reuse.json.
"""

from __future__ import annotations

import argparse
import math
import os

from common import log, save, solve_in_subprocess

NOMINAL = dict(load=20.0, speed=0.01, temperature=40.0)
GRIDS = (257, 513, 1025, 2049, 4097)
NEIGHBOURS = (dict(speed=0.0125), dict(speed=0.02), dict(temperature=35.0),
              dict(temperature=25.0), dict(load=25.0), dict(load=30.0))


def grid_table(grids: list[int], workers: list[int]) -> dict:
    rows = []
    log(f"cores: {os.cpu_count()}, load average now {os.getloadavg()}")
    log(f"{'N':>6} {'threads':>7} {'wall [s]':>9} {'CPU [s]':>8} {'cycles':>6} {'peak [GiB]':>10} "
        f"{'hc [nm]':>9} {'conv':>5} {'load avg':>9}")
    for n in grids:
        for w in workers:
            s = solve_in_subprocess({**NOMINAL, "grid": n}, workers=w)
            rows.append(dict(N=n, workers=w, wall_s=s["wall_s"], cpu_s=s["cpu_s"],
                             cycles=s["cycles"], peak_GiB=s["peak_rss_GiB"],
                             hc_nm=s["hc_m"] * 1e9, hmin_nm=s["hmin_m"] * 1e9,
                             converged=s["converged"], load_average=s["load_average"]))
            r = rows[-1]
            log(f"{n:>6} {w:>7} {r['wall_s']:>9.1f} {r['cpu_s']:>8.1f} {r['cycles']:>6} "
                f"{r['peak_GiB']:>10.2f} {r['hc_nm']:>9.4f} {r['converged']!s:>5} "
                f"{r['load_average'][0]:>9.2f}")
    out = {"case": NOMINAL, "rows": rows}
    by_n = {r["N"]: r["hc_nm"] for r in rows}
    ns = sorted(by_n)
    if len(ns) >= 3:
        h = [by_n[n] for n in ns[-3:]]
        d1, d2 = h[1] - h[0], h[2] - h[1]
        p = math.log2(abs(d1 / d2)) if d2 else float("nan")
        extrap = h[2] + d2 / (2**p - 1)
        out.update(observed_order=p, hc_richardson_nm=extrap)
        log(f"observed order p = {p:.2f} (grids {ns[-3]}, {ns[-2]}, {ns[-1]}); Richardson hc = "
            f"{extrap:.4f} nm")
        log(f"{'N':>6} {'threads':>7} {'hc error':>9} {'wall ratio':>10} {'CPU ratio':>9}")
        prev: dict[int, dict] = {}
        for r in rows:
            r["hc_error"] = abs(r["hc_nm"] - extrap) / extrap
            last = prev.get(r["workers"])
            r["wall_ratio_per_doubling"] = r["wall_s"] / last["wall_s"] if last else None
            r["cpu_ratio_per_doubling"] = r["cpu_s"] / last["cpu_s"] if last else None
            prev[r["workers"]] = r
            wr = f"{r['wall_ratio_per_doubling']:.2f}" if last else "-"
            cr = f"{r['cpu_ratio_per_doubling']:.2f}" if last else "-"
            log(f"{r['N']:>6} {r['workers']:>7} {100 * r['hc_error']:>8.2f}% {wr:>10} {cr:>9}")
    return out


def reuse_table() -> dict:
    """Neighbour start against the full multigrid start (one thread)."""
    from ehlfoam.contact.multigrid import numba_threads

    with numba_threads(1):
        return _reuse_rows()


def _reuse_rows() -> dict:
    import time

    from ehlfoam.contact.solver import Start, solve
    from ehlfoam.contact.spec import make_spec

    solve(make_spec(grid=65, max_cycles=2))
    target = make_spec(**NOMINAL)
    c0 = time.process_time()
    base = solve(target)
    scratch = time.process_time() - c0
    log(f"full multigrid start: {base.mg.cycles} cycles, {scratch:.1f} s CPU, "
        f"hc {base.summary()['hc_m'] * 1e9:.4f} nm")
    rows = []
    for kw in NEIGHBOURS:
        nb = solve(make_spec(**{**NOMINAL, **kw}))
        c0 = time.process_time()
        r = solve(target, start=Start.from_result(nb))
        t = time.process_time() - c0
        rows.append(dict(neighbour=kw, M_from=nb.contact.M, cycles=r.mg.cycles, cpu_s=t,
                         ratio=t / scratch,
                         hc_diff=r.summary()["hc_m"] / base.summary()["hc_m"] - 1.0))
        log(f"from {kw} (M {nb.contact.M:.0f}): {r.mg.cycles} cycles, {t:.1f} s CPU = "
            f"{t / scratch:.2f} x the FMG start, hc {100 * rows[-1]['hc_diff']:+.3f} %")
    return dict(full_multigrid_cpu_s=scratch, full_multigrid_cycles=base.mg.cycles, rows=rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--max", type=int, default=4097)
    ap.add_argument("--min", type=int, default=257)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--reuse", action="store_true")
    args = ap.parse_args()
    if args.reuse:
        save("ehl_bench_reuse.json", reuse_table())
        return
    grids = [n for n in GRIDS if args.min <= n <= args.max]
    save("ehl_bench.json", grid_table(grids, args.workers))


if __name__ == "__main__":
    main()
