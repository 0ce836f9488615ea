"""What a report costs: one case report, and a batch report of 20 cases (cold: every case
report made; warm: all reused).

    python bench/report_bench.py [--sources CASE ...] [--n 20] [--jobs 2] [--repeat 3]

The sources are finished cases (default: runs/bench/supply_sweep/coarse/*). They are never
written to: each report runs on a "shadow" of a case, a folder of symbolic links to the
case's entries (the report writes only its own report/ folder). The batch is a fabricated
batch folder (cases/<id>/ shadows, results.csv, plan.json, one failed case). Each report
runs in a fresh process (``python -m ehlfoam report``), so the timings include the imports, as
``ehlfoam report`` does. Prints a table and writes bench/results/report_bench.json.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "bench" / "results"
DEFAULT_SOURCES = sorted((ROOT / "runs" / "bench" / "supply_sweep" / "coarse")
                         .glob("*/metrics.json"))
PARAM_COLUMNS = ("case_id", "speed_mm_s", "temperature_C", "load_N", "supply", "disc_layer_um",
                 "ball_layer_um", "resolution", "ramp", "ramp_step", "ramp_direction", "status",
                 "end_reason", "reason", "state", "wall_s", "cells", "case_dir", "log")


def shadow(case: Path, dst: Path) -> Path:
    """A folder of links to ``case``'s entries (no report/): reports write only there."""
    dst.mkdir(parents=True)
    for entry in case.iterdir():
        if entry.name != "report":
            os.symlink(entry.resolve(), dst / entry.name)
    return dst


