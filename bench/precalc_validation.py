"""The EHL precalc against classic results: Hertz, Nijenbanning-Venner-Moes, Hamrock-Dowson.

    python bench/precalc_validation.py [--stability [--stability-grid 257|default]]
        [--accuracy] [--twophase] [--workers N] [--out FILE.json]
    python bench/precalc_validation.py --twophase-only [--quick] [--workers N]
    python bench/precalc_validation.py --quick

1. Dry limit: the solver's elastic kernel with no film (Polonsky-Keer) against Hertz's
   pressure: p_max / p_H, and the largest error inside r < 0.95 a.
2. Nijenbanning, Venner and Moes (Wear 176, 1994)'s central film formula over Moes's M in
   {20, 100, 1000} x L in {5, 10}, on 513 points a side. The formula is a function of M and
   L only, which holds for Barus viscosity and an incompressible oil: the laws used here.
3. The reference experiment's conditions (HVI60, 20 N, 40 C, u = 2..40 mm/s) with the
   default laws (Roelands, Dowson-Higginson) and with the formula's, beside NVM and
   Hamrock-Dowson.
4. The two-phase cavitation option at 20 mm/s, 25 C, 20 N on 257 points along y (513 x
   257): the sub-ambient length and the more-than-half-gas length over a, beside the thesis
   model's 0.9 a; with ``--twophase``, on three grids up to its default (2049 x 1025),
   each fully coupled and one-way: hc, hmin, the lengths, how well each satisfies the coupled
   equations (film error over hc, load error), the outer iterations, wall and CPU time, the
   part of it in the sub-ambient solves, the Newton iterations on each grid of its nested
   iteration (coarsest first) or of its last pass, peak memory and the machine's load
   average; then the one-way's error against the coupled on each grid.
5. With ``--stability``: converged / stagnated / failed over M = 10..3e4 x L = 0..20 on
   ``--stability-grid`` points a side (``default``: the solver's own grid).
6. With ``--accuracy``: the 18-point table (5 / 20 / 30 N x 25 / 40 / 60 C, each at 10 mm/s
   and at 2 or 40 mm/s: Moes M 343-34,215) on the grids main 5ad327e (before the full
   multigrid of issue 77) solved them on, hc beside its, each solve's estimate of its grid
   error, cycles, wall and CPU time.

Each solve runs in a fresh process, on ``--workers`` threads (default: the solver's own
choice). ``--quick``: the dry limit and four NVM points at M <= 100 on 129 points a side
(seconds); with ``--twophase``, the grids 129-513 along y.
"""

from __future__ import annotations

import argparse

import numpy as np

from common import add_output_options, print_table, solve_in_subprocess, write_out
from ehlfoam.contact.dry import solve_dry
from ehlfoam.contact.elastic import hertz_pressure
from ehlfoam.contact.formulas import contact_from_moes, hamrock_dowson
from ehlfoam.contact.spec import make_spec

SPEEDS = (0.002, 0.005, 0.01, 0.02, 0.04)          # m/s
NVM_POINTS = [(M, L) for M in (20, 100, 1000) for L in (5, 10)]
STABILITY_M = (10, 30, 100, 300, 1000, 3000, 10000, 30000)
STABILITY_L = (0, 2, 5, 10, 20)
#: the formula's laws: the problem depends on M and L only
MOES_LAWS = dict(viscosity="barus", density="incompressible")
#: hc [nm] of the accuracy points, (load N, temperature C, speed m/s), by the solver of main
#: 5ad327e (2026-12-06: fixed residual 3e-5, speed ramps above M 5000; a busy 2-core
#: machine, 1477 s wall, 825 s CPU for the 18): the reference of "hc unchanged within 0.5 %".
HC_MAIN_5AD327E_NM = {
    (5, 25, 0.01): 14.9042, (5, 25, 0.002): 5.0311, (5, 40, 0.01): 8.9275,
    (5, 40, 0.04): 22.7483, (5, 60, 0.01): 5.2491, (5, 60, 0.002): 1.7910,
    (20, 25, 0.01): 12.6917, (20, 25, 0.04): 33.0326, (20, 40, 0.01): 7.5254,
    (20, 40, 0.002): 2.4738, (20, 60, 0.01): 4.3620, (20, 60, 0.04): 11.2881,
    (30, 25, 0.01): 12.0693, (30, 25, 0.002): 3.9311, (30, 40, 0.01): 7.1236,
    (30, 40, 0.04): 18.6154, (30, 60, 0.01): 4.1037, (30, 60, 0.002): 1.2994,
}


