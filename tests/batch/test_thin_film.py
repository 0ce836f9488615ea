"""A batch of thin-film cases (issue 74): `scene = "thin-film"` in the base, two cases swept
over the cavitation pressure, run with OpenFOAM out of reach (/bin/false): results.csv with
their states (a bubble enclosed at 90 kPa, the wake open at 99.5 kPa) and the regime
analysis; the batch report with a page and a top view per case (slow: a case report is a
few seconds)."""

from __future__ import annotations

import csv
import json

import pytest

from ehlfoam.batch.launch import BatchOptions, run_batch
from ehlfoam.report import after_batch

BATCH = """
name = "tf"
[base]
scene = "thin-film"
contact = { speed = 0.02, grid = 129, tol_residual = 1e-4 }
domain = { upstream = 5.0, downstream = 8.0, side = 5.0 }
supply = { mode = "layers", disc_layer = 3e-6, ball_layer = 3e-6, track_half_width = 2.5e-4, initial_puddle = 3.0 }
thin_film = { cell = 0.33, steady_window = 3 }
run = { transits_max = 30.0, writes_per_transit = 2 }
[sweep]
physics.cavitation_pressure = [9e4, 9.95e4]
"""


@pytest.fixture(scope="module")
def ran(tmp_path_factory):
    """The batch, run once for the module with OpenFOAM out of reach."""
    mp = pytest.MonkeyPatch()
    mp.setenv("EHLFOAM_FOAM", "prefix")
    mp.setenv("EHLFOAM_FOAM_PREFIX", "/bin/false")
    try:
        spec = tmp_path_factory.mktemp("batch") / "tf.toml"
        spec.write_text(BATCH)
        outcome = run_batch(spec, BatchOptions(out=spec.with_suffix(""), jobs=2, quiet=True))
    finally:
        mp.undo()
    with open(outcome.batch_dir / "results.csv", newline="") as fh:
        rows = {float(r["physics.cavitation_pressure"]): r for r in csv.DictReader(fh)}
    return outcome, rows


def test_a_thin_film_batch_runs_its_cases(ran):
    outcome, rows = ran
    assert outcome.exit_code == 0
    batch = outcome.batch_dir
    assert set(rows) == {9e4, 9.95e4}
    assert all(r["status"] == "finished" and r["log"].endswith("log.thin-film")
               for r in rows.values())
    assert rows[9e4]["state"] == "I" and rows[9e4]["bubble_enclosed"] == "true"
    assert float(rows[9e4]["bubble_length_over_a"]) > 0.5
    assert rows[9.95e4]["state"] == "II" and rows[9.95e4]["wake_open"] == "true"
    for r in rows.values():
        assert int(r["cells"]) == json.loads(
            (batch / r["case_dir"] / "ehlfoam" / "thin_film.json").read_text())["cells"]
        assert (batch / r["case_dir"] / "state.npz").is_file()
    regime = json.loads((batch / "regime" / "regime.json").read_text())
    assert regime


@pytest.mark.slow
def test_the_batch_report_shows_the_thin_film_cases(ran):
    outcome, rows = ran
    after_batch(outcome.batch_dir, lambda line: None)
    batch = outcome.batch_dir
    for r in rows.values():
        made = json.loads((batch / r["case_dir"] / "report" / "report.json").read_text())
        assert made["problems"] == [] and "top_view.png" in made["images"]
    html = (batch / "report" / "index.html").read_text()
    assert all(r["case_id"] in html for r in rows.values())


