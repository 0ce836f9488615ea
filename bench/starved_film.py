"""The starved film of the EHL precalc against the published starvation relations.

    python bench/starved_film.py [--grid N] [--out FILE.json]
    python bench/starved_film.py --quick

At two Moes points, (M, L) = (1000, 10) and (100, 5) (Barus viscosity, incompressible oil:
the problem depends on M and L only), the same contact is solved fully flooded and starved,
on the same grid and domain:

1. Inlet layer (``inlet_layer``, film content): h_oil / hc,ff from 50 (flooded) down to 0.1
   (strongly starved). hc / hc,ff beside the form of Chevalier, Lubrecht, Cann, Colin and
   Dalmaz (J. Tribol. 120 (1998) 126), hc / hc,ff = r / (1 + r^gamma)^(1 / gamma) with
   r = h_oil / hc,ff; their gamma(M, L) is not available here, so gamma is fitted to the
   solver's points (least squares in hc / hc,ff) and the fit's worst deviation given, with
   the two limits the form stands for: hc <= h_oil (a thin layer passes through the
   contact whole) and hc -> hc,ff (a thick one floods it).
2. Inlet meniscus (``inlet_meniscus``, distance upstream of x = -a in units of a; Hamrock
   and Dowson's dimensionless inlet distance is m = 1 + inlet_meniscus): hc / hc,ff beside
   Hamrock and Dowson's starved point-contact fit (J. Lubr. Technol. 99 (1977) 15) as
   commonly quoted (the paper not consulted), hc / hc,ff = ((m - 1) / (m* - 1))^0.29 for
   m < m*, 1 beyond, with m* = 1 + 3.06 ((R / b)^2 hc,ff / R)^0.58 (b = a for a circular
   contact, so (R / a)^2 hc,ff / R is hc,ff in units a^2 / R); and the onset of starvation, the
   largest m where hc / hc,ff < 0.97, beside m* (Wedeven, Evans and Cameron 1971 found
   the film falling once the meniscus comes within such a distance; no constant of theirs
   is used).

``--quick``: (M, L) = (100, 5) only, on 65 points, four layers and three menisci (seconds).
Default grid: 129 points a side (the inlet zone at M = 1000 is about 0.2 a: 8 cells).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from common import add_output_options, print_table, write_out
from ehlfoam.contact.formulas import contact_from_moes
from ehlfoam.contact.solver import solve
from ehlfoam.contact.spec import make_spec

POINTS = ((1000.0, 10.0), (100.0, 5.0))
LAYERS = (50.0, 8.0, 4.0, 2.0, 1.5, 1.0, 0.7, 0.5, 0.3, 0.2, 0.1)   # h_oil / hc,ff
MENISCI = (3.0, 1.5, 1.0, 0.6, 0.35, 0.2, 0.1, 0.05, 0.02)    # distance upstream of -a [a]
QUICK_LAYERS = (50.0, 1.0, 0.5, 0.2)
QUICK_MENISCI = (1.0, 0.2, 0.05)
#: Hamrock and Dowson (1977): m* = 1 + HD_C (H_ff)^HD_E, hc / hc,ff = (...)^HD_N
HD_C, HD_E, HD_N = 3.06, 0.58, 0.29
#: hc / hc,ff below which a meniscus counts as starving the contact
ONSET = 0.97


def moes_spec(M: float, L: float, grid: int) -> dict:
    """An SI steel-on-steel contact realising Moes's (M, L) under Barus / incompressible."""
    c = contact_from_moes(M, L)
    return dict(load=c.load, speed=c.speed, radius=c.radius, modulus=c.modulus,
                lubricant="custom", eta0=c.eta0, alpha=c.alpha, rho0=870.0, grid=grid,
                viscosity="barus", density="incompressible")


def chevalier(r: np.ndarray, gamma: float) -> np.ndarray:
    """Chevalier et al.'s form: hc / hc,ff = r / (1 + r^gamma)^(1 / gamma)."""
    return r / (1.0 + r**gamma) ** (1.0 / gamma)


def fit_gamma(r: np.ndarray, ratio: np.ndarray) -> float:
    """gamma of :func:`chevalier` by least squares in hc / hc,ff (a bounded scalar fit)."""
    from scipy.optimize import minimize_scalar

    res = minimize_scalar(lambda g: float(np.sum((chevalier(r, g) - ratio) ** 2)),
                          bounds=(0.3, 20.0), method="bounded")
    return float(res.x)


def hamrock_dowson_ratio(m: float, H_ff: float) -> tuple[float, float]:
    """(hc / hc,ff, m*) of Hamrock and Dowson's starved fit; ``H_ff`` in units a^2 / R."""
    m_star = 1.0 + HD_C * H_ff**HD_E
    return (((m - 1.0) / (m_star - 1.0)) ** HD_N if m < m_star else 1.0), m_star


