"""The metrics record: its keys, units and displays, old files, the published schema."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ehlfoam.metrics import convergence
from ehlfoam.metrics.pattern import Geometry, flow_pattern
from ehlfoam.metrics.record import (LEGACY_KEYS, SCHEMA_PATH, SCHEMA_VERSION, MetricsRecord,
                                    display_of, read_metrics, schema_text, write_metrics)
from ehlfoam.run.fields import Sample

ROOT = Path(__file__).resolve().parents[2]


def test_published_schema_is_current():
    """docs/metrics.schema.json is what the record gives; rewrite it with
    ``python -m ehlfoam.metrics.record --write``."""
    assert SCHEMA_PATH == ROOT / "docs" / "metrics.schema.json"
    assert SCHEMA_PATH.read_text() == schema_text(), \
        "docs/metrics.schema.json is stale: python -m ehlfoam.metrics.record --write"
    schema = json.loads(SCHEMA_PATH.read_text())
    assert schema["properties"]["oil_volume_m3"]["unit"] == "m3"
    assert schema["properties"]["oil_volume_m3"]["display"] == {
        "label": "Oil volume (whole contact)", "unit": "nl", "scale": 1e12}


def test_schema_command_prints_and_writes(tmp_path):
    out = tmp_path / "schema.json"
    subprocess.run([sys.executable, "-m", "ehlfoam.metrics.record", "--write", str(out)],
                   check=True, capture_output=True)
    printed = subprocess.run([sys.executable, "-m", "ehlfoam.metrics.record"], check=True,
                             capture_output=True, text=True).stdout
    assert out.read_text() == printed == schema_text()


def test_every_key_has_a_description_a_unit_and_a_display():
    for name, field in MetricsRecord.model_fields.items():
        extra = field.json_schema_extra
        assert field.description, name
        assert set(extra) == {"unit", "display"}, name
        assert set(extra["display"]) == {"label", "unit", "scale"}, name
        label, unit, scale = display_of(name)
        assert label and (scale is None or scale > 0), name
        if name.endswith("_over_a"):
            assert extra["unit"] == "a" and unit == "a", name
        for suffix, si in (("_m3", "m3"), ("_m3_s", "m3/s"), ("_kg", "kg"), ("_Pa", "Pa")):
            if name.endswith(suffix):
                assert extra["unit"] == si, name
    assert display_of("not_a_key") == ("not_a_key", "", None)


def test_the_flow_pattern_and_the_history_speak_the_record():
    """Every key the flow-pattern metrics, a history row and the convergence readings use is
    a record key."""
    geom = Geometry(a=1e-4, island_radius=1.5e-4, x_min=-1e-3, x_max=1.2e-3, y_max=8e-4,
                    symmetric=False)
    x, y = np.meshgrid(np.linspace(-1e-3, 1.2e-3, 60), np.linspace(-8e-4, 8e-4, 40))
    alpha = (np.hypot(x, y) < 5e-4).astype(float)
    pattern = flow_pattern(x.ravel(), y.ravel(), alpha.ravel(), geom)
    assert set(pattern) <= set(MetricsRecord.model_fields)
    row = Sample(time=1e-3, oil_volume=1e-12, oil_in=0.0, oil_out=0.0, pattern=pattern).row()
    history_only = {"time_s", "oil_volume_m3", "oil_in_m3_s", "oil_out_m3_s"}
    assert set(row) - history_only <= set(MetricsRecord.model_fields)
    record = MetricsRecord.model_validate(pattern)
    assert record.state == pattern["state"] and not record.model_extra
    assert set(convergence.METRICS) <= set(MetricsRecord.model_fields)


def test_written_record_keeps_only_its_keys(tmp_path):
    record = MetricsRecord(status="running", cells=1200)
    write_metrics(tmp_path, record)
    data = json.loads((tmp_path / "metrics.json").read_text())
    assert data == {"schema_version": SCHEMA_VERSION, "status": "running", "cells": 1200}
    done = read_metrics(tmp_path).updated(status="finished", last_delta_t_s=math.nan,
                                          log_tail=None)
    assert done.status == "finished" and done.cells == 1200 and "log_tail" in done
    write_metrics(tmp_path, done)
    data = json.loads((tmp_path / "metrics.json").read_text())
    assert data["last_delta_t_s"] is None and data["log_tail"] is None   # JSON has no NaN
    assert list(data)[:3] == ["schema_version", "status", "cells"]


def test_mapping_view():
    record = MetricsRecord(status="finished", oil_volume_m3=2e-12, log_tail=None)
    assert record["oil_volume_m3"] == 2e-12 and record.get("oil_volume_m3") == 2e-12
    assert record["log_tail"] is None and record.get("log_tail", []) == []
    assert record.get("wall_s") is None and "wall_s" not in record
    with pytest.raises(KeyError):
        record["wall_s"]


def test_an_older_file_is_read_with_the_current_keys(tmp_path):
    """A metrics.json written before the record (no schema_version): speed_m_s, which
    repeated the case spec's contact.speed, is dropped; a key this version does not know is
    kept as it is; the values are the file's."""
    old = {"status": "finished", "end_reason": "end_time", "state": "I", "speed_m_s": 0.008,
           "oil_volume_m3": 7.5e-11, "cells": 4242, "time_steps": 17, "an_old_key": 3}
    (tmp_path / "metrics.json").write_text(json.dumps(old))
    record = read_metrics(tmp_path)
    assert LEGACY_KEYS == {"speed_m_s": None}
    assert record.schema_version == SCHEMA_VERSION
    assert "speed_m_s" not in record.to_json()
    assert record.oil_volume_m3 == 7.5e-11 and record.cells == 4242 and record.state == "I"
    assert record.get("an_old_key") == 3
    assert read_metrics(tmp_path / "metrics.json") == record


@pytest.mark.parametrize("text, message", [
    ('{"status": "done"}', "status"),
    ('{"cells": "many"}', "cells"),
    ("[1, 2]", "not a metrics record"),
    ("{", "not JSON"),
])
def test_a_broken_file_names_what_is_wrong(tmp_path, text, message):
    (tmp_path / "metrics.json").write_text(text)
    with pytest.raises(ValueError, match=message):
        read_metrics(tmp_path)
    with pytest.raises(FileNotFoundError):
        read_metrics(tmp_path / "nothing")
