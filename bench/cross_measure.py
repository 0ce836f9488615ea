"""One state measured on every level's mesh: does the spread of a metric between resolution
levels come from the states the levels reach, or from reading the same state on meshes of
different cell sizes?

    python bench/cross_measure.py SNAPSHOT.npz [...] --on CASE [...] [--save NAME.json]

Each snapshot's oil fraction (``ehlfoam snapshot``) is interpolated onto the mesh of each
case named by ``--on`` the way a start on another mesh maps it (its source's oil volume
kept; a snapshot of another contact is refused), and the flow pattern is read there from the
mid-gap fraction as a run reads it (:mod:`ehlfoam.metrics.pattern`). Prints one table per metric, a row
per snapshot (the state) and a column per mesh; the spread along a row is the reading's, the
spread down a column the states'. Writes ``bench/results/NAME.json`` (default cross_measure.json).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.common import log, save  # noqa: E402
from ehlfoam.case.geometry import load_geometry
from ehlfoam.metrics import pattern as metrics
from ehlfoam.run.fields import Structure, mid_gap_raster
from ehlfoam.seed.snapshot import map_snapshot

METRICS = ("flooded_width_over_a", "inlet_meniscus_distance_over_a", "flooded_length_over_a")


def measure_on(snapshot: Path, case: Path) -> dict:
    """The flow pattern of ``snapshot``'s state read on ``case``'s mesh, mapped as a start
    from it would be (:func:`ehlfoam.seed.snapshot.map_snapshot`: refused for another contact),
    with how its oil was carried over (:func:`ehlfoam.seed.mapping.carry_oil`)."""
    s = Structure.load(case)
    geom = load_geometry(case)
    fields, oil, _ = map_snapshot(case, s, snapshot, ["alpha.oil"])
    pattern = metrics.flow_pattern_from_raster(mid_gap_raster(fields["alpha.oil"], s, geom))
    return {"cells": len(s.cell_volumes), "oil": oil,
            **{k: pattern[k] for k in METRICS}}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("snapshots", nargs="+", type=Path, help="states (ehlfoam snapshot files)")
    p.add_argument("--on", nargs="+", type=Path, required=True, metavar="CASE",
                   help="cases whose meshes read each state")
    p.add_argument("--save", default="cross_measure.json")
    p.add_argument("--note", default="")
    args = p.parse_args(argv)
    table = {}
    for snap in args.snapshots:
        for case in args.on:
            log(f"{snap.name} on {case}")
            table[f"{snap}|{case}"] = measure_on(snap, case)
    for key in METRICS:
        log(f"\n{key}: rows = state, columns = mesh read on")
        log(" " * 44 + "".join(f"{c.name:>10}" for c in args.on))
        for snap in args.snapshots:
            row = [table[f"{snap}|{c}"][key] for c in args.on]
            known = [v for v in row if v is not None]
            spread = np.ptp(known) if known else float("nan")
            log(f"{snap.stem[:44]:44}" + "".join(
                f"{v:10.3f}" if v is not None else f"{'-':>10}" for v in row)
                + f"   spread {spread:.3f}")
    path = save(args.save, {"note": args.note, "snapshots": [str(s) for s in args.snapshots],
                            "meshes": [str(c) for c in args.on], "readings": table})
    log(f"\nwritten {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
