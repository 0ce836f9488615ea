"""bench/remeasure.py: which writes it reads and the window means it prints."""

from __future__ import annotations

import pytest

from bench.remeasure import rank_times, window_means


def test_the_ranks_writes_are_read_in_time_order(tmp_path):
    for name in ("0", "0.1", "0.025", "constant", "0.2e-1"):
        (tmp_path / "processor0" / name).mkdir(parents=True)
    (tmp_path / "processor0" / "0.3").write_text("not a folder")
    assert rank_times(tmp_path) == ["0.2e-1", "0.025", "0.1"]
    serial = tmp_path / "serial"
    for name in ("0.5", "0.05"):
        (serial / name).mkdir(parents=True)
    assert rank_times(serial) == ["0.05", "0.5"]


def test_window_means_split_the_writes_and_skip_missing_values():
    rows = [{"time_s": 0.1 * k, "recorded_inlet": 3.0 if k % 2 else 5.0,
             "inlet": 5.0, "recorded_width": 12.0 + k, "width": None if k == 4 else 12.0 + k}
            for k in range(1, 7)]
    means = window_means(rows, 0.3)       # writes 1-3, then 4-6
    assert [m["writes"] for m in means] == [3, 3]
    assert means[0]["recorded_inlet"] == pytest.approx(11.0 / 3)
    assert means[0]["inlet"] == 5.0
    assert means[1]["width"] == pytest.approx(17.5)        # 17 and 18; 16 is missing
    assert means[1]["recorded_width"] == pytest.approx(17.0)
    assert means[1]["from_s"] == pytest.approx(0.4)