def run_point(M: float, L: float, grid: int, layers, menisci) -> dict:
    base = moes_spec(M, L, grid)
    t0, c0 = time.perf_counter(), time.process_time()
    flooded = solve(make_spec(**base))
    scale = flooded.contact.film_scale
    H_ff = flooded.H_central
    rows_layer = []
    for r in layers:
        t, c = time.perf_counter(), time.process_time()
        res = solve(make_spec(**base, inlet_layer=r * H_ff * scale), flooded=flooded)
        s = res.summary()
        rows_layer.append(dict(M=M, L=L, r=r, hc_ratio=s["hc_over_hc_flooded"],
                               hmin_ratio=s["hmin_over_hmin_flooded"],
                               meniscus=s["inlet_meniscus_over_a"], converged=s["converged"],
                               cycles=s["cycles"], wall_s=time.perf_counter() - t,
                               cpu_s=time.process_time() - c))
    r_arr = np.array([row["r"] for row in rows_layer])
    ratio = np.array([row["hc_ratio"] for row in rows_layer])
    gamma = fit_gamma(r_arr, ratio)
    for row in rows_layer:
        row["chevalier"] = float(chevalier(np.array(row["r"]), gamma))
        row["dev"] = row["hc_ratio"] - row["chevalier"]
        row["hc_over_layer"] = row["hc_ratio"] / row["r"]
    rows_men = []
    for dist in menisci:
        t, c = time.perf_counter(), time.process_time()
        spec = make_spec(**base, inlet_meniscus=dist)
        res = solve(spec)  # its own flooded twin: a far meniscus widens the domain
        s = res.summary()
        m = 1.0 + dist
        hd, m_star = hamrock_dowson_ratio(m, res.flooded.H_central)
        rows_men.append(dict(M=M, L=L, m=m, hc_ratio=s["hc_over_hc_flooded"],
                             hmin_ratio=s["hmin_over_hmin_flooded"], hd=hd,
                             dev=s["hc_over_hc_flooded"] - hd, m_star=m_star,
                             converged=s["converged"] and s["flooded_converged"],
                             x_min=res.domain.x_min, wall_s=time.perf_counter() - t,
                             cpu_s=time.process_time() - c))
    starved = [row["m"] for row in rows_men if row["hc_ratio"] < ONSET]
    return dict(M=M, L=L, grid=grid, hc_ff_over_a2R=H_ff, hmin_ff_over_a2R=float(
        flooded.mg.H.min()), gamma_fit=gamma, layer=rows_layer, meniscus=rows_men,
        m_star=hamrock_dowson_ratio(1.0, H_ff)[1], onset_m=max(starved) if starved else None,
        worst_chevalier=max(abs(row["dev"]) for row in rows_layer),
        worst_hamrock_dowson=max(abs(row["dev"]) for row in rows_men),
        layer_mass_ok=all(row["hc_ratio"] <= row["r"] * (1 + 1e-9) for row in rows_layer),
        wall_s=time.perf_counter() - t0, cpu_s=time.process_time() - c0)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--grid", type=int, default=129, help="points a side (2^k + 1)")
    add_output_options(ap)
    args = ap.parse_args(argv)
    if args.quick:
        points, grid, layers, menisci = ((100.0, 5.0),), 65, QUICK_LAYERS, QUICK_MENISCI
    else:
        points, grid, layers, menisci = POINTS, args.grid, LAYERS, MENISCI
    solve(make_spec(**moes_spec(100.0, 5.0, 65), inlet_layer=1e-8, max_cycles=2))  # compile
    results = [run_point(M, L, grid, layers, menisci) for M, L in points]
    for res in results:
        print(f"\nM = {res['M']:g}, L = {res['L']:g}, grid {res['grid']}: hc,ff = "
              f"{res['hc_ff_over_a2R']:.4g} a^2/R, gamma fitted = {res['gamma_fit']:.3f}, "
              f"m* (Hamrock-Dowson) = {res['m_star']:.3f}, onset m (hc/hc,ff < {ONSET}) = "
              f"{res['onset_m']}, {res['wall_s']:.0f} s wall, {res['cpu_s']:.0f} s CPU")
        print_table(res["layer"], [
            ("r", "h_oil/hc,ff", ".2f"), ("hc_ratio", "hc/hc,ff", ".4f"),
            ("hmin_ratio", "hmin/hmin,ff", ".4f"), ("hc_over_layer", "hc/h_oil", ".3f"),
            ("chevalier", "Chevalier", ".4f"), ("dev", "dev", "+.4f"),
            ("meniscus", "meniscus [a]", ".3f"), ("converged", "conv", ""),
            ("cycles", "cycles", "d"), ("wall_s", "wall [s]", ".1f")],
            title="1. inlet layer (film content) vs Chevalier et al. 1998's form")
        print_table(res["meniscus"], [
            ("m", "m", ".2f"), ("hc_ratio", "hc/hc,ff", ".4f"),
            ("hmin_ratio", "hmin/hmin,ff", ".4f"), ("hd", "Hamrock-Dowson", ".4f"),
            ("dev", "dev", "+.4f"), ("x_min", "x_min [a]", ".2f"),
            ("converged", "conv", ""), ("wall_s", "wall [s]", ".1f")],
            title="2. inlet meniscus vs Hamrock and Dowson 1977")
        print(f"worst |dev|: Chevalier fit {res['worst_chevalier']:.4f}, Hamrock-Dowson "
              f"{res['worst_hamrock_dowson']:.4f}; hc <= h_oil everywhere: "
              f"{res['layer_mass_ok']}")
    write_out(args.out, dict(points=results, layers=list(layers), menisci=list(menisci)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
