"""Speed against accuracy over the model ladder: each reference point run on every rung, the
error of each rung against the finest that comes to rest, against its CPU cost.

    python bench/ladder_accuracy.py [--rungs R ...] [--points N ...] [--cap-s S]
        [--procs N] [--jobs N] [--set KEY=VALUE ...] [--set-3d KEY=VALUE ...]
        [--join FILE.json ...] [--reference RUNG] [--charts DIR] [--work DIR] [--out FILE.json]
    python bench/ladder_accuracy.py --quick

The reference points (HVI60, 20 N, gas below 90 kPa, layers on disc and ball over a +-0.3 mm
track; the default batch's conditions): 40 C at 8 and 17 mm/s with 0.45 and 1 um layers
(both states), 25 C and 60 C at 12 mm/s with 0.45 um. Each point is written and run on each
rung (``ehlfoam case --rung`` + ``ehlfoam run``; one after the other on one core, or
``--jobs`` cases side by side, the 3D ones on ``--procs`` MPI ranks each): the thin-film
levels to rest (150 transits at most); the 3D rungs in the gas-release scene (the thin-film
outlet's counterpart), started from the point's thin-film balance, capped at ``--cap-s`` of
wall time and 6 transits (``--set-3d`` sets a spec option on the 3D rungs alone, e.g.
``scene=interface``). The reference of a point is the finest rung (the last of
``--rungs``) that came to rest (``steady``). Per metric (state, inlet meniscus, flooded
width, bubble or wake length, oil held) each rung's error against it: the state right or
wrong, the others relative, each metric the run's mean over its last transit (a single
write carries the menisci's jitter; the last write's where the state changed within it),
and on the 3D rungs how much of the supply track upstream of the region its last write left
bare (the layers broken into drops: docs/models/interface.md#supply-layers-broken). Cost:
the CPU time of the run (the process's own, the thin-film start included, plus the OpenFOAM
solver's on every rank), the EHL precalc excluded (solved first, cached). Prints a
row per point and rung and a summary per rung (error, median CPU, CPU against the
reference's); ``--charts DIR`` draws one chart per metric, error against CPU (log axis), a
marker per rung. ``--join`` adds the rows of earlier runs (their ``--out``) at the points
run here, for a rung dear enough to run once (a joined rung not run here counts as finer than
those that are); ``--reference RUNG`` makes that rung's row each point's reference, at rest
or not (a 3D run capped before its rest; the row table says which rows rested). ``--quick``:
two points on the two cheapest thin-film levels over a small domain (seconds).
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from concurrent.futures import ProcessPoolExecutor
from contextlib import nullcontext
from pathlib import Path

from common import (add_output_options, count_option, print_table, solver_cpu_s,
                    spec_option, work_folder, write_out)
from ehlfoam.case.writer import write_case
from ehlfoam.errors import SpecError
from ehlfoam.gap.source import precalc_dir
from ehlfoam.metrics.convergence import window_mean
from ehlfoam.run.monitor import run_case
from ehlfoam.seed.follow import write_started_case
from ehlfoam.spec.case import CaseSpec, make_case_spec

#: the default batch's conditions (examples/batches/default.toml)
BASE = {"contact": {"load": 20.0, "lubricant": "HVI60"},
        "supply": {"mode": "layers", "track_half_width": 3e-4},
        "physics": {"cavitation_pressure": 9e4}}
#: (label, temperature [C], speed [m/s], layer on each wall [m])
POINTS = [("40C 8mm/s 0.45um", 40.0, 0.008, 0.45e-6), ("40C 8mm/s 1um", 40.0, 0.008, 1e-6),
          ("40C 17mm/s 0.45um", 40.0, 0.017, 0.45e-6), ("40C 17mm/s 1um", 40.0, 0.017, 1e-6),
          ("25C 12mm/s 0.45um", 25.0, 0.012, 0.45e-6), ("60C 12mm/s 0.45um", 60.0, 0.012,
                                                        0.45e-6)]
RUNGS = ["thin-film-coarse", "thin-film-medium", "thin-film-fine", "coarse"]
#: --quick: a small domain and a cheap precalc
QUICK = {"contact": {"grid": 129, "tol_residual": 1e-4},
         "domain": {"upstream": 5.0, "downstream": 8.0, "side": 5.0}}
#: metric: (record key, relative error)
METRICS = {"inlet": "inlet_meniscus_distance_over_a", "width": "flooded_width_over_a",
           "bubble": "bubble_length_over_a", "wake": "wake_gas_length_over_a",
           "oil": "oil_volume_m3"}


def point_spec(point: tuple, rung: str, base: dict, cap_s: float, procs: int = 1,
               overrides: dict | None = None, overrides_3d: dict | None = None) -> CaseSpec:
    """The case spec of a reference point on a rung (a 3D rung on ``procs`` MPI ranks),
    with ``overrides`` (dotted spec keys, as ``ehlfoam case --set``) and, on a 3D rung,
    ``overrides_3d`` after them."""
    _, temperature, speed, layer = point
    data = {**base, "contact": {**base["contact"], "speed": speed,
                                "temperature": temperature},
            "supply": {**base["supply"], "disc_layer": layer, "ball_layer": layer}}
    overrides = dict(overrides or {})
    if rung.startswith("thin-film"):
        data["run"] = {"transits_max": 150.0}
    else:
        data.update(scene="gas-release", run={"start": "thin-film", "transits_max": 6.0,
                                              "wall_limit": cap_s, "n_procs": procs})
        overrides.update(overrides_3d or {})
    return make_case_spec(data, rung=rung, **overrides)


def run_point(label: str, rung: str, spec: CaseSpec, case: Path) -> dict:
    """Write and run the point ``label`` on ``rung`` (its case spec ``spec``): its metrics,
    end and CPU [s] (the solver's on every rank: its master's ``ExecutionTime`` times the
    ranks)."""
    precalc_dir(spec.contact)                       # solved before the clock starts
    c0, t0 = time.process_time(), time.perf_counter()
    if spec.scene == "thin-film":
        write_case(spec, case, overwrite=True)
    else:
        write_started_case(spec, case, None, overwrite=True)
    m = run_case(case)
    cpu = time.process_time() - c0 + (solver_cpu_s(case) or 0.0) * spec.run.n_procs
    row = {"point": label, "rung": rung, "cpu_s": cpu, "wall_s": time.perf_counter() - t0,
           "end_reason": m.get("end_reason"), "steady": bool(m.get("steady")),
           "state": m.get("state"), "bare_track": m.get("supply_track_bare_fraction")}
    row.update(last_transit_metrics(case, m))
    return row


def last_transit_metrics(case: Path, last_write: dict) -> dict:
    """Each metric of a run case: its mean over the writes of the last transit, and its
    jitter there (``jitter_<metric>``, the standard deviation), as a single write carries
    the menisci's write-to-write jitter (up to 0.2 a on the 3D levels); the last write's
    (``last_write``: metrics.json) where the state changed within that transit, which makes
    the bubble's mean meaningless. ``writes_averaged``: 1 there."""
    w = window_mean(case, keys=tuple(METRICS.values()))
    if w is None or len(w["states"]) != 1:
        return {name: last_write.get(key) for name, key in METRICS.items()} | {
            "writes_averaged": 1}
    return ({name: w[key] for name, key in METRICS.items()}
            | {f"jitter_{name}": w["jitter"][key] for name, key in METRICS.items()}
            | {"writes_averaged": w["writes_averaged"]})