@pytest.mark.parametrize("sweep, words", [
    ("mesh.size_rim = [0.1]", 'mesh.size_rim = 0.1 does not apply to scene = "thin-film"'),
    ("thin_film.cell = [0.2, 10.0]", "thin_film.cell = 10 a is out of range"),
])
def test_a_thin_film_batch_with_a_3d_key_or_a_bad_cell_is_refused_before_anything_is_built(
        tmp_path, capsys, sweep, words):
    from ehlfoam.cli import batch as batch_cli

    spec = tmp_path / "bad.toml"
    spec.write_text(BATCH.split("[sweep]")[0] + "[sweep]\n" + sweep + "\n")
    assert batch_cli.main([str(spec), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    assert words in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_one_speed_ramp_is_one_case_started_from_a_thin_film_state(ran, tmp_path):
    """A ramp of one speed with a start_from is one case seeded from that state (how a map's
    points start from the thin-film state at the same point): it starts with the source's
    oil and comes to rest sooner than the same case from the puddle."""
    outcome, rows = ran
    source = outcome.batch_dir / rows[9e4]["case_dir"]
    spec = tmp_path / "seeded.toml"
    spec.write_text(BATCH.split("[sweep]")[0] + "physics = { cavitation_pressure = 9e4 }\n"
                    '[[ramp]]\nname = "P"\ncontact.speed = [0.02]\nbranches = "up"\n'
                    f'start_from = "{source / "state.npz"}"\n')
    seeded = run_batch(spec, BatchOptions(out=tmp_path / "seeded", jobs=1, quiet=True))
    assert seeded.exit_code == 0 and sum(seeded.counts.values()) == 1
    (case,) = (seeded.batch_dir / "cases").iterdir()
    m = json.loads((case / "metrics.json").read_text())
    src = json.loads((source / "metrics.json").read_text())
    assert m["oil_volume_initial_m3"] == pytest.approx(src["oil_volume_m3"], rel=1e-6)
    assert m["state"] == src["state"] == "I" and m["end_reason"] == "steady"
    assert m["time_steps"] < src["time_steps"]


RIG_RAMP = """
name = "rig"
[base]
scene = "thin-film"
contact = { speed = 0.02, grid = 129, tol_residual = 1e-4 }
domain = { upstream = 3.5, downstream = 5.5, side = 4.0 }
supply = { mode = "rig", disc_layer = 1e-6, ball_layer = 1e-6, track_half_width = 2.5e-4, initial_puddle = 2.5, track_radius = 1.3e-3 }
physics = { cavitation_pressure = 9e4 }
thin_film = { cell = 0.9, courant = 1.0, normal_length = 0.9 }
cycle = { passes_max = 6, tolerance = 1e-6, reflow_steps = 8, refine = 1, side = 6.0 }
[[ramp]]
name = "R"
contact.speed = [0.02, 0.03]
branches = "up-down"
"""


def test_a_ramp_of_cycles_carries_the_rig_s_oil_from_step_to_step(tmp_path):
    """A speed ramp of rig cases (issue 75): each step's cycle starts from the contact and the
    tracks the step before left, so the rig's oil at each step's start is the first step's
    to round-off; results.csv has the steps' states and films, regime.json the ramp."""
    mp = pytest.MonkeyPatch()
    mp.setenv("EHLFOAM_FOAM", "prefix")
    mp.setenv("EHLFOAM_FOAM_PREFIX", "/bin/false")
    try:
        spec = tmp_path / "rig.toml"
        spec.write_text(RIG_RAMP)
        outcome = run_batch(spec, BatchOptions(out=tmp_path / "rig", jobs=1, quiet=True))
    finally:
        mp.undo()
    assert outcome.exit_code == 0
    with open(outcome.batch_dir / "results.csv", newline="") as fh:
        rows = sorted(csv.DictReader(fh), key=lambda r: int(r["ramp_step"]))
    assert [r["ramp_direction"] for r in rows] == ["up", "up", "down"]
    oil = [float(r["oil_rig_initial_m3"]) for r in rows]
    assert oil[1:] == pytest.approx([oil[0]] * 2, rel=1e-12)
    for r in rows[1:]:
        ramp = json.loads((outcome.batch_dir / r["case_dir"] / "ehlfoam" / "ramp.json")
                          .read_text())
        assert ramp["fields"] == ["oil", "tracks"]
    assert all(r["state"] in ("I", "II") and 0.3 < float(r["hc_over_hc_flooded"]) <= 1.01
               for r in rows)
    regime = json.loads((outcome.batch_dir / "regime" / "regime.json").read_text())
    assert [rp["name"] for rp in regime["ramps"]] == ["R"]
