"""A thin-film case end to end (ehlfoam.run.thin_film, issue 74): `ehlfoam case` writes a
folder without OpenFOAM files, `ehlfoam run` marches it to rest with the 3D runs'
steady-state test and writes metrics.json (the 3D runs' keys, an exact oil balance),
history.csv (the 3D runs' columns), state.npz and its log, `ehlfoam report` draws it; it goes
on from its state, stops at its wall limit, ends `interrupted` on SIGTERM with its state
written, refuses a second run while one holds it, and starts from another thin-film case.
OpenFOAM is never called: the runtime is /bin/false throughout."""

from __future__ import annotations

import csv
import fcntl
import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from ehlfoam.cli.main import main
from ehlfoam.cli.run import KEYS
from ehlfoam.run.fields import Sample
from ehlfoam.run.thin_film import advance, sigterm_interrupts
from ehlfoam.thinfilm.state import load_state
from tests.tiny import THIN_FILM

#: the tiny thin-film case as `ehlfoam case --set` options
SET = [item for table, values in THIN_FILM.items() if isinstance(values, dict)
       for key, value in values.items()
       for item in ("--set", f"{table}.{key}={json.dumps(value)}")] + [
    "--set", f"scene={json.dumps(THIN_FILM['scene'])}", "--set", "name=tf"]

NO_FOAM = {"EHLFOAM_FOAM": "prefix", "EHLFOAM_FOAM_PREFIX": "/bin/false"}


@pytest.fixture(autouse=True)
def no_openfoam(monkeypatch):
    """Any call of OpenFOAM would run /bin/false and fail."""
    for key, value in NO_FOAM.items():
        monkeypatch.setenv(key, value)


@pytest.fixture(scope="module")
def ran(tmp_path_factory) -> Path:
    """The tiny thin-film case, written and run (once for the module)."""
    case = tmp_path_factory.mktemp("tf") / "case"
    env = {**os.environ, **NO_FOAM}
    old = {k: os.environ.get(k) for k in NO_FOAM}
    os.environ.update(env)
    try:
        assert main(["case", "--out", str(case), *SET]) == 0
        assert main(["run", str(case), "--quiet"]) == 0
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    return case


def copy_of(ran: Path, tmp_path: Path, run: bool = False) -> Path:
    """A fresh copy of the written case (without its run's outputs unless ``run``)."""
    case = tmp_path / "copy"
    shutil.copytree(ran, case)
    if not run:
        for name in ("metrics.json", "history.csv", "state.npz", "log.thin-film"):
            (case / name).unlink(missing_ok=True)
    return case


def metrics(case: Path) -> dict:
    return json.loads((case / "metrics.json").read_text())


