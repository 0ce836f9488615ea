"""How fast the flooded region fills, measured where its oil leaves it: the oil held ahead of
planes x = X behind the contact, write by write.

A run's outflow through its outlet lags the region by the time the walls take to carry the
films there (the 7 a from the rear meniscus to the outlet take 7 a / u, 0.7 of a 10 a
transit), and right after a run starts from another mesh's fields most of it is film laid
down before the start. The oil
ahead of a plane just behind the rear meniscus, V(X) = sum(alpha V) over the cells whose
column centre lies at x < X (whole contact, doubled in a half domain), changes only by what
the supply brings in and what crosses the plane (nothing leaves through the side or the
upstream boundary ahead of it; the run's history.csv says so). So between two writes

    fill(X) = (V(X, t2) - V(X, t1)) / (in (t2 - t1))

is the share of the supply the region and its surroundings ahead of X kept over that
interval: exact by conservation, with no flux to interpolate. Where fill(X) is 0 the region
is at its balance; its change with the oil held says how far off that is.

    python bench/region_fill.py CASE [CASE ...] [--planes 14 16] [--from T] [--save NAME.json]
        [--plot OUT.png [--labels L ...]]

Prints, per case and write, the oil ahead of each plane and the fill over the interval up to
that write, and the fill over all the writes from T transits on (first to last write).
``--plot`` draws the fill at the first plane against time for each case, beside the films
their rear meniscus lays (``bench/wall_films.py --rear``, 1-2 a behind it, over
Landau-Levich).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.common import save  # noqa: E402
from bench.oil_change import columns  # noqa: E402
from ehlfoam.case.geometry import load_geometry
from ehlfoam.run import fields as case_fields
from ehlfoam.metrics.convergence import history_number, read_history_rows

NL = 1e-12  # m3 per nanolitre


def oil_ahead(oil: np.ndarray, structure: case_fields.Structure, a: float, mirror: float,
              planes_over_a: list[float]) -> list[float]:
    """The oil [m3, whole contact] in the columns whose centre lies at x < X, for each plane
    X [a], of the oil per column ``oil`` [m3, as meshed]."""
    x = structure.base_x / a
    return [mirror * float(oil[x < X].sum()) for X in planes_over_a]


def fills(times: np.ndarray, ahead: np.ndarray, inflow: np.ndarray) -> np.ndarray:
    """Per interval between consecutive writes (times [s], oil ahead [m3] shape (writes,
    planes), supply inflow [m3/s] per write): the change of the oil ahead over what the
    supply brought in, shape (writes - 1, planes)."""
    dt = np.diff(times)[:, None]
    q_in = 0.5 * (inflow[1:] + inflow[:-1])[:, None]
    return np.diff(ahead, axis=0) / (q_in * dt)


def region_fill(case: str | Path, planes_over_a: list[float],
                from_transits: float = 0.0) -> dict:
    """The oil ahead of each plane at each write of ``case`` from ``from_transits`` on, the
    fill over each interval and over them all (module docstring)."""
    case = Path(case)
    geom, structure = load_geometry(case), case_fields.Structure.load(case)
    inflow = {round(history_number(r["time_s"]), 9): history_number(r["oil_in_m3_s"])
              for r in read_history_rows(case)}
    times, ahead, q_in = [], [], []
    for t, folder in case_fields.time_folders(case):
        q = inflow.get(round(t, 9))
        if t < from_transits * geom.transit_time - 1e-12 or q is None:
            continue
        oil, _ = columns(folder, structure, geom.n_layers)
        times.append(t)
        ahead.append(oil_ahead(oil, structure, geom.a, geom.mirror, planes_over_a))
        q_in.append(q)
    if len(times) < 2:
        raise ValueError(f"{case} has {len(times)} write(s) in its history from "
                         f"{from_transits} transits on; the fill needs two")
    times, ahead, q_in = np.array(times), np.array(ahead), np.array(q_in)
    per = fills(times, ahead, q_in)
    overall = fills(times[[0, -1]], ahead[[0, -1]], np.full(2, q_in.mean()))[0]
    return {"case": str(case), "planes_over_a": planes_over_a, "from_transits": from_transits,
            "transit_s": geom.transit_time, "times_s": times.tolist(),
            "oil_in_m3_s": q_in.tolist(), "oil_ahead_m3": ahead.tolist(),
            "fill_per_interval": per.tolist(), "fill": overall.tolist(),
            "fill_sd": per.std(axis=0).tolist()}


def _print(result: dict) -> None:
    planes = result["planes_over_a"]
    print(f"\n{result['case']}")
    print("transits  " + "  ".join(f"oil<{X:g}a nl   fill" for X in planes))
    ahead, per = result["oil_ahead_m3"], result["fill_per_interval"]
    for i, t in enumerate(result["times_s"]):
        cells = "  ".join(
            f"{ahead[i][k] / NL:10.2f}  " + (f"{per[i - 1][k]:5.2f}" if i else "    -")
            for k in range(len(planes)))
        print(f"{t / result['transit_s']:8.3f}  {cells}")
    print("overall   " + "  ".join(f"{'':10s}  {f:5.2f}" for f in result["fill"]))


def plot(out: Path, results: list[dict], labels: list[str]) -> None:
    """The fill at each case's first plane and its rear films against time, one line a case."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from bench.wall_films import rear_films

    fig, (ax_fill, ax_film) = plt.subplots(1, 2, figsize=(10, 4), sharex=True)
    for r, label in zip(results, labels):
        t = np.array(r["times_s"]) / r["transit_s"]
        fill = np.array(r["fill_per_interval"])[:, 0]
        ax_fill.plot(0.5 * (t[1:] + t[:-1]), fill, "o-", ms=3, label=label)
        films = rear_films(Path(r["case"]), [(1.0, 2.0)], r["from_transits"])["writes"]
        ax_film.plot([w["transits"] for w in films], [w["film_over_ll"][0] for w in films],
                     "o-", ms=3, label=label)
    ax_fill.set_ylabel(f"fill ahead of x = {results[0]['planes_over_a'][0]:g} a "
                       "(share of the supply kept)")
    ax_film.set_ylabel("films 1-2 a behind the rear meniscus / Landau-Levich")
    ax_film.axhline(1.0, color="0.6", lw=0.8, ls="--")
    for ax in (ax_fill, ax_film):
        ax.set_xlabel("transits since the start")
        ax.grid(alpha=0.3)
    ax_fill.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("cases", nargs="+", type=Path)
    ap.add_argument("--planes", nargs="+", type=float, default=[14.0, 16.0],
                    help="x of the planes [a] (default 14 16)")
    ap.add_argument("--from", dest="start", type=float, default=0.0,
                    help="first write read [transits] (default 0)")
    ap.add_argument("--save", help="write bench/results/NAME.json")
    ap.add_argument("--plot", type=Path, help="draw the fill and the rear films to OUT.png")
    ap.add_argument("--labels", nargs="+", help="with --plot: one label a case")
    args = ap.parse_args(argv)
    if args.labels and len(args.labels) != len(args.cases):
        ap.error(f"--labels has {len(args.labels)} labels for {len(args.cases)} cases")
    results = [region_fill(c, args.planes, args.start) for c in args.cases]
    for r in results:
        _print(r)
    if args.save:
        save(args.save, {"command": " ".join(sys.argv), "results": results})
    if args.plot:
        plot(args.plot, results, args.labels or [str(c) for c in args.cases])
        print(f"wrote {args.plot}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
