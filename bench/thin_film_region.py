"""The flooded region in the thin-film limit (``ehlfoam.thinfilm.model``) on a series of
grids and steps: what the gap-averaged flow with Landau-Levich films makes of a case spec,
converged on its own grid, beside the 3D interface cases.

Each run marches the spec's contact, oil, supply and wetting from the spec's initial puddle
(or from the previous run's state with ``--chain``) for ``--transits`` transits of the spec
(``run.transit_length`` a at u), or until the outflow balances the supply (``--balance``).
It prints the metrics per run and writes ``bench/results/thin_film_region[_TAG].json``
after every run (atomically), the states to ``runs/bench/thin_film/TAG/`` and, with
``--plot``, the menisci of all runs on one picture.

    python bench/thin_film_region.py [SPEC] [--cells 0.2 0.1 0.05] [--courant 0.25 ...]
        [--film-factor 1 ...] [--receding static bretherton 1.05 ...] [--transits 10]
        [--advancing static 47 ...] [--normal-length 0.3 ...] [--meniscus sub-cell cell]
        [--balance [--tolerance 0.01] [--window 5]] [--chain] [--start STATE.npz]
        [--domain -11 19 11]
        [--set KEY=VALUE ...] [--tag NAME] [--plot FILE.png]
    python bench/thin_film_region.py --plot FILE.png --plot-records RECORD.json ...
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.common import save, spec_option  # noqa: E402
from ehlfoam.thinfilm import ThinFilmProblem, solve_thin_film
from ehlfoam.thinfilm.state import load_state, save_state
from ehlfoam.spec.case import CaseSpec, load_case_spec
from ehlfoam.gap.source import load_gap

WORK = ROOT / "runs" / "bench" / "thin_film"


def problem_from_spec(spec: CaseSpec, gap, cell: float, domain: tuple[float, float, float],
                      film_factor: float = 1.0, receding: str | float = "static",
                      normal_length: float | None = None,
                      meniscus_position: str = "sub-cell",
                      advancing_angle: float | None = None) -> ThinFilmProblem:
    """The thin-film problem of a case spec: its contact, oil, wetting and supply ("layers":
    both layers on the track; "flooded": the whole inlet gap on the track), ``cell``,
    ``domain`` = (x_min, x_max, y_max) and ``normal_length`` (None: 1.5 cells) in units of
    a, and the advancing menisci's apparent angle on dry walls (deg; None: the static one)."""
    a = spec.a
    sup = spec.supply
    supply = sup.disc_layer + sup.ball_layer
    if sup.mode == "flooded":
        supply = float(gap(np.array([domain[0] * a]), np.array([0.0]))[0])
    elif sup.mode != "layers":
        raise ValueError(f"supply.mode = {sup.mode!r}: the thin-film model takes 'layers' or "
                         "'flooded'")
    return ThinFilmProblem(
        gap=gap, speed=spec.speed, viscosity=spec.oil_viscosity,
        surface_tension=spec.physics.surface_tension, contact_angle=spec.physics.contact_angle,
        supply=supply, track_half_width=sup.track_half_width,
        x_range=(domain[0] * a, domain[1] * a), y_max=domain[2] * a,
        island_radius=spec.domain.island_radius * a, cell=cell * a,
        initial_radius=sup.initial_puddle * a, film_factor=film_factor,
        receding_meniscus=receding,
        normal_length=None if normal_length is None else normal_length * a,
        advancing_angle=advancing_angle, meniscus_position=meniscus_position)


def _advancing(text: str) -> float | None:
    """--advancing: 'static' (None) or an angle in degrees."""
    if text == "static":
        return None
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"--advancing {text!r}: 'static' or an angle in degrees") from None


def _receding(text: str) -> str | float:
    """--receding: 'static', 'bretherton' or a number."""
    if text in ("static", "bretherton"):
        return text
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"--receding {text!r}: 'static', 'bretherton' or a factor in [0.5, 2]") from None