def dry(n: int) -> dict:
    """The dry contact on n points a side against Hertz."""
    r = solve_dry(n)
    X, Y = np.meshgrid(r.x, r.y)
    err = np.abs(r.P - hertz_pressure(X, Y))
    return dict(grid=n, p_max_over_pH=float(r.P.max()),
                max_err_r_lt_095=float(err[np.hypot(X, Y) < 0.95].max()),
                load_error=r.load_error, iterations=r.iterations)


def moes_spec(M: float, L: float, grid: int | None) -> dict:
    """An SI steel-on-steel contact realising Moes's (M, L) under the formula's laws."""
    c = contact_from_moes(M, L)
    return dict(load=c.load, speed=c.speed, radius=c.radius, modulus=c.modulus,
                lubricant="custom", eta0=c.eta0, alpha=c.alpha, rho0=870.0, grid=grid,
                **MOES_LAWS)


def nvm(M: float, L: float, grid: int, workers: int | None = None) -> dict:
    """One (M, L) point against NVM's formula."""
    s = solve_in_subprocess(moes_spec(M, L, grid), workers)
    return dict(M=M, L=L, grid=grid, hc_over_nvm=s["hc_m"] / s["hc_nvm_m"],
                converged=bool(s["converged"]), wall_s=s["wall_s"])


def reference(u: float, laws: dict, workers: int | None = None) -> dict:
    """The reference experiment's contact at u [m/s] under ``laws`` beside NVM and HD."""
    spec = dict(load=20.0, speed=u, temperature=40.0, **laws)
    s = solve_in_subprocess(spec, workers)
    hd_c, _ = hamrock_dowson(make_spec(**spec).contact())
    return dict(u_mm_s=u * 1e3, laws="Barus, incompressible" if laws else "default",
                M=s["M"], L=s["L"], grid=s["grid"], hc_nm=s["hc_m"] * 1e9,
                hc_nvm_nm=s["hc_nvm_m"] * 1e9, hc_hd_nm=hd_c * 1e9,
                hc_over_nvm=s["hc_m"] / s["hc_nvm_m"], hmin_nm=s["hmin_m"] * 1e9,
                converged=bool(s["converged"]), wall_s=s["wall_s"])


def accuracy(workers: int | None) -> dict:
    """The 18 points of :data:`HC_MAIN_5AD327E_NM` on the grids main 5ad327e solved them on
    (513 points a side below M = 300, 1025 above; the default is 2049 from M = 8000 now):
    hc against main 5ad327e's, the solve's own grid-error estimate, cycles and cost; where
    the default grid is another, also that solve (``default_rows``: hc, its change, its
    estimate and cost)."""
    from ehlfoam.contact.solver import default_grid
    from ehlfoam.contact.spec import make_spec

    rows, default_rows = [], []
    for (F, T, u), before in HC_MAIN_5AD327E_NM.items():
        case = dict(load=float(F), temperature=float(T), speed=u)
        M = make_spec(**case).contact().M
        grid = 513 if M < 300.0 else 1025
        s = solve_in_subprocess({**case, "grid": grid}, workers=workers)
        hc = s["hc_m"] * 1e9
        rows.append(dict(load_N=F, temperature_C=T, speed_mm_s=u * 1e3, M=s["M"], L=s["L"],
                         grid=s["grid"], hc_grid_error=s.get("hc_grid_error"),
                         hc_nm=hc, hc_main_nm=before, diff=hc / before - 1.0,
                         cycles=s["cycles"], wall_s=s["wall_s"], cpu_s=s["cpu_s"],
                         converged=bool(s["converged"]), ramp=bool(s.get("continuation_M"))))
        if default_grid(M) != grid:
            d = solve_in_subprocess(case, workers=workers)
            default_rows.append(dict(rows[-1], grid=d["grid"], hc_nm=d["hc_m"] * 1e9,
                                     diff=d["hc_m"] * 1e9 / hc - 1.0,
                                     hc_grid_error=d.get("hc_grid_error"), cycles=d["cycles"],
                                     wall_s=d["wall_s"], cpu_s=d["cpu_s"],
                                     converged=bool(d["converged"])))
    total = dict(wall_s=sum(r["wall_s"] for r in rows), cpu_s=sum(r["cpu_s"] for r in rows))
    return dict(rows=rows, largest_diff=max(abs(r["diff"]) for r in rows), **total,
                workers=workers, default_rows=default_rows,
                default_cpu_s=sum(r["cpu_s"] for r in default_rows))