def run_all(specs: list[tuple], jobs: int, work: Path) -> list[dict]:
    """Every (point label, rung, spec) of ``specs``, ``jobs`` at a time: the rows in the
    same order."""
    tasks = [(label, rung, spec, work / f"{label.replace(' ', '_').replace('/', '')}_{rung}")
             for label, rung, spec in specs]
    with ProcessPoolExecutor(jobs) if jobs > 1 else nullcontext() as pool:
        runs = pool.map(run_point, *zip(*tasks)) if pool else map(run_point, *zip(*tasks))
        rows = []
        for r in runs:
            rows.append(r)
            print(f"{r['point']} {r['rung']}: {r['state']} {r['end_reason']} "
                  f"{r['cpu_s']:.1f} s CPU", flush=True)
    return rows


def joined_rows(files: list[Path], labels: list[str], rungs: list[str]) -> list[dict]:
    """The rows of earlier runs' ``--out`` files at the points ``labels`` on rungs not in
    ``rungs`` (the runs here win), each marked ``joined``. Raises ValueError naming a file
    that cannot be read or has no rows."""
    out = []
    for path in files:
        try:
            rows = json.loads(Path(path).read_text())["rows"]
        except (OSError, ValueError, KeyError, TypeError) as err:
            raise ValueError(f"--join {path}: not a ladder_accuracy --out file ({err})") from err
        if not rows:
            raise ValueError(f"--join {path}: it has no rows")
        out += [r | {"joined": str(path)} for r in rows
                if r["point"] in labels and r["rung"] not in rungs]
    return out


