"""`ehlfoam thin-film`: a spec's region marched in the thin-film model, written as a state that
`ehlfoam case --start-from` takes; bad input refused with exit 2 before anything is written."""

from __future__ import annotations

import json

import pytest

from ehlfoam.cli.main import main
from tests.tiny import SMALL

#: the tiny case's spec as --set options
SMALL_SET = [item for table, values in SMALL.items() if isinstance(values, dict)
             for key, value in values.items()
             for item in ("--set", f"{table}.{key}={json.dumps(value)}")]


def test_thin_film_writes_a_state_a_case_starts_from(tmp_path, capsys):
    out = tmp_path / "tf"
    assert main(["thin-film", "--out", str(out), *SMALL_SET, "--cell", "0.5", "--transits",
                 "2", "--quiet"]) == 0
    printed = capsys.readouterr().out
    summary = json.loads((out / "summary.json").read_text())
    m = summary["metrics"]
    assert summary["transits"] == pytest.approx(2.0, rel=0.01)
    assert summary["set"]["contact.speed"] == SMALL["contact"]["speed"]
    assert summary["options"]["cell"] == 0.5 and not summary["balance"]
    assert m["state"] in ("I", "II") and m["oil_volume_m3"] > 0
    assert f"{m['flooded_width_over_a']:.2f} a" in printed          # the metrics, printed
    assert "2.0 transits on 0.5 a cells" in printed

    case = tmp_path / "case"
    assert main(["case", "--out", str(case), *SMALL_SET, "--start-from",
                 str(out / "state.npz")]) == 0
    info = json.loads((case / "ehlfoam" / "ramp.json").read_text())
    assert info["method"] == "thin-film" and info["fields"] == ["alpha.oil"]


@pytest.mark.parametrize("args, words", [
    (["--cell", "5"], "cell = 5.0 a is out of range: must be in (0, 3.75] a"),
    (["--transits", "-1"], "argument --transits: -1.0 is out of range: must be in (0, 10000]"),
    (["--window", "0"], "argument --window: 0 is out of range: must be in [1, 1000]"),
    (["--set", "contact.speed=-1"], "contact.speed = -1"),
    (["--set", "contact.speed"], "--set 'contact.speed': expected KEY=VALUE"),
    (["--advancing", "10"], "advancing_angle = 10.0 is out of range: must be None or in [15, 90)"),
    (["--receding", "sticky"], "'sticky': must be 'static', 'bretherton' or a factor"),
    (["--start", "missing.npz"], "--start missing.npz: not a thin-film state"),
])
def test_bad_input_is_refused_by_name_value_and_range(tmp_path, capsys, args, words):
    out = tmp_path / "tf"
    assert main(["thin-film", "--out", str(out), *args, "--quiet"]) == 2
    assert words in capsys.readouterr().err
    assert not out.exists()


def test_balance_marches_until_the_outflow_meets_the_supply(tmp_path, capsys):
    """--balance without --transits: up to 200 transits, stopping at the balance."""
    out = tmp_path / "tf"
    assert main(["thin-film", "--out", str(out), *SMALL_SET, "--cell", "0.5", "--balance",
                 "--tolerance", "0.05", "--window", "3", "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["balance"] and summary["transits_max"] == 200.0
    assert summary["metrics"]["steady"] and summary["transits"] < 200
    assert summary["metrics"]["outflow_over_supply"] == pytest.approx(1.0, abs=0.1)
    assert ", balanced (outflow / supply" in capsys.readouterr().out
