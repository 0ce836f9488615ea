"""Cost and accuracy of the EHL precalc against grid size.

    python bench/precalc_cost.py [--grids 129 257 513 1025 2049] [--speed 0.01]
        [--memory N] [--out FILE.json]
    python bench/precalc_cost.py --quick

The nominal contact (20 N, 40 C, HVI60, the default laws) at --speed [m/s], solved on each
grid of N points a side in a fresh process (numba compiled beforehand): wall time, cycles,
peak memory of the process, hc and hmin, convergence; with three grids or more, the observed
order of hc's convergence and its Richardson extrapolation from the three finest, each grid's
hc error against it, and the cost ratio per doubling of N. ``--memory N`` also runs three
cycles on N points a side and reports their peak memory (it is reached in the first cycle).
``--quick``: grids 129 and 257 at 0.2 m/s, a lighter contact (lower Moes M) that converges on
them in seconds.
"""

from __future__ import annotations

import argparse
import math
import os

from common import add_output_options, print_table, ratios, solve_in_subprocess, write_out

NOMINAL = dict(load=20.0, temperature=40.0)


def row_of(n: int, s: dict) -> dict:
    """A table row of one solve's summary."""
    return dict(N=n, wall_s=s["wall_s"], cycles=s.get("cycles"), peak_GiB=s["peak_rss_GiB"],
                hc_nm=s["hc_m"] * 1e9 if s.get("hc_m") else None,
                hmin_nm=s["hmin_m"] * 1e9 if s.get("hmin_m") else None,
                converged=bool(s["converged"]), ramp=bool(s.get("continuation_M")))


def richardson(rows: list[dict]) -> dict:
    """The observed order p of hc over the three finest grids (a doubling apart), the
    extrapolated hc [nm], and each row's hc error against it."""
    h = [r["hc_nm"] for r in rows[-3:]]
    d1, d2 = h[1] - h[0], h[2] - h[1]
    p = math.log2(abs(d1 / d2)) if d1 and d2 else float("nan")
    extrap = h[2] + d2 / (2**p - 1) if math.isfinite(p) and p else float("nan")
    for r in rows:
        r["hc_error"] = abs(r["hc_nm"] - extrap) / extrap if math.isfinite(extrap) else None
    return {"observed_order": p, "hc_extrapolated_nm": extrap}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--grids", nargs="+", type=int, default=[129, 257, 513, 1025, 2049],
                    help="points a side, coarse to fine, a doubling apart")
    ap.add_argument("--speed", type=float, default=0.01, help="rolling speed [m/s]")
    ap.add_argument("--memory", type=int, default=None, metavar="N",
                    help="also the peak memory of three cycles on N points a side")
    add_output_options(ap)
    args = ap.parse_args(argv)
    if args.quick:
        args.grids, args.speed = [129, 257], 0.2
    case = {**NOMINAL, "speed": args.speed}
    print(f"EHL precalc, {case['load']:g} N, {case['temperature']:g} C, {args.speed:g} m/s, "
          f"{os.cpu_count()} cores")
    rows = [row_of(n, solve_in_subprocess({**case, "grid": n})) for n in args.grids]
    ratios(rows, "wall_s", "cost_ratio")
    out: dict = {"case": case, "rows": rows}
    if len(rows) >= 3:
        out.update(richardson(rows))
    print_table(rows, [("N", "N", "d"), ("wall_s", "wall [s]", ".1f"),
                       ("cost_ratio", "x per doubling", ".2f"), ("cycles", "cycles", "d"),
                       ("peak_GiB", "peak [GiB]", ".2f"), ("hc_nm", "hc [nm]", ".4f"),
                       ("hmin_nm", "hmin [nm]", ".4f"), ("hc_error", "hc error", ".2%"),
                       ("converged", "converged", ""), ("ramp", "ramp", "")])
    if "observed_order" in out:
        within = [r["N"] for r in rows if (r["hc_error"] or 1.0) <= 0.02]
        print(f"observed order {out['observed_order']:.2f} (grids {rows[-3]['N']}, "
              f"{rows[-2]['N']}, {rows[-1]['N']}); Richardson hc {out['hc_extrapolated_nm']:.4f}"
              f" nm; coarsest grid within 2 %: {min(within) if within else None}")
    if args.memory:
        s = solve_in_subprocess({**case, "grid": args.memory, "max_cycles": 3})
        out["memory"] = dict(N=args.memory, peak_GiB=s["peak_rss_GiB"], wall_s=s["wall_s"])
        print(f"N = {args.memory}, three cycles: peak {s['peak_rss_GiB']:.2f} GiB, "
              f"{s['wall_s']:.0f} s")
    write_out(args.out, out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