def sigterm_run(case: Path, written: str, going_on: Callable[[], bool]) -> int:
    """`ehlfoam run case` in its own process, sent SIGTERM while it runs; its exit code. A
    tiny run ends within a second, so the signal is not timed: once ``case/written`` exists
    the run is stopped (SIGSTOP), ``going_on()`` must say from what it has written that it
    is still within the loop that takes SIGTERM, and it is sent SIGTERM and let go on."""
    proc = subprocess.Popen([sys.executable, "-m", "ehlfoam", "run", str(case), "--quiet"],
                            env={**os.environ, **NO_FOAM}, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60
        while not (case / written).exists() and time.monotonic() < deadline:
            time.sleep(0.01)
        proc.send_signal(signal.SIGSTOP)
        assert going_on(), f"the run of {case} had ended: nothing left to interrupt"
        proc.send_signal(signal.SIGTERM)
        proc.send_signal(signal.SIGCONT)
        return proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_a_thin_film_case_is_a_folder_without_openfoam_files(ran):
    names = {p.name for p in ran.iterdir()}
    assert {"ehlfoam", "precalc", "metrics.json", "history.csv", "state.npz",
            "log.thin-film"} <= names
    assert not names & {"system", "constant", "0.orig", "0", "Allrun", "Allclean"}
    meta = {p.name for p in (ran / "ehlfoam").iterdir()}
    assert {"spec.json", "geometry.json", "thin_film.json"} <= meta
    grid = json.loads((ran / "ehlfoam" / "thin_film.json").read_text())
    geom = json.loads((ran / "ehlfoam" / "geometry.json").read_text())
    assert grid["cell_over_a"] == 0.33 and geom["solver"] == "thin-film"
    assert geom["cells"] == grid["cells"] < grid["nx"] * grid["ny"]   # the island's are out


def test_the_run_comes_to_rest_with_the_3d_runs_keys_and_an_exact_oil_balance(ran):
    """State I with a bubble behind the contact that the region encloses (gas below 90 kPa),
    steady by the 3D runs' test, the oil kept to round-off."""
    m = metrics(ran)
    # "reason" is written only for a run that failed (as the 3D runs' records)
    for key in tuple(k for k in KEYS if k != "reason") + (
            "steady", "transit_time_s", "inlet_meniscus_at_rim", "wake_open",
            "oil_volume_m3", "oil_volume_initial_m3", "oil_inflow_m3_s",
            "oil_outflow_m3_s", "oil_carried_in_m3", "oil_carried_out_m3",
            "cells", "a_m", "steady_test", "bubble_volume_m3"):
        assert key in m, key
    assert (m["status"], m["end_reason"], m["steady"]) == ("finished", "steady", True)
    assert m["state"] == "I" and m["bubble_enclosed"] and m["bubble_length_over_a"] > 0.5
    assert m["inlet_meniscus_distance_over_a"] > 1.0 and m["flooded_width_over_a"] > 4.0
    assert m["min_pressure_Pa"] == pytest.approx(9e4)          # the bubble's gas
    assert m["oil_mass_balance_error"] < 1e-12
    assert m["oil_outflow_m3_s"] == pytest.approx(m["oil_inflow_m3_s"], rel=0.02)
    grid = json.loads((ran / "ehlfoam" / "thin_film.json").read_text())
    assert m["cells"] == grid["cells"]
    assert m["time_steps"] == pytest.approx(m["simulated_time_s"] / grid["time_step_s"],
                                            abs=1)
    assert 0 < m["wall_s"] < 60
    assert m["simulated_time_s"] < 30 * m["transit_time_s"]        # before its time limit


def test_history_has_the_3d_runs_columns_and_the_state_reads_back(ran):
    with open(ran / "history.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    columns = list(Sample(0.0, 0.0, 0.0, 0.0, {}, oil_out_by_boundary={
        "outlet": 0.0, "side": 0.0}).row())
    assert list(rows[0]) == columns
    times = [float(r["time_s"]) for r in rows]
    assert times == sorted(times) and len(rows) >= 2 * 5        # 2 writes a transit, 5+
    m = metrics(ran)
    assert times[-1] == pytest.approx(m["simulated_time_s"])
    sol = load_state(ran / "state.npz")
    assert sol.time == pytest.approx(m["simulated_time_s"])
    assert sol.cavity is not None and sol.cavity.any()
    assert 2 * float(sol.content.sum()) * sol.grid.cell ** 2 == pytest.approx(
        m["oil_volume_m3"], rel=1e-9)
    assert "end: steady" in (ran / "log.thin-film").read_text()


def test_the_report_draws_the_top_view_and_the_pressure_map(ran, tmp_path):
    case = copy_of(ran, tmp_path, run=True)
    assert main(["report", str(case), "--no-gif"]) == 0
    made = json.loads((case / "report" / "report.json").read_text())
    assert made["problems"] == [] and made["state"] == "I"
    assert {"top_view.png", "pressure.png", "ehl_precalc.png", "history.png"} <= \
        set(made["images"])
    assert "side_view.png" not in made["images"]                     # gap-averaged
    html = (case / "report" / "index.html").read_text()
    assert "thin-film model" in html