def fabricate_batch(out: Path, sources: list[Path], n: int, failed: int = 1) -> Path:
    """A batch folder with ``n`` cases (the sources repeated), the last ``failed`` of them
    marked failed with a log, plus results.csv and plan.json."""
    rows, plan = [], []
    for k in range(n):
        src = sources[k % len(sources)]
        cid = f"c{k:02d}_{src.name}"
        folder = out / "cases" / cid
        is_failed = k >= n - failed
        if is_failed:   # a real copy of the small files, with a failed status and a log
            folder.mkdir(parents=True)
            for entry in src.iterdir():
                if entry.name not in ("report", "metrics.json", "log.interFoam", "history.csv"):
                    os.symlink(entry.resolve(), folder / entry.name)
            (folder / "log.interFoam").write_text(
                "Time = 0.01\n...\n--> FOAM FATAL ERROR: Maximum number of iterations exceeded\n")
            (folder / "metrics.json").write_text(json.dumps(
                {"status": "failed", "end_reason": "diverged", "cells": 5808}))
        else:
            shadow(src, folder)
        spec = json.loads((src / "ehlfoam" / "spec.json").read_text())
        metrics = json.loads((folder / "metrics.json").read_text())
        row = {"case_id": cid, "speed_mm_s": spec["contact"]["speed"] * 1e3,
               "temperature_C": spec["contact"]["temperature"],
               "load_N": spec["contact"]["load"], "supply": spec["supply"]["mode"],
               "disc_layer_um": spec["supply"]["disc_layer"] * 1e6,
               "ball_layer_um": spec["supply"]["ball_layer"] * 1e6,
               "resolution": spec["mesh"]["resolution"], "ramp": "", "ramp_step": "",
               "ramp_direction": "", "status": metrics.get("status"),
               "end_reason": metrics.get("end_reason"),
               "reason": "solver diverged (time step collapsed)" if is_failed else "",
               "state": metrics.get("state"), "wall_s": metrics.get("wall_s"),
               "cells": metrics.get("cells"), "case_dir": f"cases/{cid}",
               "log": f"cases/{cid}/log.interFoam"}
        for key, value in metrics.items():
            if key not in row and not isinstance(value, (list, dict)):
                row[key] = value
        rows.append(row)
        plan.append({"id": cid, "params": {"contact.speed": spec["contact"]["speed"]},
                     "ramp": None})
    columns = list(PARAM_COLUMNS) + sorted({k for r in rows for k in r} - set(PARAM_COLUMNS))
    with open(out / "results.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=columns)
        writer.writeheader()
        writer.writerows(rows)
    (out / "plan.json").write_text(json.dumps(plan, indent=1))
    return out


def timed_report(path: Path, *extra: str) -> tuple[float, float]:
    """(wall time, CPU time) [s] of ``python -m ehlfoam report PATH`` in a fresh process; the
    CPU time (user + system, the process and its workers) is what the report costs whatever
    else runs on the machine."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "ehlfoam", "report", str(path), *extra], cwd=ROOT,
                          capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise RuntimeError(f"report of {path} failed: {proc.stderr[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sources", nargs="*", type=Path, default=[p.parent for p in DEFAULT_SOURCES])
    ap.add_argument("--n", type=int, default=20)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    sources = [p for p in args.sources if (p / "metrics.json").is_file()]
    if not sources:
        print("no finished source cases (run bench/supply_sweep.py or pass --sources)",
              file=sys.stderr)
        return 2
    tmp = Path(tempfile.mkdtemp(prefix="report-bench-"))
    try:
        load_start = os.getloadavg()[0]
        case_walls, case_cpus, per_step = [], [], []
        for k in range(args.repeat):
            case = shadow(sources[k % len(sources)], tmp / f"case{k}")
            wall, cpu = timed_report(case)
            case_walls.append(wall)
            case_cpus.append(cpu)
            per_step.append(json.loads((case / "report" / "report.json").read_text()))
        batch = fabricate_batch(tmp / "batch", sources, args.n)
        cold, cold_cpu = timed_report(batch, "--jobs", str(args.jobs))
        cold_json = json.loads((batch / "report" / "report.json").read_text())
        warm, warm_cpu = timed_report(batch, "--jobs", str(args.jobs))
        result = {
            "cpus": os.cpu_count(), "load_avg_1min_at_start": load_start,
            "load_avg_1min_at_end": os.getloadavg()[0],
            "sources": [str(s.relative_to(ROOT)) if s.is_relative_to(ROOT) else str(s)
                        for s in sources],
            "cells": [json.loads((s / "metrics.json").read_text()).get("cells") for s in sources],
            "case_report_wall_s": case_walls,
            "case_report_median_s": statistics.median(case_walls),
            "case_report_cpu_s": case_cpus,
            "case_report_steps_s": per_step[-1]["timings_s"],
            "case_report_inside_s": [p["wall_s"] for p in per_step],
            "batch_cases": args.n, "batch_jobs": args.jobs,
            "batch_cold_s": cold, "batch_cold_cpu_s": cold_cpu,
            "batch_cold_case_reports_s": cold_json["case_reports_s"],
            "batch_warm_s": warm, "batch_warm_cpu_s": warm_cpu,
        }
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "report_bench.json").write_text(json.dumps(result, indent=2) + "\n")
    print(f"{'what':44s} {'wall [s]':>9s} {'CPU [s]':>8s}  limit (wall)")
    print(f"{'case report (median of ' + str(args.repeat) + ', fresh process)':44s} "
          f"{result['case_report_median_s']:9.1f} {statistics.median(case_cpus):8.1f}  30 s")
    for name, sec in result["case_report_steps_s"].items():
        print(f"{'  ' + name:44s} {sec:9.2f}")
    print(f"{f'batch of {args.n}, cold ({args.jobs} processes)':44s} {cold:9.1f} "
          f"{cold_cpu:8.1f}  120 s")
    print(f"{f'batch of {args.n}, warm (case reports reused)':44s} {warm:9.1f} "
          f"{warm_cpu:8.1f}")
    print(f"(load average {load_start:.2f} at the start, "
          f"{result['load_avg_1min_at_end']:.2f} at the end, on {result['cpus']} CPUs; "
          f"CPU: user + system of the report and its workers)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
