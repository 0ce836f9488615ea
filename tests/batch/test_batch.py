"""Batches with the real OpenFOAM: plan -> cases -> results.csv, ramps, resume, kill and
resume, the Dask path on a LocalCluster, bad specs.

The cases are the small test case of test_case.py (coarse, a cheap precalc, a few hundred
steps): each builds and runs in a few seconds.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest
from foamlib import FoamFieldFile

from ehlfoam.spec.case import make_case_spec
from ehlfoam.case.geometry import load_geometry
from ehlfoam.case.writer import write_case
from ehlfoam.cli import batch as batch_cli
from ehlfoam.run import fields as case_fields
from ehlfoam.batch.launch import BatchError, BatchOptions, run_batch
from ehlfoam.batch.executors import parse_slurm, slurm_cluster
from ehlfoam.batch.folder import CASES
from ehlfoam.batch.results import FIXED_COLUMNS, read_results
from ehlfoam.metrics.record import SCHEMA_VERSION, MetricsRecord, read_metrics
from ehlfoam.run.fields import time_folders
from ehlfoam.seed.previous import seed_from_previous

ROOT = Path(__file__).resolve().parents[2]
BATCH = [sys.executable, "-m", "ehlfoam.cli.batch"]

#: tests/test_case.py's SMALL case as a [base] table
BASE = """
[base]
contact = { speed = 0.02, grid = 129, tol_residual = 1e-4 }
mesh = { resolution = "coarse", size_rim = 0.25, size_far = 1.2, n_layers = 3, wall_grading = 3.0 }
domain = { upstream = 5.0, downstream = 7.0, side = 5.0 }
supply = { mode = "layers", disc_layer = 3e-6, ball_layer = 3e-6, track_half_width = 2.5e-4, initial_puddle = 3.0 }
run = { end_time = 1e-3, writes_per_transit = 1000 }
"""
SMALL = tomllib.loads(BASE)["base"]

#: two sweep cases, a case whose EHL precalc cannot converge (1 um/s: M ~ 4e6, two hundred
#: times the regime the solver is made for, its pressure goes non-finite: a build failure),
#: and a ramp 10 -> 20 -> 10 mm/s
TINY = BASE + """
[[sweep]]
contact.speed = [0.01, 0.02]
[[sweep]]
contact.speed = [1e-6]
[[ramp]]
name = "A"
contact.speed = [0.01, 0.02]
"""
FAILING = "u00.001_s3um_T40_F20_coarse"
RAMP = ["rampA_up01_u10.0_s3um_T40_F20_coarse", "rampA_up02_u20.0_s3um_T40_F20_coarse",
        "rampA_down03_u10.0_s3um_T40_F20_coarse"]


def _spec(folder: Path, name: str, text: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.toml"
    path.write_text(text)
    return path


def _mtimes(batch: Path) -> dict[str, int]:
    return {p.parent.name: p.stat().st_mtime_ns for p in batch.glob(f"{CASES}/*/metrics.json")}


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    """The tiny batch run once locally, 2 at a time."""
    spec = _spec(tmp_path_factory.mktemp("batch"), "tiny", TINY)
    outcome = run_batch(spec, BatchOptions(out=spec.with_suffix(""), jobs=2, quiet=True, report=False))
    return spec, outcome


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize("body, expected", [
    (BASE + "[sweep]\ncontact.speed = [0.01]\nspeeds = [5]\n", "sweep: speeds: unknown key"),
    (BASE + "[sweep]\ncontact.speed = []\n", "sweep.contact.speed = []: empty sweep"),
    (BASE + "[sweep]\ncontact.speed = [0.01, -0.005]\n",
     "sweep: contact.speed = -0.005: Input should be greater than 0 (valid range 0 < "
     "contact.speed <= 100 m/s)"),
    (BASE + "[[ramp]]\nname = \"A\"\n",
     "ramp[0].contact.speed: missing: a ramp needs its speeds"),
    (BASE + "[[ramp]]\nname = \"A\"\ncontact.speed = []\n", "a ramp without speeds"),
])
def test_bad_batch_spec_fails_before_anything_is_built(tmp_path, capsys, body, expected):
    spec = _spec(tmp_path, "bad", body)
    rc = batch_cli.main([str(spec), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert expected in err and err.startswith("ehlfoam batch: invalid batch spec"), err
    assert not (tmp_path / "bad").exists() and not (tmp_path / "runs").exists()


def test_bad_spec_exit_code_from_the_command(tmp_path):
    spec = _spec(tmp_path, "bad", BASE + "[sweep]\ncontact.speed = [0.01]\nload = [5]\n")
    proc = subprocess.run([*BATCH, str(spec)], capture_output=True, text=True, cwd=spec.parent)
    assert proc.returncode == 2 and "sweep: load: unknown key" in proc.stderr
    assert not (tmp_path / "bad").exists() and not (tmp_path / "runs").exists()


def test_report_option_takes_the_reporting_function():
    """The batch sits below the reports: it takes the function that makes its report."""
    with pytest.raises(TypeError, match="ehlfoam.report.after_batch"):
        BatchOptions(report=True)
    assert BatchOptions().report is None and BatchOptions(report=False).report is False


def test_parser_registration_and_dry_run(tmp_path, capsys):
    parser = argparse.ArgumentParser(prog="ehlfoam")
    batch_cli.add_parser(parser.add_subparsers(dest="command"))
    spec = _spec(tmp_path, "tiny", TINY)
    args = parser.parse_args(["batch", str(spec), "--jobs", "2", "--dry-run"])
    assert args.func is batch_cli.cmd_batch and args.jobs == 2
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "batch tiny: 6 cases" in out and RAMP[2] in out and "ramp A step 3 down" in out
    assert not (tmp_path / "tiny").exists()
    with pytest.raises(SystemExit):
        parser.parse_args(["batch", str(spec), "--jobs", "2", "--cores", "2"])


# ------------------------------------------------------------------ a local batch
@pytest.mark.openfoam
def test_batch_layout_and_results(tiny):
    spec, outcome = tiny
    batch = outcome.batch_dir
    assert outcome.exit_code == 1                       # one case failed
    assert outcome.counts == {"pending": 0, "running": 0, "finished": 5, "failed": 1,
                              "interrupted": 0}
    assert (batch / "batch.toml").read_text() == spec.read_text()
    plan = json.loads((batch / "plan.json").read_text())
    assert [p["id"] for p in plan] == ["u10.0_s3um_T40_F20_coarse", "u20.0_s3um_T40_F20_coarse",
                                       FAILING, *RAMP]
    assert plan[0]["params"] == {"contact.speed": 0.01, "contact.temperature": 40.0,
                                 "contact.load": 20.0, "supply.mode": "layers",
                                 "supply.disc_layer": 3e-6, "supply.ball_layer": 3e-6,
                                 "mesh.resolution": "coarse", "scene": "interface",
                                 "rung": "coarse"}
    assert plan[0]["ramp"] is None
    assert plan[5]["ramp"] == {"name": "A", "step": 3, "direction": "down", "previous": RAMP[1]}
    with open(batch / "results.csv", newline="") as fh:
        reader = csv.DictReader(fh)
        assert tuple(reader.fieldnames[:len(FIXED_COLUMNS)]) == FIXED_COLUMNS
        assert "oil_volume_m3" in reader.fieldnames and "time_steps" in reader.fieldnames
        # every metrics column is a key of the metrics record
        assert set(reader.fieldnames[len(FIXED_COLUMNS):]) <= set(MetricsRecord.model_fields)
        rows = {r["case_id"]: r for r in reader}
    assert list(rows) == [p["id"] for p in plan]
    ok = rows["u10.0_s3um_T40_F20_coarse"]
    assert ok["status"] == "finished" and ok["end_reason"] == "end_time"
    assert float(ok["contact.speed"]) == 0.01 and ok["supply.mode"] == "layers"
    m = read_metrics(batch / ok["case_dir"])
    assert m.schema_version == SCHEMA_VERSION and m.case_id == ok["case_id"]
    assert float(ok["oil_volume_m3"]) == m.oil_volume_m3 and not m.model_extra
    assert ok["state"] in ("I", "II") and float(ok["wall_s"]) > 0 and int(ok["cells"]) > 0
    assert (batch / ok["case_dir"] / "metrics.json").is_file() and (batch / ok["log"]).is_file()
    bad = rows[FAILING]
    assert bad["status"] == "failed" and "PrecalcFailed" in bad["reason"] and bad["state"] == ""
    assert (batch / bad["case_dir"] / "error.log").is_file()
    assert rows[RAMP[2]]["ramp"] == "A" and rows[RAMP[2]]["ramp_direction"] == "down"
    regime = json.loads((batch / "regime" / "regime.json").read_text())
    assert regime["ramps"][0]["name"] == "A"
    assert regime["ramps"][0]["up"]["contact.speed"] == [0.01, 0.02]


@pytest.mark.openfoam
def test_ramp_step_starts_from_the_previous_final_fields(tiny):
    batch = tiny[1].batch_dir / CASES
    down, up = batch / RAMP[2], batch / RAMP[1]
    info = json.loads((down / "ehlfoam" / "ramp.json").read_text())
    assert info["method"] == "copy" and info["previous"] == f"../{RAMP[1]}"
    last = time_folders(up)[-1][1]
    for name in ("alpha.oil", "U"):
        seeded = np.asarray(FoamFieldFile(down / "0.orig" / name).internal_field, float)
        final = np.asarray(FoamFieldFile(last / name).internal_field, float)
        assert np.array_equal(seeded, final), name
    m_down = json.loads((down / "metrics.json").read_text())
    m_up = json.loads((up / "metrics.json").read_text())
    fresh = json.loads((batch / "u10.0_s3um_T40_F20_coarse" / "metrics.json").read_text())
    # same cells, the gap differs by nanometres: the oil carried over to 0.1 %
    assert m_down["oil_volume_initial_m3"] == pytest.approx(m_up["oil_volume_m3"], rel=1e-3,
                                                            abs=0)
    assert m_down["oil_volume_initial_m3"] != pytest.approx(fresh["oil_volume_initial_m3"],
                                                            rel=1e-3, abs=0)
    assert m_down["ramp_start_method"] == "copy"
    # the first step starts fresh, like the sweep case at its speed: identical results
    first = json.loads((batch / RAMP[0] / "metrics.json").read_text())
    assert first["oil_volume_m3"] == fresh["oil_volume_m3"]


@pytest.mark.openfoam
def test_ramp_start_on_another_mesh_is_interpolated(tiny, tmp_path):
    previous = tiny[1].batch_dir / CASES / RAMP[1]
    case = tmp_path / "finer"
    write_case(make_case_spec({**SMALL, "mesh": {**SMALL["mesh"], "size_rim": 0.2}},
                              **{"contact.speed": 0.01}), case)
    info = seed_from_previous(case, previous)
    assert info["method"] == "interpolated" and info["fields"] == ["alpha.oil", "U", "p_rgh"]
    assert not (case / "0").exists()
    structure = case_fields.Structure.load(case)
    seeded = case_fields.initial_oil_volume(case, structure, load_geometry(case))
    final = json.loads((previous / "metrics.json").read_text())["oil_volume_m3"]
    # interpolated, then put back to the previous case's oil volume (ehlfoam.seed.mapping)
    assert info["oil"]["conserved"] and info["oil"]["interpolated_m3"] != pytest.approx(
        info["oil"]["source_m3"], rel=1e-6, abs=0)
    assert seeded == pytest.approx(final, rel=1e-6, abs=0)


@pytest.mark.openfoam
def test_ramp_starts_from_a_run_case(tiny, tmp_path, capsys):
    """``start_from``: the ramp's first step starts from a case that ran elsewhere (here a
    finished step of the tiny batch), not from the puddle; a folder that has not run is
    refused before anything is built."""
    source = tiny[1].batch_dir / CASES / RAMP[1]
    ramp = "[[ramp]]\nname = \"S\"\ncontact.speed = [0.015, 0.025]\nbranches = \"up\"\n"
    bad = _spec(tmp_path, "bad", BASE + ramp + f"start_from = \"{tmp_path}\"\n")
    assert batch_cli.main([str(bad), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "ramp 'S' start_from = " in err and "not a case folder with a written time" in err
    assert not (tmp_path / "bad").exists() and not (tmp_path / "runs").exists()
    spec = _spec(tmp_path, "from_run", BASE + ramp + f"start_from = \"{source}\"\n")
    outcome = run_batch(spec, BatchOptions(out=spec.with_suffix(""), jobs=1, quiet=True, report=False))
    assert outcome.exit_code == 0
    case = outcome.batch_dir / CASES / "rampS_up01_u15.0_s3um_T40_F20_coarse"
    info = json.loads((case / "ehlfoam" / "ramp.json").read_text())
    assert (case / info["previous"]).resolve() == source.resolve() and info["method"] == "copy"
    m = json.loads((case / "metrics.json").read_text())
    assert m["ramp_start_method"] == "copy"
    assert m["oil_volume_initial_m3"] == pytest.approx(
        json.loads((source / "metrics.json").read_text())["oil_volume_m3"], rel=1e-3, abs=0)


@pytest.mark.openfoam
def test_ramp_steps_with_mesh_follow_follow_the_meniscus_they_start_from(tiny, tmp_path):
    """With ``mesh.follow`` every ramp step's mesh has bands along the meniscus of what it
    starts from (start_from, then the step before), and its written spec keeps them."""
    source = tiny[1].batch_dir / CASES / RAMP[1]
    base = BASE.replace("wall_grading = 3.0 }",
                        "wall_grading = 3.0, follow = { half_width = 0.5 } }")
    assert base != BASE
    ramp = "[[ramp]]\nname = \"F\"\ncontact.speed = [0.015, 0.025]\nbranches = \"up\"\n"
    spec = _spec(tmp_path, "follow", base + ramp + f"start_from = \"{source}\"\n")
    outcome = run_batch(spec, BatchOptions(out=spec.with_suffix(""), jobs=1, quiet=True, report=False))
    assert outcome.exit_code == 0
    for step in ("rampF_up01_u15.0_s3um_T40_F20_coarse", "rampF_up02_u25.0_s3um_T40_F20_coarse"):
        case = outcome.batch_dir / CASES / step
        mesh = json.loads((case / "ehlfoam" / "spec.json").read_text())["mesh"]
        assert mesh["follow"] is None and mesh["refine"]
        assert {b["size"] for b in mesh["refine"]} == {0.24}
        info = json.loads((case / "ehlfoam" / "ramp.json").read_text())
        assert info["method"] == "interpolated"   # its own mesh, not the source's
        assert json.loads((case / "metrics.json").read_text())["status"] == "finished"


@pytest.mark.openfoam
def test_rerun_keeps_finished_and_failed_cases(tiny):
    spec, outcome = tiny
    before = _mtimes(outcome.batch_dir)
    again = run_batch(spec, BatchOptions(out=spec.with_suffix(""), jobs=2, quiet=True, report=False, regime=False))
    assert again.ran == [] and len(again.skipped) == 6 and again.exit_code == 1
    assert _mtimes(outcome.batch_dir) == before
    retry = run_batch(spec, BatchOptions(out=spec.with_suffix(""), jobs=2, quiet=True, report=False, regime=False,
                                         rerun_failed=True))
    assert retry.ran == [FAILING]
    after = _mtimes(outcome.batch_dir)
    assert after[FAILING] != before[FAILING]
    assert {k: v for k, v in after.items() if k != FAILING} == \
        {k: v for k, v in before.items() if k != FAILING}
    assert len(read_results(outcome.batch_dir)) == 6


def test_failed_ramp_step_leaves_the_later_steps_pending(tmp_path):
    """A ramp whose first step cannot be built (1 um/s: the precalc does not converge)."""
    spec = _spec(tmp_path, "ramp",
                 BASE + "[[ramp]]\nname = \"B\"\ncontact.speed = [1e-6, 0.01]\n")
    outcome = run_batch(spec, BatchOptions(out=spec.with_suffix(""), jobs=2, quiet=True, report=False))
    assert outcome.exit_code == 1 and outcome.ran == ["rampB_up01_u00.001_s3um_T40_F20_coarse"]
    rows = read_results(outcome.batch_dir)
    assert [r["status"] for r in rows] == ["failed", "pending", "pending"]
    assert rows[1]["reason"] == f"waits for ramp step {rows[0]['case_id']} (failed)"
    assert rows[2]["reason"] == f"waits for ramp step {rows[1]['case_id']} (not run)"
    assert not (outcome.batch_dir / CASES / rows[1]["case_id"]).exists()
    again = run_batch(spec, BatchOptions(out=spec.with_suffix(""), jobs=2, quiet=True, report=False, regime=False))
    assert again.ran == [] and [r["status"] for r in read_results(outcome.batch_dir)] == \
        ["failed", "pending", "pending"]


@pytest.mark.openfoam
def test_finished_case_with_another_spec_is_refused(tiny, tmp_path):
    spec, outcome = tiny
    changed = _spec(tmp_path, "tiny", spec.read_text().replace("end_time = 1e-3",
                                                               "end_time = 2e-3"))
    before = _mtimes(outcome.batch_dir)
    with pytest.raises(BatchError, match="finished with another case spec.*run.end_time"):
        run_batch(changed, BatchOptions(out=outcome.batch_dir, jobs=2, quiet=True))
    assert _mtimes(outcome.batch_dir) == before
    assert (outcome.batch_dir / "batch.toml").read_text() == spec.read_text()


# ------------------------------------------------------------------ the Dask path
@pytest.mark.slow
def test_dask_local_cluster_gives_the_same_results(tiny, tmp_path):
    from distributed import Client, LocalCluster

    spec, outcome = tiny
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=True,
                      resources={"CPU": 2}, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        dask = run_batch(spec, BatchOptions(out=tmp_path / "dask", client=client, quiet=True,
                                            report=False, regime=False))
    assert dask.counts == outcome.counts
    local = {r["case_id"]: r for r in read_results(outcome.batch_dir)}
    remote = {r["case_id"]: r for r in read_results(tmp_path / "dask")}
    assert list(local) == list(remote)
    for cid, a in local.items():
        b = remote[cid]
        assert (a["status"], a["state"], a["end_reason"]) == (b["status"], b["state"],
                                                               b["end_reason"]), cid
        if a["status"] == "finished":
            assert a["time_steps"] == b["time_steps"]
            assert float(b["oil_volume_m3"]) == pytest.approx(float(a["oil_volume_m3"]),
                                                              rel=1e-9, abs=0)


def test_slurm_cluster_is_configured_for_mpi_cases():
    opts = parse_slurm("cores=4,memory=8GB,walltime=00:30:00,queue=short,jobs=2")
    assert opts == {"cores": 4, "memory": "8GB", "walltime": "00:30:00", "queue": "short",
                    "jobs": 2}
    cluster = slurm_cluster(opts, scale=False)
    try:
        script = cluster.job_script()
    finally:
        cluster.close()
    for text in ("--cpus-per-task=4", "-p short", "-t 00:30:00", "--resources CPU=4"):
        assert text in script, script
    from ehlfoam.errors import SpecError

    with pytest.raises(SpecError, match="KEY=VALUE"):
        parse_slurm("nodes=3")


# ------------------------------------------------------------------ interrupt, kill, resume
KILL = BASE.replace("end_time = 1e-3, writes_per_transit = 1000",
                    "end_time = 2e-2, writes_per_transit = 100") + """
