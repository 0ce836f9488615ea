"""Cost and accuracy of the EHL precalc against grid size.

    python bench/precalc_cost.py [--grids 129 257 513 1025 2049] [--speed 0.01] [--load 20]
        [--temperature 40] [--workers 1 2] [--memory N] [--reuse] [--out FILE.json]
    python bench/precalc_cost.py --quick

The nominal contact (20 N, 40 C, HVI60, the default laws; --load [N], --temperature [C]
change it) at --speed [m/s], solved on each grid of N points a side in a fresh process
(numba compiled beforehand) on each thread count of --workers (the solver's one thread
setting; default: its own choice): wall and CPU time, cycles, peak memory of the process, hc
and hmin, the solve's own estimate of hc's grid error, convergence, and the machine's load
average (timings on a shared machine are noisy); with three grids or more, the observed
order of hc's convergence and its Richardson extrapolation from the three finest, each
grid's hc error against it, and the cost ratio per doubling of N (wall and CPU, per thread
count).
``--memory N`` also runs three cycles on N points a side and reports their peak memory (it is
reached in the first cycle). ``--reuse`` also times the nominal point on its default grid
started from a neighbouring solution (another speed, temperature or load;
``ehlfoam.contact.solver.Start``) against the full multigrid start, on one thread.
``--quick``: grids 129 and 257 at 0.2 m/s, a lighter contact (lower Moes M) that converges on
them in seconds.
"""

from __future__ import annotations

import argparse
import math
import os
import time

from common import add_output_options, print_table, solve_in_subprocess, write_out

NOMINAL = dict(load=20.0, temperature=40.0)


def row_of(n: int, s: dict) -> dict:
    """A table row of one solve's summary."""
    return dict(N=n, threads=s.get("threads"), wall_s=s["wall_s"], cpu_s=s.get("cpu_s"),
                cycles=s.get("cycles"), peak_GiB=s["peak_rss_GiB"],
                hc_nm=s["hc_m"] * 1e9 if s.get("hc_m") else None,
                hmin_nm=s["hmin_m"] * 1e9 if s.get("hmin_m") else None,
                hc_grid_error_estimate=s.get("hc_grid_error"),
                converged=bool(s["converged"]), ramp=bool(s.get("continuation_M")),
                load_average=s.get("load_average", (None,))[0])


def doubling(grids) -> list[int]:
    """The grids of 2**k + 1 points among ``grids``, ascending."""
    return sorted(n for n in set(grids) if (n - 1) & (n - 2) == 0)


def richardson(rows: list[dict]) -> dict:
    """The observed order p of hc over the three finest grids (a doubling apart), the
    extrapolated hc [nm], and each row's hc error against it (every grid's, 769 included)."""
    by_n = {r["N"]: r["hc_nm"] for r in rows}
    h = [by_n[n] for n in doubling(by_n)[-3:]]
    d1, d2 = h[1] - h[0], h[2] - h[1]
    p = math.log2(abs(d1 / d2)) if d1 and d2 else float("nan")
    extrap = h[2] + d2 / (2**p - 1) if math.isfinite(p) and p else float("nan")
    for r in rows:
        r["hc_error"] = abs(r["hc_nm"] - extrap) / extrap if math.isfinite(extrap) else None
    return {"observed_order": p, "hc_extrapolated_nm": extrap}


