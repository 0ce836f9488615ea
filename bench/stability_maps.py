"""Stability maps of the model ladder: where each rung comes to rest, where it does not within
its cap, where it fails, and where the thin-film state flips between one grid level and the
next, over speed x supply at the reference conditions (HVI60, 40 C, 20 N, gas below 90 kPa).

    python bench/stability_maps.py --work DIR [--maps DIR] [--speeds 2 100 6]
        [--supplies 0.3 0.6 1.1 2 4] [--levels coarse medium fine] [--wall-limit 120]
        [--3d-speeds 4.373 9.564 20.91] [--3d-supplies 0.6 2] [--3d-wall-limit 240]
        [--3d-from thin-film|puddle] [--no-3d] [--jobs 1] [--out FILE.json]
    python bench/stability_maps.py --work DIR --collect    # the maps of what has run
    python bench/stability_maps.py --quick

Every point runs through the batch (``ehlfoam batch``'s own engine, ``run_batch``), from
specs this script writes into the work folder: one batch of the thin-film levels (a sweep
of ``mesh.resolution`` x speed x supply, to rest, ``run.transits_max`` and
``run.wall_limit`` the cap a case), then one of the 3D interface scene on the coarse mesh
(OpenFOAM) on fewer points, each a one-speed ramp whose ``start_from`` is the thin-film
medium level's state at the same point (``--3d-from puddle``: a sweep from the default
start), capped by ``--3d-wall-limit`` and ``--3d-transits``. Running it again resumes: the
finished cases are kept.

Each point is classified: ``rest I`` / ``rest II`` (end_reason steady), ``not at rest``
(end_time: its transits ran out; wall_limit: its wall-clock cap), ``failed`` (status failed,
with the record's one-line reason or the log's last line). A thin-film level's point
*flips* where its state differs from the next finer level's at the same point (the finest
level: from the level below it); the 3D points are compared with the thin-film medium
level. Per pair of levels, how far the inlet meniscus, the flooded width and the bubble
move (in a).

Writes into ``--maps`` (default: the work folder): ``stability.csv`` (every point) and
``stability_<rung>.png`` (the speed x supply plane, log speed axis, a marker per point by
outcome, a ring where the state flips), and prints the tables. ``--quick``: two speeds x one
supply on the coarse and medium levels, a 129-point precalc, no 3D (seconds).

Costs: ``cost_s`` is the run's wall time on one core (a thin-film case runs on one thread:
its CPU time on an idle core) and, for a 3D case, the solver's own ``ExecutionTime`` (CPU).
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import time
from pathlib import Path
from typing import Any

from common import add_output_options, print_table, solver_cpu_s, work_folder, write_out
from ehlfoam._io import atomic_write_text
from ehlfoam.batch.launch import BatchOptions, run_batch
from ehlfoam.batch.results import read_results

LEVELS = ("coarse", "medium", "fine")
OUTCOMES = ("rest I", "rest II", "not at rest (end_time)", "not at rest (wall_limit)",
            "failed", "not run")
# outcome -> (marker, colour) on the maps
STYLE = {"rest I": ("o", "#1f77b4"), "rest II": ("^", "#d62728"),
         "not at rest (end_time)": ("s", "#ff7f0e"),
         "not at rest (wall_limit)": ("D", "#9467bd"), "failed": ("X", "black"),
         "not run": ("o", "none")}

BASE = """
[base]
scene = "{scene}"
contact = {{ load = 20.0, temperature = 40.0, lubricant = "HVI60", grid = {grid} }}
supply = {{ mode = "layers", track_half_width = 3e-4 }}
physics = {{ cavitation_pressure = 9e4 }}
{extra}"""

#: --quick: a small domain and a shorter steady window (seconds a case)
QUICK = ('domain = { upstream = 3.0, downstream = 4.0, side = 3.0 }\n'
         'thin_film = { steady_window = 3 }\n')

THIN_FILM = """name = "stability_thin_film"
description = "Stability map: the thin-film levels over speed x supply, 40 C, to rest"
{base}
[base.run]
transits_max = {transits!r}
wall_limit = {wall!r}