def test_a_run_goes_on_from_its_state(ran, tmp_path, capsys):
    """--extend 1: one transit more from where it stopped, the history kept and continued."""
    case = copy_of(ran, tmp_path, run=True)
    before = metrics(case)
    rows = len((case / "history.csv").read_text().splitlines())
    assert main(["run", str(case), "--extend", "1", "--quiet"]) == 0
    after = metrics(case)
    assert after["end_reason"] == "end_time"
    assert after["simulated_time_s"] == pytest.approx(
        before["simulated_time_s"] + before["transit_time_s"], rel=1e-3)
    assert len((case / "history.csv").read_text().splitlines()) >= rows + 2   # 2 a transit
    assert after["oil_mass_balance_window_s"][0] == pytest.approx(before["simulated_time_s"])
    assert after["oil_volume_initial_m3"] == before["oil_volume_initial_m3"]
    assert after["oil_mass_balance_error"] < 1e-12
    assert list(case.glob("log.thin-film.*"))                         # the first log kept


def test_a_wall_limit_ends_the_run_with_its_state(ran, tmp_path):
    case = copy_of(ran, tmp_path)
    spec = json.loads((case / "ehlfoam" / "spec.json").read_text())
    spec["run"]["steady_tolerance"] = 1e-9        # never steady: only the wall limit ends it
    (case / "ehlfoam" / "spec.json").write_text(json.dumps(spec))
    assert main(["run", str(case), "--wall-limit", "0.3", "--quiet"]) == 0
    m = metrics(case)
    assert (m["status"], m["end_reason"]) == ("finished", "wall_limit")
    assert load_state(case / "state.npz").time == pytest.approx(m["simulated_time_s"])