def errors(rows: list[dict], rungs: list[str],
           reference: str | None = None) -> dict[str, dict]:
    """Each point's reference row (the finest rung at rest, or the ``reference`` rung's row
    at rest or not) and every row's errors against it, in place: ``state_ok`` and
    ``err_<metric>`` (relative; the bubble's where the reference has one, else the
    wake's)."""
    refs = {}
    for point in dict.fromkeys(r["point"] for r in rows):
        candidates = [r for r in rows if r["point"] == point and (
            r["rung"] == reference if reference else r["steady"])]
        if not candidates:
            continue
        ref = max(candidates, key=lambda r: rungs.index(r["rung"]))
        refs[point] = ref
        for r in (r for r in rows if r["point"] == point):
            r["reference"] = ref["rung"]
            r["state_ok"] = r["state"] == ref["state"] if r["state"] else None
            for name in METRICS:
                mine, theirs = r.get(name), ref.get(name)
                ok = mine is not None and theirs
                r[f"err_{name}"] = abs(mine - theirs) / abs(theirs) if ok else None
    return refs


def summary(rows: list[dict], rungs: list[str]) -> list[dict]:
    """One row per rung: states right, worst and median errors, median CPU and its ratio to
    the reference's."""
    out = []
    ref_cpu = {r["point"]: r["cpu_s"] for r in rows if r.get("reference") == r["rung"]}
    for rung in rungs:
        mine = [r for r in rows if r["rung"] == rung]
        if not mine:
            continue
        row = {"rung": rung, "points": len(mine), "at_rest": sum(r["steady"] for r in mine),
               "states_right": sum(bool(r.get("state_ok")) for r in mine),
               "cpu_median_s": statistics.median(r["cpu_s"] for r in mine)}
        speedups = [ref_cpu[r["point"]] / r["cpu_s"] for r in mine if r["point"] in ref_cpu]
        row["cpu_over_reference"] = 1 / statistics.median(speedups) if speedups else None
        for name in METRICS:
            errs = [r[f"err_{name}"] for r in mine if r.get(f"err_{name}") is not None]
            row[f"max_{name}"] = max(errs) if errs else None
        out.append(row)
    return out