def twophase(grids: tuple[int, ...], workers: int | None,
             couplings: tuple[str, ...] = ("coupled", "one-way"), load: float = 20.0,
             speed: float = 0.02, temperature: float = 25.0) -> list[dict]:
    """The two-phase option at 20 mm/s, 25 C, 20 N (default) on ``grids`` (points along y; x
    has 2n - 1), each coupling of ``couplings``: hc, hmin, sub-ambient and more-than-half-gas
    lengths over a, the coupled equations' errors (film over hc, load), outer iterations,
    time and peak memory; a one-way row also its error against the coupled row of its grid
    (hc, hmin relative, lengths in a)."""
    rows = []
    for n in grids:
        for coupling in couplings:
            s = solve_in_subprocess(dict(load=load, speed=speed, temperature=temperature,
                                         cavitation="twophase", grid=n,
                                         twophase_coupling=coupling), workers=workers)
            levels = s.get("subambient_levels") or []
            rows.append(dict(grid=s.get("grid", n), coupling=coupling,
                             converged=bool(s["converged"]),
                             hc_nm=s["hc_m"] * 1e9 if s.get("hc_m") else None,
                             hmin_nm=s["hmin_m"] * 1e9 if s.get("hmin_m") else None,
                             cavity_over_a=s.get("cavity_length_over_a"),
                             half_gas_over_a=s.get("cavity_half_density_length_over_a"),
                             reaches_outlet=s.get("cavity_reaches_outlet"),
                             film_error=s.get("coupling_film_error_over_hc"),
                             load_error=s.get("coupling_load_error"),
                             outer=s.get("coupling_outer_iterations"),
                             p_min_Pa=s.get("p_min_Pa"), wall_s=s["wall_s"], cpu_s=s["cpu_s"],
                             subambient_s=sum(lv["wall_s"] for lv in levels) if levels else None,
                             newton="/".join(str(lv["newton_iterations"]) for lv in levels),
                             factorisations=sum(lv["factorisations"] for lv in levels),
                             levels=levels, coupling_outer=s.get("coupling_outer"),
                             peak_GiB=s["peak_rss_GiB"],
                             load=s.get("load_average", [None])[0], failure=s.get("failure")))
    def rows_of(r: dict) -> int:   # points along y (a failed solve has no [nx, ny])
        return r["grid"][1] if isinstance(r["grid"], list) else r["grid"]

    coupled = {rows_of(r): r for r in rows if r["coupling"] == "coupled" and r["converged"]}
    for r in rows:
        c = coupled.get(rows_of(r))
        if r["coupling"] == "one-way" and c is not None and r["converged"]:
            r.update(hc_err=r["hc_nm"] / c["hc_nm"] - 1.0,
                     hmin_err=r["hmin_nm"] / c["hmin_nm"] - 1.0,
                     cavity_err_a=r["cavity_over_a"] - c["cavity_over_a"],
                     half_gas_err_a=r["half_gas_over_a"] - c["half_gas_over_a"])
    return rows


