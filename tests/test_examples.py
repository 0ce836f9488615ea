"""The example specs users start from: every one is valid (tests/batch/test_spec.py), and every
case spec builds and runs, cut short: a coarse mesh, a small precalc grid and a few hundredths
of a transit (the run's own settings otherwise). nominal_resolved.toml's mesh follows a start
state's meniscus, so it runs from a thin-film state the test makes first."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CASES = sorted((ROOT / "examples" / "cases").glob("*.toml"))
EHLFOAM = [sys.executable, "-m", "ehlfoam"]
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
    case = _ehlfoam("case", str(spec), "--out", "case", *SHORT, *start, cwd=tmp_path)
    assert case.returncode == 0, case.stderr
    run = _ehlfoam("run", "case", "--quiet", cwd=tmp_path)
    assert run.returncode == 0, run.stdout + run.stderr
    metrics = json.loads((tmp_path / "case" / "metrics.json").read_text())
    assert metrics["status"] == "finished" and metrics["end_reason"] == "end_time"
    assert metrics["time_steps"] > 0 and metrics["state"] in ("I", "II")
