"""The regime map as shown: its text in mm/s and its pictures, from the SI analysis."""

from __future__ import annotations

from ehlfoam.batch.regime import analyse
from ehlfoam.report.regime import FIGURES, summary_lines, write_figures
from tests.batch.test_regime import ramp_rows, row


def test_summary_lines_in_display_units():
    rows = [row(u, s, supply=sup) for sup, states in ((1.0, "I II II II II"),
                                                      (2.0, "I I I II II"),
                                                      (4.0, "I I I I I"))
            for u, s in zip((5, 8, 12, 17, 25), states.split())]
    rows += [row(u, s, supply=2.0, T=60.0) for u, s in zip((5, 8, 12), ("II", "I", "II"))]
    lines = summary_lines(analyse(rows))
    assert "T 40 C, F 20 N, 2um, coarse: I -> II at 14.5 +- 2.5 mm/s" in lines
    assert "T 40 C, F 20 N, 4um, coarse: state I up to 25 mm/s: transition above it" in lines
    assert any(line.startswith("T 60 C") and "non-monotonic: state II also at 5 mm/s" in line
               for line in lines), lines


def test_ramp_lines_say_hysteresis():
    lines = summary_lines(analyse(ramp_rows("I I I II II".split(), "II II I I".split())))
    assert lines == ["ramp A (2um, T 40 C): up I -> II at 14.5 +- 2.5 mm/s; down I -> II at "
                     "10 +- 2 mm/s; hysteresis observed, width 4.5 +- 4.5 mm/s (states differ "
                     "at 12 mm/s)"]
    one_way = summary_lines(analyse(ramp_rows("I I II".split(), [], speeds=(8, 14, 20))))
    assert "up I -> II at 17" in one_way[0] and "down" not in one_way[0]


def test_figures(tmp_path):
    rows = [row(u, s, supply=sup) for sup in (1.0, 2.0)
            for u, s in zip((5, 8, 12), ("I", "I", "II"))]
    rows += [row(8, "", supply=4.0, status="failed")]
    rows += ramp_rows("I I II".split(), "II I".split(), speeds=(5, 8, 12))
    written = write_figures(analyse(rows), tmp_path)
    assert [p.name for p in written] == list(FIGURES)
    assert all(p.stat().st_size > 5000 for p in written)
    one_way = write_figures(analyse(ramp_rows("I I II".split(), [], speeds=(8, 14, 20))),
                            tmp_path / "one")   # draws without a down branch
    assert [p.name for p in one_way] == ["regime_speed_supply.png"]