TWOPHASE_COLUMNS = [("grid", "grid", "d"), ("coupling", "coupling", ""),
                    ("hc_nm", "hc [nm]", ".3f"), ("hmin_nm", "hmin [nm]", ".3f"),
                    ("cavity_over_a", "sub-ambient l/a", ".3f"),
                    ("reaches_outlet", "to outlet", ""), ("half_gas_over_a", "half-gas l/a", ".3f"),
                    ("film_error", "film err/hc", ".1e"), ("load_error", "load err", ".1e"),
                    ("outer", "outer", "d"), ("converged", "converged", ""),
                    ("wall_s", "wall [s]", ".0f"), ("cpu_s", "CPU [s]", ".0f"),
                    ("subambient_s", "sub-ambient [s]", ".0f"),
                    ("newton", "Newton per grid", ""), ("factorisations", "LUs", "d"),
                    ("peak_GiB", "peak [GiB]", ".2f"), ("load", "load", ".1f")]
#: the one-way coupling's error against the coupled solution on the same grid
ONE_WAY_ERROR_COLUMNS = [("grid", "grid", "d"), ("hc_err", "hc one-way/coupled - 1", "+.2%"),
                         ("hmin_err", "hmin one-way/coupled - 1", "+.2%"),
                         ("cavity_err_a", "sub-ambient diff [a]", "+.3f"),
                         ("half_gas_err_a", "half-gas diff [a]", "+.3f")]


def print_twophase(rows: list[dict], title: str) -> None:
    """The two-phase table and the one-way's error against the coupled."""
    print_table(rows, TWOPHASE_COLUMNS, title)
    errors = [r for r in rows if "hc_err" in r]
    if errors:
        print_table(errors, ONE_WAY_ERROR_COLUMNS, title + ": one-way against coupled")