def per_threads(rows: list[dict]) -> None:
    """The cost ratios per doubling of N (``cost_ratio`` of wall time, ``cpu_ratio``), each
    against the row of half the cells a side on the same thread count (none for a grid
    without one, e.g. 769 among 2**k + 1 grids)."""
    for threads in dict.fromkeys(r["threads"] for r in rows):
        same = {r["N"]: r for r in rows if r["threads"] == threads}
        for n, row in same.items():
            half = same.get((n - 1) // 2 + 1)
            for key, name in (("wall_s", "cost_ratio"), ("cpu_s", "cpu_ratio")):
                ok = half is not None and half.get(key) and row.get(key) is not None
                row[name] = row[key] / half[key] if ok else None


#: neighbours of the nominal point that ``--reuse`` starts it from
NEIGHBOURS = (dict(speed=0.0125), dict(speed=0.02), dict(temperature=35.0),
              dict(temperature=25.0), dict(load=25.0), dict(load=30.0))


def reuse(case: dict) -> dict:
    """The nominal point on its default grid started from each of :data:`NEIGHBOURS` against
    the full multigrid start, on one thread, in this process: CPU time, cycles, hc change."""
    from ehlfoam.contact.threads import numba_threads
    from ehlfoam.contact.solver import Start, solve
    from ehlfoam.contact.spec import make_spec

    with numba_threads(1):
        solve(make_spec(grid=65, max_cycles=2))  # numba's compile
        target = make_spec(**case)
        c0 = time.process_time()
        base = solve(target)
        scratch = time.process_time() - c0
        rows = []
        for kw in NEIGHBOURS:
            nb = solve(make_spec(**{**case, **kw}))
            c0 = time.process_time()
            r = solve(target, start=Start.from_result(nb))
            t = time.process_time() - c0
            rows.append(dict(neighbour=", ".join(f"{k}={v:g}" for k, v in kw.items()),
                             M_from=nb.contact.M, cycles=r.mg.cycles, cpu_s=t,
                             over_fmg=t / scratch,
                             hc_diff=r.summary()["hc_m"] / base.summary()["hc_m"] - 1.0))
    print_table(rows, [("neighbour", "from", ""), ("M_from", "M", ".0f"),
                       ("cycles", "cycles", "d"), ("cpu_s", "CPU [s]", ".1f"),
                       ("over_fmg", "x FMG start", ".2f"), ("hc_diff", "hc change", ".3%")],
                f"start from a neighbour (one thread); the full multigrid start: "
                f"{base.mg.cycles} cycles, {scratch:.1f} s CPU")
    return dict(full_multigrid_cpu_s=scratch, full_multigrid_cycles=base.mg.cycles, rows=rows)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--grids", nargs="+", type=int, default=[129, 257, 513, 1025, 2049],
                    help="points a side, coarse to fine, the three finest a doubling apart "
                         "(others, e.g. 769, between them)")
    ap.add_argument("--speed", type=float, default=0.01, help="rolling speed [m/s]")
    ap.add_argument("--load", type=float, default=NOMINAL["load"], help="load [N]")
    ap.add_argument("--temperature", type=float, default=NOMINAL["temperature"],
                    help="temperature [C]")
    ap.add_argument("--workers", nargs="+", type=int, default=[None],
                    help="thread counts of each solve (default: the solver's own choice)")
    ap.add_argument("--memory", type=int, default=None, metavar="N",
                    help="also the peak memory of three cycles on N points a side")
    ap.add_argument("--reuse", action="store_true",
                    help="also the nominal point started from neighbouring solutions")
    add_output_options(ap)
    args = ap.parse_args(argv)
    if args.quick:
        args.grids, args.speed = [129, 257], 0.2
    case = dict(load=args.load, temperature=args.temperature, speed=args.speed)
    print(f"EHL precalc, {case['load']:g} N, {case['temperature']:g} C, {args.speed:g} m/s, "
          f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}")
    rows = [row_of(n, solve_in_subprocess({**case, "grid": n}, workers=w))
            for n in args.grids for w in args.workers]
    per_threads(rows)
    out: dict = {"case": case, "rows": rows}
    if len(doubling(args.grids)) >= 3:
        out.update(richardson(rows))
    print_table(rows, [("N", "N", "d"), ("wall_s", "wall [s]", ".1f"),
                       ("threads", "threads", "d"), ("cpu_s", "CPU [s]", ".1f"),
                       ("cost_ratio", "x per doubling", ".2f"), ("cpu_ratio", "CPU x", ".2f"),
                       ("cycles", "cycles", "d"), ("peak_GiB", "peak [GiB]", ".2f"),
                       ("hc_nm", "hc [nm]", ".4f"), ("hmin_nm", "hmin [nm]", ".4f"),
                       ("hc_error", "hc error", ".2%"),
                       ("hc_grid_error_estimate", "its estimate", ".2%"),
                       ("converged", "converged", ""),
                       ("ramp", "ramp", ""), ("load_average", "load avg", ".2f")])
    if "observed_order" in out:
        within = [r["N"] for r in rows if (r["hc_error"] or 1.0) <= 0.02]
        ns = doubling(r["N"] for r in rows)
        print(f"observed order {out['observed_order']:.2f} (grids {ns[-3]}, {ns[-2]}, "
              f"{ns[-1]}); Richardson hc {out['hc_extrapolated_nm']:.4f} nm; coarsest grid "
              f"within 2 %: {min(within) if within else None}")
    if args.memory:
        s = solve_in_subprocess({**case, "grid": args.memory, "max_cycles": 3},
                                workers=args.workers[0])
        out["memory"] = dict(N=args.memory, peak_GiB=s["peak_rss_GiB"], wall_s=s["wall_s"],
                             cpu_s=s["cpu_s"])
        print(f"N = {args.memory}, three cycles: peak {s['peak_rss_GiB']:.2f} GiB, "
              f"{s['wall_s']:.0f} s wall, {s['cpu_s']:.0f} s CPU")
    if args.reuse:
        out["reuse"] = reuse(case)
    write_out(args.out, out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
