"""A chart of rest values over a series of meshes, from ``bench/rest_value.py`` records: per
mesh and metric, where each run ended (up: still rising, down: still falling), the bracket
they leave the rest in (a bar) and the one-relaxation fit (a point with its sd; hollow where
fewer than two of several runs fix a rest of their own, so that the fit stands on the
model; left out where its relaxation time is not determined).

    python bench/rest_chart.py RECORD.json@SIZE [RECORD.json@SIZE ...]
        [--metrics KEY ...] [--xlabel TEXT] --out PNG

RECORD is a name under bench/results/ or a path; SIZE is the mesh's cell size (the x axis,
log scale, finest on the right).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.common import RESULTS  # noqa: E402
from ehlfoam.metrics.convergence import fixes_a_rest

LABELS = {"flooded_width_over_a": "flooded width / a",
          "inlet_meniscus_distance_over_a": "inlet meniscus distance / a",
          "flooded_length_over_a": "flooded length / a"}


def record_at(arg: str) -> tuple[dict, float]:
    """"RECORD.json@SIZE" -> (the record, SIZE)."""
    name, sep, size = arg.rpartition("@")
    if not sep:
        raise SystemExit(f"rest_chart: {arg!r}: give RECORD.json@SIZE")
    path = Path(name) if Path(name).is_file() else RESULTS / name
    try:
        return json.loads(path.read_text()), float(size)
    except (OSError, ValueError) as err:
        raise SystemExit(f"rest_chart: {arg!r}: {err}") from None


def determined(r: dict) -> bool:
    """True when a record's fit fixes its rest (``ehlfoam.metrics.convergence.fixes_a_rest`` over its
    longest run); else its rest is the model's guess, and the chart leaves it out."""
    return fixes_a_rest(r, max(run["t_last"] - run["t_first"] for run in r["runs"]))


def plot(records: list[tuple[dict, float]], metrics: list[str], xlabel: str, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(metrics), figsize=(4.6 * len(metrics), 3.8), squeeze=False)
    for ax, key in zip(axes[0], metrics):
        for record, size in records:
            r = record["metrics"].get(key)
            if r is None:
                continue
            if r["bracket"] is not None:
                ax.plot([size, size], r["bracket"], lw=9, alpha=0.25, color="C0",
                        solid_capstyle="butt")
            for run in r["runs"]:
                ax.plot(size * 1.06, run["last"], "^" if run["rate"] > 0 else "v",
                        color="C1", ms=6)
            if not determined(r):
                continue
            own = r.get("consistent") is not None or len(r["runs"]) == 1
            ax.errorbar(size, r["rest"], yerr=r["rest_sd"], fmt="o", color="C0",
                        mfc="C0" if own else "white", ms=6, capsize=3)
        ax.set_xscale("log")
        sizes = sorted({s for _, s in records})
        ax.set_xticks(sizes, [f"{s:g}" for s in sizes])
        ax.minorticks_off()
        ax.invert_xaxis()
        ax.set_xlabel(xlabel)
        ax.set_ylabel(LABELS.get(key, key))
        ax.grid(alpha=0.3)
    axes[0][0].plot([], [], lw=9, alpha=0.25, color="C0", label="bracket")
    axes[0][0].plot([], [], "^", color="C1", label="a run's end, rising")
    axes[0][0].plot([], [], "v", color="C1", label="a run's end, falling")
    axes[0][0].errorbar([], [], yerr=[], fmt="o", color="C0", label="fit (hollow: on the model)")
    axes[0][0].legend(fontsize=7, loc="best")
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("records", nargs="+", help="RECORD.json@SIZE")
    ap.add_argument("--metrics", nargs="+", default=list(LABELS), choices=list(LABELS))
    ap.add_argument("--xlabel", default="cell size [a]")
    ap.add_argument("--out", required=True, type=Path)
    args = ap.parse_args(argv)
    records = [record_at(a) for a in args.records]
    plot(records, args.metrics, args.xlabel, args.out)
    for key in args.metrics:
        rows = [(s, r["metrics"][key]) for r, s in records if key in r["metrics"]]
        print(key + ": " + "; ".join(
            f"{s:g}: fit " + (f"{m['rest']:.3f} +- {m['rest_sd']:.3f}" if determined(m)
                              else "not determined") + (
                "" if m["bracket"] is None else
                f", bracket {m['bracket'][0]:.3f}-{m['bracket'][1]:.3f}") for s, m in rows))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