[[sweep]]
mesh.resolution = {levels}
contact.speed = {{ start = {lo!r}, stop = {hi!r}, num = {num}, spacing = "log" }}
supply = {supplies}
"""

THREE_D = """name = "stability_3d"
description = "Stability map: the 3D interface scene, coarse mesh, capped"
{base}
[base.run]
transits_max = {transits!r}
wall_limit = {wall!r}
{cases}"""


def _supply(layer: float) -> str:
    return f"{{disc_layer = {layer!r}, ball_layer = {layer!r}}}"


def key(speed: float) -> float:
    """A speed [m/s] to 4 significant digits (the case ids' rounding): points' key."""
    return float(f"{speed:.4g}")


def thin_film_spec(speeds: tuple[float, float, int], supplies: list[float],
                   levels: list[str], grid: int, transits: float, wall: float,
                   extra: str = "") -> str:
    """The batch spec of the thin-film levels: ``speeds`` (lowest, highest [m/s], how many,
    log-spaced) x supplies [m on each wall]."""
    lo, hi, num = speeds
    return THIN_FILM.format(base=BASE.format(grid=grid, scene="thin-film",
                                                      extra=extra), transits=transits,
                            wall=wall, levels=list(levels), lo=lo, hi=hi, num=int(num),
                            supplies="[" + ", ".join(_supply(s) for s in supplies) + "]")


def three_d_spec(points: list[tuple[float, float, Path | None]], grid: int, transits: float,
                 wall: float) -> str:
    """The batch spec of the 3D coarse interface scene: one one-speed ramp a point, started
    from its thin-film state, or a sweep case from the default start where it has none."""
    cases = []
    for k, (speed, layer, state) in enumerate(points):
        if state is None:
            cases.append(f'\n[[sweep]]\nmesh.resolution = ["coarse"]\n'
                         f"contact.speed = [{speed!r}]\nsupply = [{_supply(layer)}]\n")
        else:
            cases.append(f'\n[[ramp]]\nname = "P{k + 1}"\nbranches = "up"\n'
                         f'mesh.resolution = "coarse"\n'
                         f"contact.speed = [{speed!r}]\nsupply = {_supply(layer)}\n"
                         f'start_from = "{state}"\n')
    return THREE_D.format(base=BASE.format(grid=grid, scene="interface", extra=""),
                          transits=transits, wall=wall, cases="".join(cases))


def one_line(text: str, width: int = 160) -> str:
    """The last non-empty line of ``text``, at most ``width`` characters."""
    lines = [x.strip() for x in (text or "").splitlines() if x.strip()]
    return lines[-1][:width] if lines else ""


def outcome(row: dict) -> str:
    """The point's class from its results.csv row."""
    if row["status"] in ("pending", "interrupted", "running"):
        return "not run"
    if row["status"] != "finished":
        return "failed"
    if row["end_reason"] == "steady":
        return f"rest {row['state']}"
    if row["end_reason"] in ("end_time", "wall_limit"):
        return f"not at rest ({row['end_reason']})"
    return "failed"


def _float(value: Any) -> float | None:
    try:
        x = float(value)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def point_rows(batch: Path, rung_of: Any) -> list[dict]:
    """One row a case of the batch folder: the rung, speed [m/s], supply [m], outcome,
    state, metrics [a], cost [s] and, for a failed case, its one-line reason."""
    rows = []
    for r in read_results(batch):
        case = batch / r["case_dir"]
        reason = ""
        if outcome(r) == "failed":
            reason = one_line(r.get("reason") or "")
            if not reason and r.get("log") and (batch / r["log"]).is_file():
                reason = one_line((batch / r["log"]).read_text(errors="replace"))
        is_3d = r.get("scene") != "thin-film"
        cost = solver_cpu_s(case) if is_3d else None
        rows.append({
            "rung": rung_of(r), "case_id": r["case_id"],
            "speed_m_s": float(r["contact.speed"]), "supply_m": float(r["supply.disc_layer"]),
            "status": r["status"], "end_reason": r["end_reason"] or "",
            "steady": r.get("steady") == "true", "outcome": outcome(r),
            "state": r.get("state") or "",
            "transits": (_float(r.get("simulated_time_s")) or 0.0)
            / (_float(r.get("transit_time_s")) or math.inf),
            "inlet_meniscus_over_a": _float(r.get("inlet_meniscus_distance_over_a")),
            "flooded_width_over_a": _float(r.get("flooded_width_over_a")),
            "bubble_length_over_a": _float(r.get("bubble_length_over_a")),
            "bubble_enclosed": r.get("bubble_enclosed") or "",
            "cells": int(r["cells"]) if r.get("cells") else None,
            "cost_s": None if outcome(r) == "not run"
            else cost if cost is not None else _float(r.get("wall_s")),
            "failure_reason": reason})
    return rows


METRICS = ("inlet_meniscus_over_a", "flooded_width_over_a", "bubble_length_over_a")


def compare(rows: list[dict], rungs: list[str], against: dict[str, str]) -> None:
    """Set each row's ``vs`` (the rung it is compared with), ``vs_state``, ``flips`` and the
    metrics' moves ``d_<metric>`` [a] (this rung's minus the other's) where both ran."""
    at = {(r["rung"], key(r["speed_m_s"]), r["supply_m"]): r for r in rows}
    for r in rows:
        other = at.get((against.get(r["rung"], ""), key(r["speed_m_s"]), r["supply_m"]))
        r["vs"] = other["rung"] if other else ""
        r["vs_state"] = other["state"] if other else ""
        r["flips"] = bool(other and r["state"] and other["state"]
                          and r["state"] != other["state"])
        for m in METRICS:   # the interface scene has no gas: no bubble to compare
            gasless = m == "bubble_length_over_a" and r["rung"].startswith("3D")
            a, b = r.get(m), other.get(m) if other and not gasless else None
            r[f"d_{m}"] = a - b if a is not None and b is not None else None


def summary(rows: list[dict], rungs: list[str]) -> list[dict]:
    """Per rung: points and outcomes, flips against its comparison, the largest moves."""
    out = []
    for rung in rungs:
        mine = [r for r in rows if r["rung"] == rung]
        if not mine:
            continue
        costs = [r["cost_s"] for r in mine if r["cost_s"] is not None]
        s = {"rung": rung, "points": len(mine), "vs": mine[0]["vs"] or "-",
             **{o: sum(r["outcome"] == o for r in mine) for o in OUTCOMES},
             "flips": sum(r["flips"] for r in mine),
             "compared": sum(bool(r["vs_state"] and r["state"]) for r in mine),
             "cost_median_s": sorted(costs)[len(costs) // 2] if costs else None,
             "cost_total_s": sum(costs)}
        for m in METRICS:
            moves = [abs(r[f"d_{m}"]) for r in mine
                     if r[f"d_{m}"] is not None and not r["flips"]]
            s[f"max_d_{m}"] = max(moves) if moves else None
        out.append(s)
    return out


def write_csv(path: Path, rows: list[dict]) -> None:
    """``rows`` as CSV, atomically (SI: speed m/s, supply m; lengths in a; cost s)."""
    import io

    keys = list(rows[0]) if rows else []
    buf = io.StringIO()
    w = csv.DictWriter(buf, keys, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: ("" if v is None else repr(v) if isinstance(v, float) else v)
                    for k, v in r.items()})
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(path, buf.getvalue())


def draw(path: Path, rows: list[dict], rung: str, title: str) -> None:
    """The rung's map: speed [mm/s, log] x supply [um], a marker per point by outcome, a
    ring where the state flips against the rung it is compared with."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    mine = [r for r in rows if r["rung"] == rung]
    fig, ax = plt.subplots(figsize=(6.4, 3.4), dpi=100)
    for name in OUTCOMES:
        pts = [r for r in mine if r["outcome"] == name]
        if pts:
            marker, colour = STYLE[name]
            ax.scatter([r["speed_m_s"] * 1e3 for r in pts], [r["supply_m"] * 1e6 for r in pts],
                       marker=marker, s=46, label=name, zorder=3,
                       facecolors=colour, edgecolors=colour if colour != "none" else "grey")
    flips = [r for r in mine if r["flips"]]
    if flips:
        ax.scatter([r["speed_m_s"] * 1e3 for r in flips], [r["supply_m"] * 1e6 for r in flips],
                   s=190, facecolors="none", edgecolors="#2ca02c", linewidths=1.6,
                   label=f"state flips vs {flips[0]['vs']}", zorder=4)
    ax.set_xscale("log")
    ax.set_yscale("log")
    xs = sorted({r["speed_m_s"] * 1e3 for r in mine})
    ys = sorted({r["supply_m"] * 1e6 for r in mine})
    ax.set_xticks(xs, [f"{x:.3g}" for x in xs])
    ax.set_yticks(ys, [f"{y:.2g}" for y in ys])
    ax.minorticks_off()
    ax.set_xlim(xs[0] / 1.35, xs[-1] * 1.35)
    ax.set_ylim(ys[0] / 1.35, ys[-1] * 1.35)
    ax.set_xlabel("speed [mm/s]")
    ax.set_ylabel("layer on each wall [um]")
    ax.set_title(title, fontsize=9)
    ax.grid(True, alpha=0.25)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)


def run(spec: Path, out: Path, args: argparse.Namespace, jobs: int | None = None
        ) -> Path | None:
    """Run the batch ``spec`` into ``out`` (``--collect``: only read what it holds): the
    batch folder, or None if the batch was interrupted."""
    if args.collect:
        return out
    done = run_batch(spec, BatchOptions(out=out, jobs=jobs or args.jobs, quiet=True,
                                        regime=False, report=None))
    if done.interrupted:
        print("interrupted: run the same command again to resume")
        return None
    return done.batch_dir


def thin_film_rung(row: dict) -> str:
    return f"thin-film {row['mesh.resolution']}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--speeds", nargs=3, type=float, default=[2.0, 100.0, 6],
                    metavar=("LO", "HI", "NUM"), help="mm/s, log-spaced")
    ap.add_argument("--supplies", nargs="+", type=float, default=[0.3, 0.6, 1.1, 2.0, 4.0],
                    help="um of oil on each wall")
    ap.add_argument("--levels", nargs="+", default=list(LEVELS), choices=LEVELS)
    ap.add_argument("--grid", type=int, default=257, help="EHL precalc grid (contact.grid)")
    ap.add_argument("--transits", type=float, default=150.0, help="thin-film cap [transits]")
    ap.add_argument("--wall-limit", type=float, default=120.0, help="thin-film cap [s a case]")
    ap.add_argument("--3d-speeds", dest="speeds_3d", nargs="+", type=float,
                    default=[4.373, 9.564, 20.91], help="mm/s")
    ap.add_argument("--3d-supplies", dest="supplies_3d", nargs="+", type=float,
                    default=[0.6, 2.0], help="um")
    ap.add_argument("--3d-transits", dest="transits_3d", type=float, default=20.0)
    ap.add_argument("--3d-wall-limit", dest="wall_3d", type=float, default=240.0,
                    help="3D cap [s a case]")
    ap.add_argument("--3d-from", dest="from_3d", choices=("thin-film", "puddle"),
                    default="thin-film")
    ap.add_argument("--no-3d", action="store_true", help="the thin-film levels only")
    ap.add_argument("--collect", action="store_true",
                    help="run nothing: classify what the work folder's batches hold (cases "
                         "not run are drawn hollow)")
    ap.add_argument("--jobs", type=int, default=1, help="cases at once")
    ap.add_argument("--maps", type=Path, default=None, metavar="DIR",
                    help="where the CSV and the figures go (default: the work folder)")
    add_output_options(ap, work=True)
    args = ap.parse_args(argv)
    if args.quick:
        args.speeds, args.supplies, args.levels = [45.0, 100.0, 2], [0.3], ["coarse", "medium"]
        args.grid, args.no_3d, args.transits = 129, True, 40.0
    speeds = (args.speeds[0] / 1e3, args.speeds[1] / 1e3, int(args.speeds[2]))
    supplies = [s * 1e-6 for s in args.supplies]
    levels = [lv for lv in LEVELS if lv in args.levels]
    rungs = [f"thin-film {lv}" for lv in levels]
    against = {f"thin-film {a}": f"thin-film {b}" for a, b in zip(levels, levels[1:])}
    if len(levels) > 1:   # the finest: against the level below it
        against[rungs[-1]] = rungs[-2]
    record: dict[str, Any] = {"args": {k: str(v) for k, v in vars(args).items()}}
    with work_folder(args.work) as work:
        maps = args.maps or work
        spec = work / "stability_thin_film.toml"
        atomic_write_text(spec, thin_film_spec(speeds, supplies, levels, args.grid,
                                               args.transits, args.wall_limit,
                                               QUICK if args.quick else ""))
        t0, load = time.perf_counter(), os.getloadavg()[0]
        tf_dir = run(spec, work / "thin_film", args)
        record["thin_film_wall_s"] = time.perf_counter() - t0
        if tf_dir is None:
            return 130
        rows = point_rows(tf_dir, thin_film_rung)
        if not args.no_3d:
            seed_level = "medium" if "medium" in levels else levels[-1]
            states = {(key(r["speed_m_s"]), r["supply_m"]): tf_dir / "cases" / r["case_id"]
                      / "state.npz" for r in rows if r["rung"] == f"thin-film {seed_level}"}
            points = []
            for v in [key(s / 1e3) for s in args.speeds_3d]:
                for layer in [s * 1e-6 for s in args.supplies_3d]:
                    state = states.get((v, layer))
                    use = state if args.from_3d == "thin-film" and state and state.is_file() \
                        else None
                    points.append((v, layer, use))
            spec3 = work / "stability_3d.toml"
            atomic_write_text(spec3, three_d_spec(points, args.grid, args.transits_3d,
                                                  args.wall_3d))
            t0 = time.perf_counter()
            three_d = run(spec3, work / "three_d", args, jobs=1)
            record["three_d_wall_s"] = time.perf_counter() - t0
            if three_d is None:
                return 130
            rung3 = "3D coarse"
            rows += point_rows(three_d, lambda r: rung3)
            rungs.append(rung3)
            against[rung3] = f"thin-film {seed_level}"
            record["three_d_started_from"] = (f"thin-film {seed_level} state"
                                              if args.from_3d == "thin-film" else "puddle")
        compare(rows, rungs, against)
        table = summary(rows, rungs)
        write_csv(maps / "stability.csv", rows)
        for rung in rungs:
            s = next(t for t in table if t["rung"] == rung)
            draw(maps / f"stability_{rung.replace('thin-film ', 'tf_').replace(' ', '_')}.png",
                 rows, rung, f"{rung}: {s['points']} points, 40 C, 20 N, 90 kPa")
    ran = ("read only" if args.collect
           else f"thin-film batch {record['thin_film_wall_s']:.0f} s wall")
    print(f"{len(rows)} points, {len(rungs)} rungs (load {load:.2f} at the start; {ran})")
    print_table(table, [("rung", "rung", ""), ("points", "points", "d"),
                        ("rest I", "rest I", "d"), ("rest II", "rest II", "d"),
                        ("not at rest (end_time)", "end_time", "d"),
                        ("not at rest (wall_limit)", "wall_limit", "d"),
                        ("failed", "failed", "d"), ("not run", "not run", "d"),
                        ("vs", "vs", ""),
                        ("flips", "flips", "d"), ("compared", "of", "d"),
                        ("max_d_inlet_meniscus_over_a", "max d inlet [a]", ".2f"),
                        ("max_d_flooded_width_over_a", "max d width [a]", ".2f"),
                        ("max_d_bubble_length_over_a", "max d bubble [a]", ".2f"),
                        ("cost_median_s", "median cost [s]", ".1f"),
                        ("cost_total_s", "total cost [s]", ".0f")],
                title="stability per rung (flips and moves against the rung in 'vs')")
    odd = [r for r in rows if r["outcome"] != r"rest I" and r["outcome"] != "rest II"
           or r["flips"]]
    if odd:
        print_table(sorted(odd, key=lambda r: (r["rung"], r["supply_m"], r["speed_m_s"])),
                    [("rung", "rung", ""), ("speed_m_s", "speed [m/s]", ".4g"),
                     ("supply_m", "supply [m]", ".2g"), ("outcome", "outcome", ""),
                     ("state", "state", ""), ("vs_state", "vs state", ""),
                     ("transits", "transits", ".1f"), ("cost_s", "cost [s]", ".0f"),
                     ("failure_reason", "reason", "")],
                    title="points not at rest, failed or flipping")
    record.update(rows=rows, summary=table)
    write_out(args.out, record)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