def charts(rows: list[dict], rungs: list[str], folder: Path) -> list[Path]:
    """One chart per metric: each point's error against its CPU, a marker per rung."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    markers = dict(zip(rungs, "osD^vP"))
    for name in ("state", *METRICS):
        key = "state_ok" if name == "state" else f"err_{name}"
        fig, ax = plt.subplots(figsize=(5.5, 3.6))
        for rung in rungs:
            pts = [(r["cpu_s"], (0.0 if r[key] else 1.0) if name == "state" else 100 * r[key])
                   for r in rows if r["rung"] == rung and r.get(key) is not None]
            if pts:
                ax.plot(*zip(*pts), linestyle="none", marker=markers[rung], label=rung)
        ax.set_xscale("log")
        ax.set_xlabel("CPU time of the run [s]")
        ax.set_ylabel("state wrong (1) / right (0)" if name == "state"
                      else f"{name}: error against the reference [%]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        fig.tight_layout()
        path = folder / f"ladder_{name}.png"
        fig.savefig(path, dpi=100)
        plt.close(fig)
        paths.append(path)
    return paths


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rungs", nargs="+", default=RUNGS, help="cheapest first")
    ap.add_argument("--points", nargs="+", type=int, default=list(range(len(POINTS))),
                    help="indices into the reference points (0-5)")
    ap.add_argument("--cap-s", type=float, default=1200.0,
                    help="wall-time cap of a 3D run [s] (default 1200)")
    ap.add_argument("--procs", type=count_option(1, 64), default=1, metavar="N",
                    help="MPI ranks of each 3D case (1-64, default 1)")
    ap.add_argument("--jobs", type=count_option(1, 64), default=1, metavar="N",
                    help="cases run side by side (1-64, default 1)")
    ap.add_argument("--set", action="append", default=[], type=spec_option,
                    metavar="KEY=VALUE", help="a spec option on every case (repeatable)")
    ap.add_argument("--set-3d", action="append", default=[], type=spec_option,
                    metavar="KEY=VALUE", help="a spec option on the 3D rungs' cases, after "
                    "--set's (repeatable)")
    ap.add_argument("--join", nargs="+", type=Path, default=[], metavar="FILE.json",
                    help="rows of earlier runs (their --out) at the points run here")
    ap.add_argument("--reference", default=None, metavar="RUNG",
                    help="the rung whose rows are the references, at rest or not "
                    "(default: the finest rung at rest at each point)")
    ap.add_argument("--charts", type=Path, default=None, metavar="DIR",
                    help="draw one chart per metric into DIR")
    add_output_options(ap, work=True)
    args = ap.parse_args(argv)
    base, rungs, points = BASE, args.rungs, [POINTS[i] for i in args.points]
    if args.quick:
        base = {**BASE, **QUICK, "contact": {**BASE["contact"], **QUICK["contact"]}}
        rungs, points = ["thin-film-coarse", "thin-film-medium"], [POINTS[0], POINTS[2]]
    try:                                            # every spec checked before any run
        specs = [(point[0], rung, point_spec(point, rung, base, args.cap_s, args.procs,
                                             dict(args.set), dict(args.set_3d)))
                 for point in points for rung in rungs]
        joined = joined_rows(args.join, [p[0] for p in points], rungs)
    except (SpecError, ValueError) as err:
        ap.error(str(err))
    rungs = rungs + list(dict.fromkeys(j["rung"] for j in joined))   # joined: the finest
    if args.reference is not None and args.reference not in rungs:
        ap.error(f"--reference {args.reference}: not a rung run or joined here "
                 f"({', '.join(rungs)})")
    with work_folder(args.work) as work:
        rows = run_all(specs, args.jobs, work)
    order = [p[0] for p in points]
    rows = sorted(rows + joined, key=lambda r: (order.index(r["point"]), rungs.index(r["rung"])))
    errors(rows, rungs, args.reference)
    print_table(rows, [
        ("point", "point", ""), ("rung", "rung", ""), ("end_reason", "end", ""),
        ("state", "state", ""), ("steady", "at rest", ""), ("inlet", "inlet [a]", ".2f"),
        ("width", "width [a]", ".2f"),
        ("bubble", "bubble [a]", ".2f"), ("wake", "wake [a]", ".2f"),
        ("oil", "oil [m3]", ".3g"), ("bare_track", "bare track", ".0%"),
        ("cpu_s", "CPU [s]", ".1f"), ("reference", "ref", ""),
        ("err_inlet", "e inlet", ".3f"), ("err_width", "e width", ".3f"),
        ("err_bubble", "e bubble", ".3f"), ("err_oil", "e oil", ".3f")],
        "every point on every rung (errors relative to the point's reference)")
    table = summary(rows, rungs)
    print_table(table, [
        ("rung", "rung", ""), ("points", "points", "d"), ("at_rest", "at rest", "d"),
        ("states_right", "states right", "d"), ("max_inlet", "max e inlet", ".3f"),
        ("max_width", "max e width", ".3f"), ("max_bubble", "max e bubble", ".3f"),
        ("max_oil", "max e oil", ".3f"), ("cpu_median_s", "CPU median [s]", ".1f"),
        ("cpu_over_reference", "CPU / ref", ".3g")],
        "per rung: worst error against the reference, cost")
    if args.charts:
        for path in charts(rows, rungs, args.charts):
            print(f"chart {path}")
    write_out(args.out, {"rungs": rungs, "points": [p[0] for p in points],
                         "cap_s": args.cap_s, "procs": args.procs, "jobs": args.jobs,
                         "set": dict(args.set), "set_3d": dict(args.set_3d),
                         "join": [str(f) for f in args.join], "reference": args.reference,
                         "rows": rows, "summary": table})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
