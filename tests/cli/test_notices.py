"""Warnings on the command line: one line each with its code and docs pointer; a batch shows
each code once (the first case that raised it) and counts the cases at the end. The tiny case
of tests/tiny.py raises two (its rear meniscus and its front sit in coarse cells)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from ehlfoam.notices import from_text
from tests.tiny import SMALL

pytestmark = pytest.mark.openfoam   # every test here runs OpenFOAM

EHLFOAM = [str(Path(sys.executable).parent / "ehlfoam")]


def _toml(table: dict, prefix: str = "") -> str:
    """A flat TOML text of ``table`` (tables of scalars), keys under ``prefix``."""
    lines = [f"[{prefix}{k}]\n" + "".join(f"{kk} = {json.dumps(vv)}\n" for kk, vv in v.items())
             for k, v in table.items() if isinstance(v, dict)]
    return "".join(lines)


@pytest.fixture(scope="module")
def batch(tmp_path_factory):
    """Two cases of the tiny case (10 and 20 mm/s) run as a batch, its log."""
    root = tmp_path_factory.mktemp("notices")
    spec = root / "two.toml"
    spec.write_text(_toml(SMALL, "base.") + "[sweep]\ncontact.speed = [0.01, 0.02]\n")
    proc = subprocess.run([*EHLFOAM, "batch", str(spec), "--out", str(root / "two"), "--quiet",
                           "--no-report", "--jobs", "2"], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return root / "two", proc.stdout


def test_a_batch_shows_each_notice_once_and_counts_the_cases(batch):
    folder, log = batch
    cases = sorted(p.parent for p in folder.glob("cases/*/metrics.json"))
    raised = [from_text(json.loads((c / "metrics.json").read_text())["warnings"]) for c in cases]
    codes = [n.code for n in raised[0]]
    assert len(cases) == 2 and codes and [n.code for n in raised[1]] == codes, raised
    lines = log.splitlines()
    for code in codes:
        shown = [ln for ln in lines if f"[{code}]" in ln and " warning  " in ln]
        assert len(shown) == 1, log                   # once, not per case
        assert any(str(n) in shown[0] for r in raised for n in r), shown
    [summary] = [ln for ln in lines if " warnings [" in ln]
    assert all(f"[{code}] 2 cases" in summary for code in codes), summary
    assert max(len(ln) for ln in lines) < 400, log    # no paragraphs


def test_case_and_run_print_their_notices_one_line_each(tmp_path):
    spec = tmp_path / "small.toml"
    spec.write_text(f"name = {json.dumps(SMALL['name'])}\n" + _toml(SMALL))
    made = subprocess.run([*EHLFOAM, "case", str(spec), "--out", str(tmp_path / "c"),
                           "--set", "mesh.n_layers=12", "--set", "mesh.wall_grading=40",
                           "--set", "run.end_time=1e-4"], capture_output=True, text=True)
    assert made.returncode == 0, made.stderr
    [line] = made.stderr.splitlines()
    assert line.startswith("ehlfoam case: warning [ball-wall-steps] the ball's wall cells "), line
    ran = subprocess.run([*EHLFOAM, "run", str(tmp_path / "c"), "--quiet"],
                         capture_output=True, text=True, timeout=300)
    assert ran.returncode == 0, ran.stderr
    metrics = json.loads((tmp_path / "c" / "metrics.json").read_text())
    notices = from_text(metrics["warnings"])
    assert [n.code for n in notices][:1] == ["ball-wall-steps"] and len(notices) > 1
    assert ran.stderr.splitlines() == [f"ehlfoam run: warning {n}" for n in notices]
