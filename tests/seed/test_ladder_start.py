"""A 3D case started from the thin-film balance of its own point (``run.start =
"thin-film"``, the resolved rungs), by ``ehlfoam case`` and by a batch that sweeps the rung."""

from __future__ import annotations

import json
import subprocess

import pytest

from ehlfoam.batch.launch import BatchOptions, run_batch
from ehlfoam.batch.folder import CASES, STARTS
from ehlfoam.batch.results import read_results
from ehlfoam.metrics.record import read_metrics
from tests.case.test_writer import EHLFOAM
from tests.tiny import SMALL, as_toml

#: the tiny case with a thin-film start of 0.5 a cells (seconds)
STARTED = SMALL | {"thin_film": {"cell": 0.5, "steady_window": 3}}


@pytest.mark.openfoam
def test_a_resolved_rung_starts_from_the_thin_film_balance_of_its_point(tmp_path):
    """`ehlfoam case SPEC --rung resolved-coarse`: no --start-from needed; the thin-film
    balance is run first, the mesh's bands follow its meniscus, the case starts from its oil
    and keeps its record; no scratch folder is left beside the case."""
    spec = tmp_path / "small.toml"
    spec.write_text(as_toml({k: v for k, v in STARTED.items() if k != "mesh"}))
    out = tmp_path / "case"
    proc = subprocess.run([*EHLFOAM, "case", str(spec), "--out", str(out), "--rung",
                           "resolved-coarse"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "starts from" in proc.stdout and "thin-film" in proc.stdout
    start = out / "ehlfoam" / "thin-film-start"
    record = read_metrics(start / "metrics.json")
    assert record.status == "finished" and record.state in ("I", "II")
    assert (start / "state.npz").is_file()
    written = json.loads((out / "ehlfoam" / "spec.json").read_text())
    assert written["rung"] == "resolved-coarse" and written["mesh"]["follow"] is None
    assert written["mesh"]["refine"] and written["physics"]["wall_slip_length"] == 1e-6
    assert json.loads((out / "ehlfoam" / "ramp.json").read_text())["method"] == "thin-film"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case", "small.toml"]


@pytest.mark.openfoam
def test_a_batch_sweeps_the_rung_and_starts_its_3d_cases_from_the_thin_film(tmp_path):
    """One batch, two rungs of the same point: the thin-film case and the 3D coarse case
    started from its own thin-film balance (kept in starts/, reused on a resume)."""
    spec = tmp_path / "ladder.toml"
    base = {k: v for k, v in STARTED.items() if k not in ("name", "mesh")}
    base["run"] = {**base["run"], "start": "thin-film"}
    spec.write_text("[base]\n" + "\n".join(
        f"{k} = {json.dumps(v).replace(':', ' =')}" for k, v in base.items())
        + '\n[[sweep]]\nrung = ["thin-film-coarse", "coarse"]\n')
    outcome = run_batch(spec, BatchOptions(out=tmp_path / "ladder", jobs=1, quiet=True,
                                           report=False))
    assert outcome.exit_code == 0
    rows = {r["rung"]: r for r in read_results(outcome.batch_dir)}
    assert set(rows) == {"thin-film-coarse", "coarse"}
    assert rows["thin-film-coarse"]["case_id"].endswith("_tf-coarse")
    assert rows["thin-film-coarse"]["scene"] == "thin-film"
    three_d = rows["coarse"]
    assert three_d["scene"] == "interface" and three_d["status"] == "finished"
    assert (outcome.batch_dir / STARTS / three_d["case_id"] / "state.npz").is_file()
    case = outcome.batch_dir / CASES / three_d["case_id"]
    assert read_metrics(case).ramp_start_method == "thin-film"
    assert (case / "ehlfoam" / "thin-film-start" / "metrics.json").is_file()
    assert not (outcome.batch_dir / STARTS / rows["thin-film-coarse"]["case_id"]).exists()
