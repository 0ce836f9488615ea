"""What a batch costs: cases per hour one at a time, on a local process pool and through a
Dask LocalCluster (with the same results?), and what its reports cost.

    python bench/batch_cost.py [--cores 2] [--end-time 0.1] [--speeds 10 20]
        [--supplies 2 3 4 6] [--no-dask] [--repeat 3] [--work DIR] [--out FILE.json]
    python bench/batch_cost.py --quick

The batch: the small test case (coarse, 3 layers, a 129-point precalc, a small domain) at
each speed [mm/s] x supply [um on disc and ball], run to ``--end-time`` [s] of flow (a fixed
simulated time: deterministic). The EHL precalcs are solved before the clock starts (they
are cached per machine). The same batch runs three times into three folders: ``--jobs 1``,
``--cores N`` (the local process pool) and a ``distributed.LocalCluster(n_workers=1,
threads_per_worker=N, resources={"CPU": N})``; the table gives wall and CPU time, cases per
hour and the cores kept busy, and whether the three give the same states, steps and oil.
Then the reports, each in a fresh process (``python -m ehlfoam report``, imports included,
as ``ehlfoam report`` runs): one case's report (the median of ``--repeat``), and the batch's
report cold (every case report made) and warm (all reused). ``--quick``: two cases of 5 ms,
no Dask run (seconds).
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

from common import add_output_options, print_table, work_folder, write_out
from ehlfoam.batch.launch import BatchOptions, run_batch
from ehlfoam.batch.results import read_results
from ehlfoam.batch.plan import load_plan
from ehlfoam.gap.source import precalc_dir

BATCH = """
name = "throughput"
[base]
contact = {{ speed = 0.02, grid = 129, tol_residual = 1e-4 }}
mesh = {{ resolution = "coarse", size_rim = 0.25, size_far = 1.2, n_layers = 3 }}
domain = {{ upstream = 5.0, downstream = 7.0, side = 5.0 }}
run = {{ end_time = {end_time!r}, writes_per_transit = 20 }}
[base.supply]
mode = "layers"
disc_layer = 3e-6
ball_layer = 3e-6
track_half_width = 2.5e-4
initial_puddle = 3.0
[sweep]
contact.speed = {speeds}
supply = {supplies}
"""


def cpu_s() -> float:
    """CPU seconds of this process and its waited-for descendants (workers, solvers)."""
    return sum(r.ru_utime + r.ru_stime for r in (resource.getrusage(resource.RUSAGE_SELF),
                                                 resource.getrusage(resource.RUSAGE_CHILDREN)))


def timed_batch(name: str, spec: Path, out: Path, **kw) -> dict:
    """Run the batch into ``out``: its wall and CPU time, cases, cases per hour."""
    shutil.rmtree(out, ignore_errors=True)
    t0, c0 = time.perf_counter(), cpu_s()
    outcome = run_batch(spec, BatchOptions(out=out, quiet=True, report=None, regime=False, **kw))
    wall, cpu = time.perf_counter() - t0, cpu_s() - c0
    n = sum(outcome.counts.values())
    return {"run": name, "wall_s": wall, "cpu_s": cpu, "cores_busy": cpu / wall, "cases": n,
            "finished": outcome.counts.get("finished", 0), "cases_per_hour": 3600.0 * n / wall}


def dask_batch(spec: Path, out: Path, cores: int) -> dict:
    """:func:`timed_batch` through a Dask LocalCluster of one worker with ``cores`` threads,
    its start counted; its workers' CPU counted once they have exited."""
    from distributed import Client, LocalCluster

    t0, c0 = time.perf_counter(), cpu_s()
    with LocalCluster(n_workers=1, threads_per_worker=cores, processes=True,
                      resources={"CPU": cores}, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        start = time.perf_counter() - t0
        row = timed_batch(f"Dask LocalCluster, {cores} CPU", spec, out, client=client)
    wall, row["cpu_s"] = time.perf_counter() - t0, cpu_s() - c0
    row.update(wall_s=wall, cores_busy=row["cpu_s"] / wall, cluster_start_s=start,
               cases_per_hour=3600.0 * row["cases"] / wall)
    return row


def same_results(a: Path, b: Path) -> dict:
    """Whether two runs of the batch gave the same cases, states and steps, and the largest
    relative difference of their oil volumes."""
    ra = {r["case_id"]: r for r in read_results(a)}
    rb = {r["case_id"]: r for r in read_results(b)}
    same = list(ra) == list(rb)
    rel = 0.0
    for cid, x in ra.items():
        y = rb.get(cid, {})
        same &= (x["status"], x["state"], x.get("time_steps")) == (
            y.get("status"), y.get("state"), y.get("time_steps"))
        va, vb = float(x["oil_volume_m3"]), float(y.get("oil_volume_m3", "nan"))
        rel = max(rel, abs(va - vb) / abs(va))
    return {"same_cases_states_steps": same, "oil_volume_max_rel_diff": rel}


def timed_report(path: Path, *extra: str) -> dict:
    """Wall and CPU time [s] of ``python -m ehlfoam report PATH`` in a fresh process."""
    c0, t0 = cpu_s(), time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "ehlfoam", "report", str(path), *extra],
                          capture_output=True, text=True)
    wall, cpu = time.perf_counter() - t0, cpu_s() - c0
    if proc.returncode != 0:
        raise RuntimeError(f"report of {path} failed: {proc.stderr[-2000:]}")
    return {"wall_s": wall, "cpu_s": cpu}


