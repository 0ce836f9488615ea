"""The example specs users start from: every one is valid (tests/batch/test_spec.py), every
case spec builds with a small precalc grid, and the short ones run, cut short: a coarse mesh
and a few hundredths of a transit, a stop of milliseconds (the run's own settings
otherwise). The cases of tens of thousands of cells (the film-resolving boxes, the levels
that follow the meniscus) are built only: a run of theirs takes minutes even cut short.
nominal_resolved.toml's mesh follows a start state's meniscus, so it is built from a
thin-film state the test makes first."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CASES = sorted((ROOT / "examples" / "cases").glob("*.toml"))
EHLFOAM = [sys.executable, "-m", "ehlfoam"]
#: the most cells a case may have for this test to run it
RUN_CELLS = 20_000
SHORT = ["--set", "mesh.resolution=coarse", "--set", "contact.grid=129",
         "--set", "contact.tol_residual=1e-4", "--set", "run.transits_max=0.02"]

pytestmark = pytest.mark.openfoam


def _ehlfoam(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([*EHLFOAM, *args], cwd=cwd, capture_output=True, text=True,
                          timeout=600)


@pytest.mark.parametrize("spec", CASES, ids=lambda p: p.name)
def test_every_example_case_builds_and_runs(spec: Path, tmp_path: Path) -> None:
    start: list[str] = []
    if "follow" in spec.read_text():          # its mesh follows a start state's meniscus
        made = _ehlfoam("thin-film", str(spec), "--out", "tf", "--set", "contact.grid=129",
                        "--set", "contact.tol_residual=1e-4", "--cell", "0.4",
                        "--transits", "0.5", "--quiet", cwd=tmp_path)
        assert made.returncode == 0, made.stderr
        start = ["--start-from", "tf/state.npz"]
    if "[stop]" in spec.read_text():          # the stop sets the end: a short one
        start += ["--set", "stop.at=0.002", "--set", "stop.duration=0.001",
                  "--set", "stop.after=0.001", "--set", "stop.frames_from=0"]
    case = _ehlfoam("case", str(spec), "--out", "case", *SHORT, *start, cwd=tmp_path)
    assert case.returncode == 0, case.stderr
    geometry = json.loads((tmp_path / "case" / "ehlfoam" / "geometry.json").read_text())
    if geometry["solver"] == "thin-film":       # the gap-averaged model: no OpenFOAM files
        assert (tmp_path / "case" / "ehlfoam" / "thin_film.json").is_file()
    else:
        assert (tmp_path / "case" / "constant" / "polyMesh" / "owner").is_file()
        assert (tmp_path / "case" / "system" / "controlDict").is_file()
    if geometry["cells"] > RUN_CELLS:
        return
    run = _ehlfoam("run", "case", "--quiet", cwd=tmp_path)
    assert run.returncode == 0, run.stdout + run.stderr
    metrics = json.loads((tmp_path / "case" / "metrics.json").read_text())
    assert metrics["status"] == "finished" and metrics["end_reason"] == "end_time"
    assert metrics["time_steps"] > 0 and metrics["state"] in ("I", "II")
