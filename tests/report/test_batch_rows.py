"""A batch report's rows: results.csv and plan.json in the case spec's names (SI), an older
batch folder's columns read as the current ones, and one display table for the inputs."""

from __future__ import annotations

import csv
import json

import pytest

from ehlfoam.batch.plan import PARAM_KEYS
from ehlfoam.report import units
from ehlfoam.report.batch_rows import read_results


def _write(folder, columns, rows, plan):
    folder.mkdir()
    with open(folder / "results.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=columns)
        w.writeheader()
        w.writerows(rows)
    (folder / "plan.json").write_text(json.dumps(plan))


def test_current_and_older_batch_folders_read_alike(tmp_path):
    now = {"case_id": "a", "contact.speed": "0.008", "contact.temperature": "40.0",
           "contact.load": "20.0", "supply.mode": "layers", "supply.disc_layer": "1.5e-06",
           "supply.ball_layer": "1.5e-06", "mesh.resolution": "coarse", "status": "finished",
           "state": "I", "oil_volume_m3": "7e-11"}
    old = {"case_id": "a", "speed_mm_s": "8.0", "temperature_C": "40.0", "load_N": "20.0",
           "supply": "layers", "disc_layer_um": "1.5", "ball_layer_um": "1.5",
           "resolution": "coarse", "status": "finished", "state": "I", "oil_volume_m3": "7e-11"}
    _write(tmp_path / "now", list(now), [now],
           [{"id": "a", "params": {}}, {"id": "b", "params": {"contact.speed": 0.012}}])
    _write(tmp_path / "old", list(old), [old],
           [{"id": "a", "params": {}}, {"id": "b", "params": {"speed_mm_s": 12.0}}])
    a_now, b_now = read_results(tmp_path / "now")
    a_old, b_old = read_results(tmp_path / "old")
    for key in PARAM_KEYS:
        expected = a_now.get(key)          # a batch from before "scene" was a column: None
        assert a_old.get(key) == (pytest.approx(expected) if isinstance(expected, float)
                                  else expected), key
    assert a_now["contact.speed"] == 0.008 and a_now["supply.mode"] == "layers"
    assert b_now["status"] == b_old["status"] == "pending"
    assert b_old["contact.speed"] == pytest.approx(b_now["contact.speed"]) == 0.012


def test_every_parameter_has_its_display_in_the_one_table():
    for key in PARAM_KEYS:
        assert key in units.SPEC, key
    assert units.short_label("contact.speed") == "u [mm/s]"
    assert units.scaled("contact.speed", 0.008) == pytest.approx(8.0)
    assert units.short_label("supply.disc_layer") == "disc layer [um]"
    assert units.short_label("oil_volume_m3") == "Oil volume (whole contact) [nl]"


def test_the_first_screen_says_what_and_how_far(tmp_path):
    """The batch report's summary: the spec's description, then a trust line per rung family
    of the batch (thin-film first), none for a rung it does not hold."""
    from ehlfoam.report.trust import TRUST, batch_description, trust_lines

    (tmp_path / "batch.toml").write_text('name = "m"\ndescription = "A map, 40 C"\n')
    assert batch_description(tmp_path) == "A map, 40 C"
    assert batch_description(tmp_path / "nowhere") == ""
    rows = [{"scene": "interface", "mesh.resolution": "coarse"},
            {"scene": "thin-film", "mesh.resolution": "medium"},
            {"mesh.resolution": "coarse"}]           # an older batch: no scene column
    lines = trust_lines(rows)
    assert len(lines) == 2
    assert TRUST["thin-film"] in lines[0] and TRUST["coarse"] in lines[1]
    assert trust_lines([{"scene": "interface", "mesh.resolution": "fine"}]) == [
        f"How far to trust it: {TRUST['fine']}"]


def test_a_live_batchs_staging_folders_are_not_cases(tmp_path):
    """A case folder being built or replaced lives under a dot name (``.ID.XXXX``,
    ``.ID.old.XXXX``) until it is renamed into place: a report of a running batch lists
    the real folder that has no row yet, and not the staging ones."""
    _write(tmp_path / "b", ["case_id", "status"], [{"case_id": "a", "status": "finished"}],
           [{"id": "a", "params": {}}])
    for name in ("a", "c", ".c.k2j9x", ".a.old.q1w2e"):
        (tmp_path / "b" / "cases" / name).mkdir(parents=True)
    assert [r["case_id"] for r in read_results(tmp_path / "b")] == ["a", "c"]