def _progress(a: float, transit_s: float):
    """A line on stderr for each transit of a run: its oil, outflow, width and the cells
    that ran dry within a step."""
    def show(rec: dict) -> None:
        print(f"  transit {rec['time_s'] / transit_s:6.1f}: oil {rec['oil_m3'] * 2e12:7.1f} nl, "
              f"out / in {rec['outflow_over_supply']:5.3f}, width {rec['width_m'] / a:6.2f} a, "
              f"{rec['cells_opened_dry']} cells ran dry",
              file=sys.stderr, flush=True)
    return show


def plot_menisci(records: list[dict], a: float, out: Path) -> None:
    """The outline of each run's flooded region on one top view."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(11, 3.6))
    for rec in records:
        d = np.load(rec["state"])
        region = d["flooded"].astype(float)
        color = plt.cm.viridis(0.9 * rec["index"] / max(len(records) - 1, 1))
        ax.contour(d["x"] / a, d["y"] / a, region, levels=[0.5], linewidths=1.2,
                   colors=[color])
        ax.plot([], [], color=color,
                label=f"{rec['label']}: width {rec['metrics']['flooded_width_over_a']:.2f} a")
    ax.add_patch(plt.Circle((0, 0), 1.0, color="0.3"))
    ax.set_aspect("equal")
    ax.set_xlabel("x / a (rolling ->)")
    ax.set_ylabel("y / a")
    ax.set_title("thin-film model: flooded region (half domain)")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    fig.savefig(out, dpi=130, bbox_inches="tight")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("spec", nargs="?", default=str(ROOT / "runs" / "nominal.toml"))
    ap.add_argument("--cells", nargs="+", type=float, default=[0.2, 0.1],
                    help="cell sizes, units of a")
    ap.add_argument("--courant", nargs="+", type=float, default=[0.25],
                    help="step over a cell's transit at u")
    ap.add_argument("--film-factor", nargs="+", type=float, default=[1.0])
    ap.add_argument("--receding", nargs="+", default=["static"], type=_receding,
                    help="the receding meniscus's capillary pressure: static, bretherton or "
                         "a factor on the static one")
    ap.add_argument("--advancing", nargs="+", default=[None], type=_advancing,
                    help="the apparent angle (deg) of menisci advancing onto dry walls (off "
                         "the track), or static (the static angle)")
    ap.add_argument("--normal-length", nargs="+", type=float, default=[0.3],
                    help="units of a: the smoothing of the region for the receding "
                         "meniscus's normal (0.3-0.6 a give the same region; 0.15 a and "
                         "1.5 cells of 0.1 a shed it)")
    ap.add_argument("--meniscus", nargs="+", default=["sub-cell"], choices=["sub-cell", "cell"],
                    help="where a meniscus sits in its open cell (ThinFilmProblem."
                         "meniscus_position)")
    ap.add_argument("--transits", type=float, default=10.0)
    ap.add_argument("--balance", action="store_true",
                    help="stop when the outflow balances the supply and the oil stands")
    ap.add_argument("--tolerance", type=float, default=0.01,
                    help="of --balance: the mean outflow / supply within it of 1 and the "
                         "oil changed by less than it over --window transits")
    ap.add_argument("--window", type=int, default=5, help="of --balance, transits")
    ap.add_argument("--chain", action="store_true",
                    help="start each run from the previous one's state")
    ap.add_argument("--start", default="", metavar="STATE.npz",
                    help="start from a state a run wrote (any grid): every run, or the "
                         "first with --chain")
    ap.add_argument("--domain", nargs=3, type=float, default=[-11.0, 19.0, 11.0],
                    metavar=("X_MIN", "X_MAX", "Y_MAX"), help="units of a")
    ap.add_argument("--set", action="append", default=[], type=spec_option,
                    metavar="KEY=VALUE", help="spec options")
    ap.add_argument("--tag", default="")
    ap.add_argument("--plot", default="", help="a PNG of the menisci of all runs")
    ap.add_argument("--plot-records", nargs="+", default=[], metavar="RECORD.json",
                    help="with --plot: draw the runs of these records, run nothing")
    args = ap.parse_args(argv)
    if args.plot_records:
        import json

        runs = [run for r in args.plot_records for run in json.loads(Path(r).read_text())["runs"]]
        runs = [run | {"index": i} for i, run in enumerate(runs)]
        plot_menisci(runs, load_case_spec(args.spec, **dict(args.set)).a, Path(args.plot))
        return 0
    spec = load_case_spec(args.spec, **dict(args.set))
    gap, _ = load_gap(spec.contact)
    a = spec.a
    name = f"thin_film_region{'_' + args.tag if args.tag else ''}"
    record = {"spec": args.spec, "set": dict(args.set), "domain_over_a": args.domain,
              "start": args.start or None,
              "transits": args.transits, "balance": args.balance, "chain": args.chain,
              "tolerance": args.tolerance if args.balance else None,
              "window": args.window if args.balance else None,
              "transit_s": spec.transit_time, "runs": []}
    initial = load_state(Path(args.start)) if args.start else None
    start = initial
    print(f"{'cell/a':>7} {'Co':>5} {'film':>5} {'recede':>6} {'transits':>8} {'state':>5} "
          f"{'inlet/a':>8} "
          f"{'width/a':>8} {'length/a':>8} {'rear/a':>7} {'oil nl':>8} {'out/in':>7} "
          f"{'wall s':>7}", flush=True)
    for position, advancing, receding, nl, ff, courant, cell in itertools.product(
            args.meniscus, args.advancing, args.receding, args.normal_length,
            args.film_factor, args.courant, args.cells):
        prob = problem_from_spec(spec, gap, cell, tuple(args.domain), ff, receding, nl,
                                 position, advancing)
        dynamic = receding != "static" or advancing is not None
        t0 = time.perf_counter()
        sol = solve_thin_film(prob, transits_max=args.transits,
                              tolerance=args.tolerance if args.balance else 0.0,
                              transit_length=spec.run.transit_length * a,
                              start=start if args.chain else initial,
                              courant=courant, window=args.window,
                              progress=_progress(a, spec.transit_time))
        wall = time.perf_counter() - t0
        m = sol.metrics(a)
        label = f"{cell:g} a, Co {courant:g}, {ff:g} LL, {receding}" + (
            f", advancing {advancing:g} deg" if advancing is not None else "") + (
            f", normal {nl:g} a" if dynamic else "") + f", {position}"
        state = WORK / (args.tag or "default") / (
            f"{cell:g}_{courant:g}_{ff:g}_{receding}"
            + (f"_adv{advancing:g}" if advancing is not None else "")
            + (f"_n{nl:g}" if dynamic else "")
            + f"_{position}.npz")
        save_state(sol, state)
        record["runs"].append({"index": len(record["runs"]), "label": label,
                               "cell_over_a": cell, "courant": courant, "film_factor": ff,
                               "receding_meniscus": receding, "normal_length_over_a": nl,
                               "advancing_angle_deg": advancing,
                               "meniscus_position": position,
                               "wall_s": wall, "metrics": m,
                               "history": sol.history, "state": str(state)})
        save(f"{name}.json", record)
        start = sol
        print(f"{cell:7.3f} {courant:5.2f} {ff:5.2f} {str(receding)[:6]:>6} "
              f"{sol.time / spec.transit_time:8.1f} {m['state']:>5} "
              f"{m['inlet_meniscus_distance_over_a'] or 0:8.2f} "
              f"{m['flooded_width_over_a'] or 0:8.2f} {m['flooded_length_over_a'] or 0:8.2f} "
              f"{m['rear_meniscus_x_over_a'] or 0:7.2f} {m['oil_volume_m3'] * 1e12:8.1f} "
              f"{m['outflow_over_supply'] or 0:7.3f} {wall:7.0f}", flush=True)
    if args.plot:
        plot_menisci(record["runs"], a, Path(args.plot))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