def stability(M: float, L: float, grid: int | None, workers: int | None = None) -> dict:
    """One point of the stability map: converged, stagnated (within ten times the residual
    tolerance) or failed."""
    s = solve_in_subprocess(moes_spec(M, L, grid), workers)
    res = s.get("residual")
    status = ("converged" if s["converged"] else
              "stagnated" if res is not None and res < 10 * 3e-5 else "failed")
    ratio = s["hc_m"] / s["hc_nvm_m"] if s.get("hc_m") and s.get("hc_nvm_m") else None
    return dict(M=M, L=L, grid=s.get("grid"), status=status, residual=res,
                cycles=s.get("cycles"), hc_over_nvm=ratio, wall_s=s["wall_s"],
                failure=s.get("failure"))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--stability", action="store_true", help="also the stability map")
    ap.add_argument("--stability-grid", default="257",
                    help="points a side of the map, or 'default' (the solver's own)")
    ap.add_argument("--accuracy", action="store_true",
                    help="also the 18-point table against main 5ad327e's hc")
    ap.add_argument("--twophase", action="store_true",
                    help="the two-phase option on three grids up to its default")
    ap.add_argument("--twophase-only", action="store_true",
                    help="only that (sections 1-3 and the one-grid section 4 skipped)")
    ap.add_argument("--workers", type=int, default=None, help="threads of each solve")
    add_output_options(ap)
    args = ap.parse_args(argv)
    q = args.quick
    if args.twophase_only:
        out = {"twophase_grids": twophase((129, 257, 513) if q else (257, 513, 1025),
                                          args.workers)}
        print_twophase(out["twophase_grids"],
                       "4. two-phase on three grids, 20 mm/s, 25 C, 20 N (thesis model: 0.9 a)")
        write_out(args.out, out)
        return 0
    out: dict = {"dry": [dry(n) for n in ((129,) if q else (257, 513))]}
    print_table(out["dry"], [("grid", "grid", "d"), ("p_max_over_pH", "p_max / p_H", ".6f"),
                             ("max_err_r_lt_095", "max |P - Hertz| r<0.95a", ".2e"),
                             ("load_error", "load error", ".1e")], "1. dry limit vs Hertz")
    points = [(M, L) for M, L in NVM_POINTS if M <= 100] if q else NVM_POINTS
    out["nvm"] = [nvm(M, L, 129 if q else 513, args.workers) for M, L in points]
    print_table(out["nvm"], [("M", "M", "g"), ("L", "L", "g"), ("grid", "grid", "d"),
                             ("hc_over_nvm", "hc / NVM", ".4f"), ("converged", "converged", ""),
                             ("wall_s", "wall [s]", ".1f")], "2. NVM, Barus + incompressible")
    if not q:
        out["reference"] = [reference(u, laws, args.workers)
                            for laws in ({}, MOES_LAWS) for u in SPEEDS]
        print_table(out["reference"], [
            ("u_mm_s", "u [mm/s]", "g"), ("laws", "laws", ""), ("M", "M", ".0f"),
            ("L", "L", ".2f"), ("grid", "grid", "d"), ("hc_nm", "hc [nm]", ".2f"),
            ("hc_nvm_nm", "NVM [nm]", ".2f"), ("hc_hd_nm", "HD [nm]", ".2f"),
            ("hc_over_nvm", "hc / NVM", ".3f"), ("hmin_nm", "hmin [nm]", ".2f"),
            ("converged", "converged", "")], "3. reference conditions (HVI60, 20 N, 40 C)")
        out["twophase"] = twophase((257,), args.workers)
        print_twophase(out["twophase"], "4. two-phase, 20 mm/s, 25 C, 20 N (thesis model: 0.9 a)")
    if args.twophase:
        out["twophase_grids"] = twophase((129, 257, 513) if q else (257, 513, 1025),
                                         args.workers)
        print_twophase(out["twophase_grids"],
                       "4. two-phase on three grids, 20 mm/s, 25 C, 20 N (thesis model: 0.9 a)")
    if args.stability:
        grid = None if args.stability_grid == "default" else int(args.stability_grid)
        rows = [stability(M, L, grid, args.workers) for L in STABILITY_L for M in STABILITY_M]
        out["stability"] = {"grid": args.stability_grid, "points": rows}
        print_table(rows, [("M", "M", "g"), ("L", "L", "g"), ("grid", "grid", "d"),
                           ("status", "status", ""), ("cycles", "cycles", "d"),
                           ("hc_over_nvm", "hc / NVM", ".3f"), ("wall_s", "wall [s]", ".1f")],
                    f"5. stability map, grid {args.stability_grid}")
        for status in ("converged", "stagnated", "failed"):
            print(f"{status}: {sum(r['status'] == status for r in rows)}/{len(rows)}")
    if args.accuracy:
        out["accuracy"] = acc = accuracy(args.workers)
        print_table(acc["rows"], [
            ("load_N", "F [N]", "g"), ("temperature_C", "T [C]", "g"),
            ("speed_mm_s", "u [mm/s]", "g"), ("M", "M", ".0f"), ("L", "L", ".2f"),
            ("grid", "grid", "d"), ("hc_nm", "hc [nm]", ".4f"),
            ("hc_main_nm", "5ad327e [nm]", ".4f"), ("diff", "diff", "+.2%"),
            ("hc_grid_error", "grid error (est.)", ".1%"),
            ("cycles", "cycles", "d"), ("wall_s", "wall [s]", ".1f"), ("cpu_s", "CPU [s]", ".1f"),
            ("converged", "converged", "")], "6. accuracy, 18 points against main 5ad327e")
        print(f"largest |hc - 5ad327e| / 5ad327e = {acc['largest_diff']:.2%}; total "
              f"{acc['wall_s']:.0f} s wall, {acc['cpu_s']:.0f} s CPU")
        if acc["default_rows"]:
            print_table(acc["default_rows"], [
                ("load_N", "F [N]", "g"), ("temperature_C", "T [C]", "g"),
                ("speed_mm_s", "u [mm/s]", "g"), ("M", "M", ".0f"), ("grid", "grid", "d"),
                ("hc_nm", "hc [nm]", ".4f"), ("diff", "against the row above", "+.2%"),
                ("hc_grid_error", "grid error (est.)", ".1%"), ("cycles", "cycles", "d"),
                ("cpu_s", "CPU [s]", ".1f"), ("converged", "converged", "")],
                "6b. the points whose default grid is finer, on it")
            print(f"their CPU on the default grid: {acc['default_cpu_s']:.0f} s")
    write_out(args.out, out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
