"""Stability map of the EHL solver: converged / failed over Moes M and L.

    .venv/bin/python bench/stability_map.py [--grid 257|default] [--m-max 1000] [--jobs 2]

Each point is an SI contact realising (M, L) (ehlfoam.contact.formulas.contact_from_moes, steel
on steel) with Barus viscosity and an incompressible oil, the laws under which the problem
depends on M and L only, solved from scratch on one grid. A point is 'converged' when the
residual and load tolerances were met, 'stagnated' when the cycles stalled within ten times
the tolerance, 'failed' otherwise (diverged or far from converged); it records hc / NVM and
the reason. Writes bench/results/stability_map.{json,png}; ``--grid default`` solves each point
on the grid the solver picks by itself (ehlfoam.contact.solver.default_grid: 513^2 below M = 300,
1025^2 from there) and writes stability_map_default.{json,png}; ``--m-max`` keeps the points
with M up to that value (1000: the classic range).
"""

from __future__ import annotations

import argparse
import json
from concurrent.futures import ThreadPoolExecutor


from common import RESULTS, log, save, solve_in_subprocess
from ehlfoam.contact.formulas import contact_from_moes

M_VALUES = [10, 30, 100, 300, 1000, 3000, 10000, 30000]
L_VALUES = [0, 2, 5, 10, 20]


def point(M: float, L: float, grid: int | None) -> dict:
    """Solve one (M, L) point on ``grid`` points a side (None: the solver's default grid)."""
    c = contact_from_moes(M, L)
    spec = dict(load=c.load, speed=c.speed, radius=c.radius, modulus=c.modulus,
                lubricant="custom", eta0=c.eta0, alpha=c.alpha, rho0=870.0, grid=grid,
                viscosity="barus", density="incompressible")
    s = solve_in_subprocess(spec)
    hc_ratio = (s["hc_m"] / s["hc_nvm_m"]) if s.get("hc_nvm_m") and s.get("hc_m") else None
    res = s.get("residual")
    status = ("converged" if s["converged"] else
              "stagnated" if res is not None and res < 10 * 3e-5 else "failed")
    row = dict(M=M, L=L, grid=s.get("grid"), status=status, converged=bool(s["converged"]),
               residual=res,
               load_error=s.get("load_error"), cycles=s.get("cycles"), wall_s=s["wall_s"],
               hc_over_nvm=hc_ratio, hmin_positive=(s.get("hmin_m") or -1) > 0,
               failure=s.get("failure"), continuation=s.get("continuation_M"),
               stalled_at_cycle=s.get("stalled_at_cycle"))
    log(f"M={M:>6g} L={L:>4g}: {status:10} cycles={row['cycles']} "
        f"res={row['residual']} hc/NVM={hc_ratio} wall={row['wall_s']:.1f}s {row['failure'] or ''}")
    return row


def plot(rows: list[dict], grid: int | str, name: str = "stability_map") -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5))
    style = {"converged": ("o", "tab:green"), "stagnated": ("s", "tab:orange"),
             "failed": ("x", "tab:red")}
    for r in rows:
        mark, color = style[r["status"]]
        filled = r["hmin_positive"] or mark == "x"
        ax.scatter(r["M"], r["L"], marker=mark, s=70, edgecolors=color,
                   facecolors=color if filled else "none")
        if r["hc_over_nvm"] is not None:
            ax.annotate(f"{r['hc_over_nvm']:.2f}", (r["M"], r["L"]), textcoords="offset points",
                        xytext=(6, 4), fontsize=7)
    ax.set_xscale("log")
    ax.set_xlabel("Moes M")
    ax.set_ylabel("Moes L")
    ax.set_title(f"EHL solver, grid {grid}, Barus + incompressible: o converged, s stagnated "
                 "(< 10 x tol), x failed; hollow: hmin <= 0 (under-resolved); labels hc/NVM",
                 fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(RESULTS / f"{name}.png", dpi=120)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", default="257", help="points a side, or 'default'")
    ap.add_argument("--m-max", type=float, default=max(M_VALUES))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--replot", action="store_true",
                    help="only redraw the saved map of --grid")
    args = ap.parse_args()
    grid = None if args.grid == "default" else int(args.grid)
    name = "stability_map" if grid is not None else "stability_map_default"
    if args.replot:
        data = json.loads((RESULTS / f"{name}.json").read_text())
        plot(data["points"], data["grid"], name)
        return
    pts = [(M, L) for L in L_VALUES for M in M_VALUES if M <= args.m_max]
    with ThreadPoolExecutor(args.jobs) as ex:
        rows = list(ex.map(lambda ml: point(ml[0], ml[1], grid), pts))
    save(f"{name}.json", {"grid": args.grid, "points": rows})
    plot(rows, args.grid, name)
    for st in ("converged", "stagnated", "failed"):
        log(f"{st}: {sum(r['status'] == st for r in rows)}/{len(rows)}")
    for r in rows:
        if r["status"] != "converged":
            log(f"  {r['status']} M={r['M']} L={r['L']}: {r['failure']}")
    log(f"map in {RESULTS / (name + '.png')}")


if __name__ == "__main__":
    main()
