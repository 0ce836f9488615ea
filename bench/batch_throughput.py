"""Batch throughput: cases per hour on 2 cores, local 2-at-once against one at a time, and the
same batch through a Dask LocalCluster (identical results?).

    python bench/batch_throughput.py [--cores 2] [--end-time 0.1] [--speeds 10 20]
        [--supplies 2 3 4 6] [--work runs/bench/batch_throughput]

The batch: the small test case (tests/test_case.py: coarse, 3 layers, a 129-point precalc)
at each speed x supply, run to ``--end-time`` (a fixed simulated time: deterministic). The
EHL precalcs are solved before the clock starts (they are cached per machine). Three runs of
the same spec into three folders: ``--jobs 1``, ``--cores N`` (local process pool), and a
``distributed.LocalCluster(n_workers=1, threads_per_worker=N, processes=True,
resources={"CPU": N})``. Writes ``bench/results/batch_throughput.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from ehlfoam.batch.launch import BatchOptions, run_batch
from ehlfoam.batch.results import read_results
from ehlfoam.batch.plan import load_plan

RESULTS = ROOT / "bench" / "results"

BASE = """
name = "throughput"
[base]
contact = {{ speed = 0.02, grid = 129, tol_residual = 1e-4 }}
mesh = {{ resolution = "coarse", size_rim = 0.25, size_far = 1.2, n_layers = 3 }}
domain = {{ upstream = 5.0, downstream = 7.0, side = 5.0 }}
supply = {{ mode = "layers", disc_layer = 3e-6, ball_layer = 3e-6, track_half_width = 2.5e-4, initial_puddle = 3.0 }}
run = {{ end_time = {end_time!r}, writes_per_transit = 20 }}
[sweep]
contact.speed = {speeds}
supply = {supplies}
"""


def _spec(work: Path, args) -> Path:
    work.mkdir(parents=True, exist_ok=True)
    path = work / "throughput.toml"
    supplies = ", ".join(f"{{disc_layer = {um * 1e-6!r}, ball_layer = {um * 1e-6!r}}}"
                         for um in args.supplies)            # --speeds in mm/s, --supplies in um
    path.write_text(BASE.format(end_time=args.end_time, speeds=[u * 1e-3 for u in args.speeds],
                                supplies=f"[{supplies}]"))
    return path


def _warm_precalcs(spec: Path) -> float:
    from ehlfoam.gap.source import precalc_dir

    t0 = time.perf_counter()
    _, plan = load_plan(spec)
    for contact in {pc.spec.contact.model_dump_json(): pc.spec.contact for pc in plan}.values():
        precalc_dir(contact)
    return time.perf_counter() - t0


def _cpu_s() -> float:
    """CPU seconds of this process and its waited-for descendants (workers, solvers)."""
    return sum(r.ru_utime + r.ru_stime for r in (resource.getrusage(resource.RUSAGE_SELF),
                                                 resource.getrusage(resource.RUSAGE_CHILDREN)))


def _timed(spec: Path, out: Path, **kw) -> dict:
    if out.exists():
        shutil.rmtree(out)
    t0, c0 = time.perf_counter(), _cpu_s()
    outcome = run_batch(spec, BatchOptions(out=out, quiet=True, report=False, regime=False, **kw))
    wall, cpu = time.perf_counter() - t0, _cpu_s() - c0
    n = sum(outcome.counts.values())
    rows = read_results(out)
    return {"wall_s": wall, "cpu_s": cpu, "cores_used": cpu / wall,
            "cases": n, "finished": outcome.counts["finished"],
            "cases_per_hour": 3600.0 * n / wall,
            "case_wall_s": [float(r["case_wall_s"]) for r in rows if r.get("case_wall_s")],
            "solver_wall_s": [float(r["wall_s"]) for r in rows if r.get("wall_s")]}


def _dask_run(spec: Path, out: Path, cores: int) -> dict:
    from distributed import Client, LocalCluster

    t0, c0 = time.perf_counter(), _cpu_s()
    with LocalCluster(n_workers=1, threads_per_worker=cores, processes=True,
                      resources={"CPU": cores}, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        start = time.perf_counter() - t0
        result = _timed(spec, out, client=client)
    # the workers' CPU is counted once the cluster's processes have exited
    total_wall, result["cpu_s"] = time.perf_counter() - t0, _cpu_s() - c0
    result["cores_used"] = result["cpu_s"] / total_wall
    result["cluster_start_s"], result["cluster_wall_s"] = start, total_wall
    return result


def _compare(a: Path, b: Path) -> dict:
    """Largest differences between two runs' results (same case ids)."""
    ra = {r["case_id"]: r for r in read_results(a)}
    rb = {r["case_id"]: r for r in read_results(b)}
    rel = 0.0
    same_state = same_steps = True
    for cid, x in ra.items():
        y = rb[cid]
        same_state &= (x["status"], x["state"]) == (y["status"], y["state"])
        same_steps &= x.get("time_steps") == y.get("time_steps")
        va, vb = float(x["oil_volume_m3"]), float(y["oil_volume_m3"])
        rel = max(rel, abs(va - vb) / abs(va))
    return {"same_ids": list(ra) == list(rb), "same_status_and_state": same_state,
            "same_time_steps": same_steps, "oil_volume_max_rel_diff": rel}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--end-time", type=float, default=0.1, help="simulated time per case [s]")
    ap.add_argument("--speeds", nargs="+", type=float, default=[10.0, 20.0], help="mm/s")
    ap.add_argument("--supplies", nargs="+", type=float, default=[2.0, 3.0, 4.0, 6.0],
                    help="um on disc and ball")
    ap.add_argument("--work", default=str(ROOT / "runs" / "bench" / "batch_throughput"))
    args = ap.parse_args(argv)
    work = Path(args.work)
    spec = _spec(work, args)
    load0 = os.getloadavg()
    warm = _warm_precalcs(spec)
    serial = _timed(spec, work / "serial", jobs=1)
    local = _timed(spec, work / "local", cores=args.cores)
    dask = _dask_run(spec, work / "dask", args.cores)
    out = {
        "args": {k: v for k, v in vars(args).items()},
        "machine": {"cpus": os.cpu_count(), "loadavg_before": load0,
                    "loadavg_after": os.getloadavg()},
        "precalc_warmup_s": warm,
        "serial_jobs1": serial, f"local_cores{args.cores}": local,
        f"dask_localcluster_cpu{args.cores}": dask,
        "speedup_local_vs_serial": serial["wall_s"] / local["wall_s"],
        "speedup_dask_vs_serial": serial["wall_s"] / dask["wall_s"],
        "local_vs_serial": _compare(work / "serial", work / "local"),
        "dask_vs_local": _compare(work / "local", work / "dask"),
    }
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "batch_throughput.json").write_text(json.dumps(out, indent=2) + "\n")
    n = serial["cases"]
    print(f"{n} cases, {args.end_time * 1e3:g} ms simulated each, {args.cores} cores "
          f"(load before {load0[0]:.2f})")
    for name, r in (("one at a time", serial), (f"local, {args.cores} cores", local),
                    (f"Dask LocalCluster, {args.cores} CPU", dask)):
        print(f"  {name:28s} {r['wall_s']:7.1f} s  {r['cases_per_hour']:7.0f} cases/h  "
              f"{r['cores_used']:.2f} cores busy on average")
    print(f"  speed-up local {out['speedup_local_vs_serial']:.2f}, "
          f"Dask {out['speedup_dask_vs_serial']:.2f}")
    print(f"  Dask vs local: {out['dask_vs_local']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
