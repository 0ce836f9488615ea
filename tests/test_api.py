"""The public API (``ehlfoam.__all__``): examples/api.py runs (real OpenFOAM, seconds) and prints
what its metrics.json says; ``import ehlfoam`` loads nothing heavy and changes nothing; every
name resolves; the thin wrappers pass their arguments on."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import ehlfoam
from tests.tiny import SMALL

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.openfoam
def test_the_api_example_writes_runs_and_reads_a_case(tmp_path):
    proc = subprocess.run([sys.executable, str(ROOT / "examples" / "api.py"), str(tmp_path)],
                          capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    case = tmp_path / "nominal"
    m = json.loads((case / "metrics.json").read_text())
    geometry = json.loads((case / "ehlfoam" / "geometry.json").read_text())
    assert proc.stdout.splitlines() == [
        f"{case}: {geometry['cells']} cells, {m['status']}, state {m['state']}",
        f"inlet meniscus {m['inlet_meniscus_distance_over_a']:.2f} a upstream, "
        f"flooded width {m['flooded_width_over_a']:.2f} a"]
    # the overrides took: a coarse mesh, a twentieth of a transit, and a flooded region
    assert m["status"] == "finished" and m["end_reason"] == "end_time"
    assert m["simulated_time_s"] == pytest.approx(0.05 * m["transit_time_s"], rel=0.02)
    assert m["state"] == "I" and 0.0 < m["inlet_meniscus_distance_over_a"] < 20.0
    assert ehlfoam.read_metrics(case).to_json() == m


def test_import_ehlfoam_is_light_and_changes_nothing():
    code = ("import json, os, sys; before = dict(os.environ)\n"
            "import ehlfoam\n"
            "light = [m for m in ('numpy', 'scipy', 'pydantic', 'foamlib', 'pyvista') "
            "if m in sys.modules]\n"
            "same = dict(os.environ) == before\n"
            "names = {n: type(getattr(ehlfoam, n)).__name__ for n in ehlfoam.__all__}\n"
            "print(json.dumps([light, same, names]))\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, env={k: v for k, v in os.environ.items()
                                         if k != "OPENBLAS_NUM_THREADS"})
    assert proc.returncode == 0, proc.stderr
    light, same, names = json.loads(proc.stdout)
    assert light == [] and same
    assert names == {"SpecError": "type", "__version__": "str", "load_case_spec": "function",
                     "make_case_spec": "function", "precalc": "function",
                     "read_metrics": "function", "run_batch": "function",
                     "run_case": "function", "write_case": "function",
                     "write_report": "function"}
    assert re.fullmatch(r"\d+\.\d+\.\d+.*", ehlfoam.__version__)
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        ehlfoam.nothing


def test_write_report_stays_the_function_once_the_report_subpackage_is_imported():
    import ehlfoam.report

    assert callable(ehlfoam.write_report) and ehlfoam.write_report is ehlfoam.report.report


def test_precalc_returns_the_cached_solution_summary():
    spec = ehlfoam.make_case_spec(SMALL)
    summary = ehlfoam.precalc(spec)
    assert summary["converged"] and 0.0 < summary["hmin_m"] < summary["hc_m"] < 1e-6
    assert summary["a_m"] == pytest.approx(spec.a, rel=1e-9)
    assert json.loads((summary["folder"] / "summary.json").read_text())["hc_m"] == summary["hc_m"]
    assert ehlfoam.precalc(spec.contact) == summary       # a contact spec alike


def test_bad_input_through_the_api(tmp_path):
    with pytest.raises(ehlfoam.SpecError, match="contact.speed"):
        ehlfoam.make_case_spec(SMALL, **{"contact.speed": -1.0})
    with pytest.raises(FileNotFoundError, match="metrics.json: no such file"):
        ehlfoam.read_metrics(tmp_path)
    spec = tmp_path / "b.toml"
    spec.write_text("[base]\n[sweep]\ncontact.speed = [0.01]\nloads = [5]\n")
    with pytest.raises(ehlfoam.SpecError, match="sweep: loads: unknown key"):
        ehlfoam.run_batch(spec, out=tmp_path / "b", jobs=1, quiet=True)
    with pytest.raises(TypeError, match="nonsense"):
        ehlfoam.run_batch(spec, nonsense=1)
    assert not (tmp_path / "b").exists()


def test_the_readme_shows_the_example_that_runs():
    """The README's Python block is examples/api.py's code, so the example users read is the
    one this file's first test runs."""
    readme = (ROOT / "README.md").read_text()
    block = readme.split("```python\n", 1)[1].split("```", 1)[0]
    api = (ROOT / "examples" / "api.py").read_text()
    assert block.strip() and block.strip() in api


def test_write_case_and_run_batch_refuse_a_folder_before_any_work(tmp_path):
    """The API checks where it writes as the command line does (issue 73): a path OpenFOAM
    cannot take, a file in the way; nothing is written (the batch spec does not even exist:
    the folder is refused first)."""
    spec = ehlfoam.make_case_spec(SMALL)
    (tmp_path / "f").write_text("a file")
    for out, words in ((tmp_path / "a b", "OpenFOAM cannot take this path: it has a space"),
                       (tmp_path / "f", "is a file, not a folder")):
        with pytest.raises(ehlfoam.SpecError, match=words):
            ehlfoam.write_case(spec, out)
        with pytest.raises(ehlfoam.SpecError, match=words):
            ehlfoam.run_batch(tmp_path / "b.toml", out=out)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f"]