[sweep]
contact.speed = [0.01, 0.02]
supply = [{disc_layer = 2e-6, ball_layer = 2e-6}, {disc_layer = 3e-6, ball_layer = 3e-6},
          {disc_layer = 4e-6, ball_layer = 4e-6}]
"""


def _finished(batch: Path) -> set[str]:
    out = set()
    for p in batch.glob(f"{CASES}/*/metrics.json"):
        try:
            if json.loads(p.read_text())["status"] == "finished":
                out.add(p.parent.name)
        except (OSError, ValueError, KeyError):
            pass
    return out


def _children(pid: int) -> list[int]:
    out = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                if f"PPid:\t{pid}\n" in (d / "status").read_text():
                    out.append(int(d.name))
            except OSError:
                pass
    return out


def _inside(batch: Path) -> list[int]:
    """Processes working in the batch folder (solvers)."""
    out = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                if os.readlink(d / "cwd").startswith(str(batch)):
                    out.append(int(d.name))
            except OSError:
                pass
    return out


def _start_and_wait(spec: Path, batch: Path, n_finished: int) -> subprocess.Popen:
    proc = subprocess.Popen([*BATCH, str(spec), "--jobs", "2", "--quiet", "--no-report"],
                            cwd=spec.parent, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    deadline = time.monotonic() + 120
    while len(_finished(batch)) < n_finished:
        assert proc.poll() is None, proc.stdout.read()
        assert time.monotonic() < deadline, "no case finished in 120 s"
        time.sleep(0.1)
    return proc


def _gone(pids: list[int], batch: Path, timeout: float = 60.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if not any(Path(f"/proc/{p}").exists() for p in pids) and not _inside(batch):
            return True
        time.sleep(0.2)
    return False


@pytest.mark.openfoam
def test_interrupt_kill_and_resume(tmp_path):
    """Ctrl-C, then SIGKILL of the batch process, each after a case finished; the re-runs
    never recompute a finished case and results.csv keeps one row per case."""
    spec = _spec(tmp_path, "kill", KILL)
    batch = tmp_path / "runs" / "kill"
    # 1. SIGINT (Ctrl-C): the cases in flight stop gracefully, exit 130
    proc = _start_and_wait(spec, batch, 1)
    proc.send_signal(signal.SIGINT)
    out, _ = proc.communicate(timeout=200)
    assert proc.returncode == 130, out
    rows = read_results(batch)
    assert len(rows) == 6 and {r["status"] for r in rows} <= {"finished", "interrupted",
                                                             "pending"}
    # 2. SIGKILL after one more case: the workers and their solvers die with the batch
    done = {cid: (batch / CASES / cid / "metrics.json").read_bytes() for cid in _finished(batch)}
    stamps = _mtimes(batch)
    proc = _start_and_wait(spec, batch, len(done) + 1)
    workers = _children(proc.pid)
    proc.kill()
    proc.communicate()
    assert _gone(workers, batch), "workers or solvers survived the killed batch"
    for cid, text in done.items():
        assert (batch / CASES / cid / "metrics.json").read_bytes() == text
        assert _mtimes(batch)[cid] == stamps[cid]
    done = {cid: (batch / CASES / cid / "metrics.json").stat().st_mtime_ns
            for cid in _finished(batch)}
    # 3. re-run to the end
    rerun = subprocess.run([*BATCH, str(spec), "--jobs", "2", "--quiet", "--no-report"],
                           cwd=spec.parent, capture_output=True, text=True, timeout=300)
    assert rerun.returncode == 0, rerun.stdout + rerun.stderr
    assert f"{len(done)} kept" in rerun.stdout
    for cid, mtime in done.items():
        assert (batch / CASES / cid / "metrics.json").stat().st_mtime_ns == mtime
    rows = read_results(batch)
    assert sorted(r["case_id"] for r in rows) == sorted(json.loads(
        (batch / "plan.json").read_text())[k]["id"] for k in range(6))
    assert [r["status"] for r in rows] == ["finished"] * 6
    assert not list((batch / CASES).glob(".*"))        # no half-built case left behind