def test_a_case_another_process_runs_is_refused(ran, tmp_path, capsys):
    case = copy_of(ran, tmp_path)
    with open(case / "ehlfoam" / "run.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        assert main(["run", str(case), "--quiet"]) == 2
    assert "is being run by another process" in capsys.readouterr().err
    assert not (case / "metrics.json").exists()


def test_sigterm_ends_the_run_interrupted_with_its_state_written(ran, tmp_path):
    case = copy_of(ran, tmp_path)
    spec = json.loads((case / "ehlfoam" / "spec.json").read_text())
    spec["run"]["steady_tolerance"] = 1e-9                   # never steady: it runs on
    (case / "ehlfoam" / "spec.json").write_text(json.dumps(spec))
    transit = json.loads((case / "ehlfoam" / "geometry.json").read_text())["transit_time"]

    def marching() -> bool:        # short of its transits_max: it marches on
        with open(case / "history.csv", newline="") as fh:
            last = float(list(csv.DictReader(fh))[-1]["time_s"])
        return last < (spec["run"]["transits_max"] - 1) * transit

    assert sigterm_run(case, "history.csv", marching) == 1   # not finished: metrics.json says why
    m = metrics(case)
    assert (m["status"], m["end_reason"]) == ("interrupted", "interrupted")
    assert load_state(case / "state.npz").time == pytest.approx(m["simulated_time_s"])


class _SignallingMarch:
    """A march whose second step sends this process ``sig`` halfway through."""

    c = np.zeros(3)

    def __init__(self, sig: int):
        self.sig, self.started, self.done = sig, 0, 0

    def step(self) -> None:
        self.started += 1
        if self.started == 2:
            os.kill(os.getpid(), self.sig)
        sum(range(1000))                 # bytecodes on which a raising handler would run
        self.done += 1


main_thread_only = pytest.mark.skipif(threading.current_thread() is not threading.main_thread(),
                                      reason="signal handlers are set in the main thread")


@main_thread_only
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_a_signal_interrupts_the_march_after_the_step_it_came_in(sig):
    before = signal.getsignal(sig)
    m = _SignallingMarch(sig)
    with pytest.raises(KeyboardInterrupt):
        with sigterm_interrupts():
            advance(m, 5)
    assert (m.started, m.done) == (2, 2)        # the step it came in was done whole
    assert signal.getsignal(sig) is before


@main_thread_only
def test_a_signal_after_the_last_step_interrupts_at_the_blocks_end():
    m = _SignallingMarch(signal.SIGTERM)
    with pytest.raises(KeyboardInterrupt):
        with sigterm_interrupts():
            advance(m, 1)
            m.started = 1
            m.step()                            # not through advance: nothing checks
            assert m.done == 2
    with sigterm_interrupts():                  # the next block starts with none caught
        advance(m, 1)


def test_a_thin_film_case_starts_from_another_ones_state_and_not_from_a_3d_case(ran, tmp_path,
                                                                              capsys):
    started = tmp_path / "started"
    assert main(["case", "--out", str(started), *SET, "--start-from", str(ran)]) == 0
    info = json.loads((started / "ehlfoam" / "ramp.json").read_text())
    assert info["method"] == "thin-film state" and info["gap_difference"] < 1e-9
    assert (started / "ehlfoam" / "start.npz").is_file()
    assert main(["run", str(started), "--quiet"]) == 0
    assert metrics(started)["simulated_time_s"] < metrics(ran)["simulated_time_s"]
    capsys.readouterr()
    not_a_state = tmp_path / "3d"
    (not_a_state / "0.001").mkdir(parents=True)                # a 3D case's time folder
    out = tmp_path / "refused"
    assert main(["case", "--out", str(out), *SET, "--start-from", str(not_a_state)]) == 2
    err = capsys.readouterr().err
    assert "is not a thin-film state" in err and "Traceback" not in err
    assert not out.exists()


def test_a_killed_run_is_said_and_only_a_case_not_being_run_is_overwritten(ran, tmp_path,
                                                                         capsys):
    """Issue 73's guards hold for the scene: a metrics.json left `running` by a killed run is
    said and the run goes on from its state; the case carries ehlfoam/case.json, so
    --overwrite replaces it, but not while its run lock is held."""
    case = copy_of(ran, tmp_path, run=True)
    m = metrics(case)
    (case / "metrics.json").write_text(json.dumps({**m, "status": "running"}))
    capsys.readouterr()
    assert main(["run", str(case), "--extend", "0.5", "--quiet"]) == 0
    err = capsys.readouterr().err
    assert "was killed before it ended" in err and "monitor_killed" in err
    assert metrics(case)["status"] == "finished"
    assert metrics(case)["oil_volume_initial_m3"] == m["oil_volume_initial_m3"]
    assert (case / "ehlfoam" / "case.json").is_file()
    with open(case / "ehlfoam" / "run.lock", "a") as lock:        # a run holds it
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        assert main(["case", "--out", str(case), *SET, "--overwrite"]) == 2
    assert "run lock" in capsys.readouterr().err
    assert (case / "state.npz").is_file()                          # left as it was
    assert main(["case", "--out", str(case), *SET, "--overwrite"]) == 0
    assert not (case / "state.npz").exists() and (case / "ehlfoam" / "case.json").is_file()


def test_an_extension_beyond_max_steps_is_refused_before_anything_is_written(ran, tmp_path,
                                                                           capsys):
    case = copy_of(ran, tmp_path, run=True)
    before = (case / "metrics.json").read_text()
    assert main(["run", str(case), "--extend", "1e6", "--quiet"]) == 2
    assert "more than run.max_steps" in capsys.readouterr().err
    assert (case / "metrics.json").read_text() == before


def test_a_run_with_the_gas_balance_writes_its_closing_budget(ran, tmp_path):
    """`thin_film.bubble_gas = "balance"`: the run writes gas.json, its budget (whole
    contact) closing to round-off of the air held, its constants those of the spec; the oil
    balance is exact as ever; without the balance no gas.json."""
    assert not (ran / "gas.json").exists()
    case = tmp_path / "gas"
    assert main(["case", "--out", str(case), *SET, "--set",
                 'thin_film.bubble_gas="balance"', "--set", "run.transits_max=8"]) == 0
    assert main(["run", str(case), "--quiet"]) == 0
    gas = json.loads((case / "gas.json").read_text())
    b = gas["budget_mol"]
    released = b["released_by_diffusion_mol"] + b["released_at_release_pressure_mol"]
    assert released > 0
    assert abs(gas["residual_mol"]) <= 1e-9 * released
    assert gas["constants"]["release_pressure_Pa"] == 9e4
    assert gas["constants"]["solubility_ostwald"] == 0.09
    assert len(gas["per_transit"]["held_mol"]) == len(gas["per_transit"]["time_s"]) >= 1
    metrics = json.loads((case / "metrics.json").read_text())
    assert metrics["oil_mass_balance_error"] < 1e-9
