"""Validation of ehl_precalc against classic results (prints tables, writes results/validation.json).

    .venv/bin/python bench/validation.py [--quick]

1. Dry limit: Polonsky-Keer on the solver's DC-FFT kernel against Hertz.
2. Nijenbanning-Venner-Moes (Wear 176, 1994) central film, M in {20, 100, 1000} x L in {5, 10}.
   The formula is a function of M and L only, which holds for Barus viscosity and an
   incompressible oil: those are the laws used here (the formula's own model).
3. The reference experiment's conditions (HVI60, 20 N, 40 C, u = 2..40 mm/s) with the default
   laws (Roelands, Dowson-Higginson) and with the formula's laws, beside NVM and Hamrock-Dowson.
4. The two-phase option at 20 mm/s, 25 C, 20 N: sub-ambient length l/a beside 0.9 (thesis) and
   5 (experiment).
"""

from __future__ import annotations

import argparse

import numpy as np

from common import log, save, solve_in_subprocess
from ehlfoam.contact.dry import solve_dry
from ehlfoam.contact.elastic import hertz_pressure
from ehlfoam.contact.formulas import contact_from_moes, hamrock_dowson


def dry(n: int) -> dict:
    r = solve_dry(n)
    X, Y = np.meshgrid(r.x, r.y)
    R = np.hypot(X, Y)
    err = np.abs(r.P - hertz_pressure(X, Y))
    out = dict(grid=n, p_max_over_pH=float(r.P.max()), max_err_r_lt_095=float(err[R < 0.95].max()),
               rms_err_contact=float(np.sqrt((err[R < 1] ** 2).mean())), max_err_all=float(err.max()),
               load_error=r.load_error, H0=r.H0, iterations=r.iterations)
    log(f"dry {n}: p_max/pH = {out['p_max_over_pH']:.6f}, max|P - Hertz| (r<0.95) = "
        f"{out['max_err_r_lt_095']:.2e}, rms in contact = {out['rms_err_contact']:.2e}, max "
        f"(edge cells) = {out['max_err_all']:.2e}, load error = {out['load_error']:.1e}, H0 = {r.H0:.6f}")
    return out


def nvm_case(M: float, L: float, grid: int) -> dict:
    c = contact_from_moes(M, L)
    spec = dict(load=c.load, speed=c.speed, radius=c.radius, modulus=c.modulus, lubricant="custom",
                eta0=c.eta0, alpha=c.alpha, rho0=870.0, viscosity="barus",
                density="incompressible", grid=grid)
    s = solve_in_subprocess(spec)
    ratio = s["hc_m"] / s["hc_nvm_m"]
    log(f"NVM M={M:5g} L={L:3g} grid {grid}: hc/NVM = {ratio:.4f} ({100 * (ratio - 1):+.1f} %), "
        f"converged={s['converged']}, {s['wall_s']:.1f} s")
    return dict(M=M, L=L, grid=grid, hc_over_nvm=ratio, converged=s["converged"], wall_s=s["wall_s"])


def reference(u: float, laws: dict, grid: int | None) -> dict:
    spec = dict(load=20.0, speed=u, temperature=40.0, **laws)
    if grid:
        spec["grid"] = grid
    s = solve_in_subprocess(spec)
    from ehlfoam.contact.spec import make_spec

    hd_c, _ = hamrock_dowson(make_spec(**{k: v for k, v in spec.items() if k != "grid"}).contact())
    row = dict(u_mm_s=u * 1e3, laws=laws or "default (Roelands, Dowson-Higginson)", M=s["M"], L=s["L"],
               grid=s["grid"], hc_nm=s["hc_m"] * 1e9, hmin_nm=s["hmin_m"] * 1e9,
               hc_nvm_nm=s["hc_nvm_m"] * 1e9, hc_hd_nm=hd_c * 1e9,
               hc_over_nvm=s["hc_m"] / s["hc_nvm_m"], converged=s["converged"], wall_s=s["wall_s"])
    log(f"ref u={u * 1e3:4g} mm/s {row['laws']}: M={s['M']:.0f} L={s['L']:.2f} grid {s['grid']}: "
        f"hc = {row['hc_nm']:.2f} nm, NVM {row['hc_nvm_nm']:.2f}, HD {row['hc_hd_nm']:.2f}, "
        f"hc/NVM = {row['hc_over_nvm']:.3f}, hmin = {row['hmin_nm']:.2f} nm, "
        f"converged={s['converged']}, {s['wall_s']:.1f} s")
    return row


def twophase(grid: int) -> dict:
    s = solve_in_subprocess(dict(load=20.0, speed=0.02, temperature=25.0, cavitation="twophase",
                                 grid=grid))
    log(f"two-phase 20 mm/s 25 C grid {s.get('grid')}: l/a = {s.get('cavity_length_over_a')}, "
        f"p_min = {s.get('p_min_Pa')} Pa, converged={s['converged']} (residual "
        f"{s.get('residual')}), {s['wall_s']:.1f} s")
    return s


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="coarser grids (a smoke test)")
    args = ap.parse_args()
    q = args.quick
    out = {"dry": [dry(n) for n in ((129,) if q else (257, 513))]}
    out["nvm"] = [nvm_case(M, L, 129 if q else 513) for M in (20, 100, 1000) for L in (5, 10)]
    speeds = (0.01,) if q else (0.002, 0.005, 0.01, 0.02, 0.04)
    out["reference_default"] = [reference(u, {}, 257 if q else None) for u in speeds]
    out["reference_nvm_laws"] = [reference(u, dict(viscosity="barus", density="incompressible"),
                                           257 if q else None) for u in speeds]
    out["twophase"] = twophase(129 if q else 257)
    save("validation_quick.json" if q else "validation.json", out)


if __name__ == "__main__":
    main()