def report_costs(batch: Path, cores: int, repeat: int) -> list[dict]:
    """One case's report (median of ``repeat``, each from scratch) and the batch's report,
    cold and warm."""
    case = next(p.parent for p in sorted((batch / "cases").glob("*/metrics.json")))
    runs = []
    for _ in range(repeat):
        shutil.rmtree(case / "report", ignore_errors=True)
        runs.append(timed_report(case))
    for folder in (batch / "cases").iterdir():
        shutil.rmtree(folder / "report", ignore_errors=True)
    rows = [{"what": f"case report (median of {repeat})",
             "wall_s": statistics.median(r["wall_s"] for r in runs),
             "cpu_s": statistics.median(r["cpu_s"] for r in runs)}]
    for state in ("cold", "warm"):
        rows.append({"what": f"batch report, {state} ({cores} processes)",
                     **timed_report(batch, "--jobs", str(cores))})
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--end-time", type=float, default=0.1, help="flow per case [s]")
    ap.add_argument("--speeds", nargs="+", type=float, default=[10.0, 20.0], help="mm/s")
    ap.add_argument("--supplies", nargs="+", type=float, default=[2.0, 3.0, 4.0, 6.0],
                    help="um on disc and ball")
    ap.add_argument("--no-dask", action="store_true", help="leave out the Dask run")
    ap.add_argument("--repeat", type=int, default=3, help="case reports timed")
    add_output_options(ap, work=True)
    args = ap.parse_args(argv)
    if args.quick:
        args.end_time, args.speeds, args.supplies = 0.005, [20.0], [2.0, 4.0]
        args.repeat, args.no_dask = 1, True
    with work_folder(args.work) as work:
        spec = work / "throughput.toml"
        spec.write_text(BATCH.format(
            end_time=args.end_time, speeds=[v * 1e-3 for v in args.speeds],
            supplies="[" + ", ".join(f"{{disc_layer = {s * 1e-6!r}, ball_layer = {s * 1e-6!r}}}"
                                     for s in args.supplies) + "]"))
        t0 = time.perf_counter()
        for contact in {pc.spec.contact.model_dump_json(): pc.spec.contact
                        for pc in load_plan(spec)[1]}.values():
            precalc_dir(contact)
        warm_s = time.perf_counter() - t0
        load = os.getloadavg()[0]
        rows = [timed_batch("one at a time", spec, work / "serial", jobs=1),
                timed_batch(f"local, {args.cores} cores", spec, work / "local",
                            cores=args.cores)]
        compared = {"local vs one at a time": same_results(work / "serial", work / "local")}
        if not args.no_dask:
            rows.append(dask_batch(spec, work / "dask", args.cores))
            compared["Dask vs local"] = same_results(work / "local", work / "dask")
        for r in rows:
            r["speed_up"] = rows[0]["wall_s"] / r["wall_s"]
        reports = report_costs(work / "local", args.cores, args.repeat)
    print(f"{rows[0]['cases']} cases of {args.end_time * 1e3:g} ms flow, {args.cores} cores "
          f"({os.cpu_count()} CPUs, load {load:.2f} at the start; precalcs {warm_s:.1f} s)")
    print_table(rows, [("run", "run", ""), ("cases", "cases", "d"),
                       ("finished", "finished", "d"), ("wall_s", "wall [s]", ".1f"),
                       ("cpu_s", "CPU [s]", ".1f"), ("cases_per_hour", "cases/h", ".0f"),
                       ("cores_busy", "cores busy", ".2f"), ("speed_up", "speed-up", ".2f")])
    for name, c in compared.items():
        print(f"{name}: same cases, states and steps: {c['same_cases_states_steps']}; "
              f"oil volume within {c['oil_volume_max_rel_diff']:.1e}")
    print_table(reports, [("what", "report", ""), ("wall_s", "wall [s]", ".1f"),
                          ("cpu_s", "CPU [s]", ".1f")])
    write_out(args.out, {"args": {k: str(v) for k, v in vars(args).items()},
                         "precalc_warmup_s": warm_s, "load_at_start": load, "batches": rows,
                         "compared": compared, "reports": reports})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
