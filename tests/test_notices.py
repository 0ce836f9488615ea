"""Notices: one line each with a code and a docs pointer, kept in metrics.json as text and read
back, shown once per batch; every warning the package raises fits the line."""

from __future__ import annotations

import numpy as np
import pytest

from ehlfoam.case.geometry import BALL_WALL_STEPS_LIMIT, mesh_warnings
from ehlfoam.notices import MAX_TEXT, Notice, NoticeTally, from_text, to_text
from ehlfoam.run.monitor import (FRONT_CELL_WARNING, REAR_CELL_WARNING, boundary_warnings,
                                 front_cell_warnings, rear_cell_warnings)
from ehlfoam.run.warnings import bare_track_warnings, enclosure_warnings
from tests.test_docs_links import ROOT, _anchors
from tests.tiny import tiny_geometry

REAR = Notice("rear-meniscus-cells", "the rear meniscus sits in 0.59 a cells (above 0.15 a)",
              "docs/models/interface.md#rear-meniscus-cells")
SIDE = Notice("outflow-off-outlet", "55% of the outflow left (through the side)",
              "docs/models/interface.md")


@pytest.mark.parametrize("code, text, docs, words", [
    ("Rear", "x", "docs/validation.md", "lowercase"),
    ("rear cells", "x", "docs/validation.md", "lowercase"),
    ("rear", "x" * (MAX_TEXT + 1), "docs/validation.md", f"at most {MAX_TEXT}"),
    ("rear", "two\nlines", "docs/validation.md", "one line"),
    ("rear", "a; b", "docs/validation.md", "without ';'"),
    ("rear", "x", "validation.md", "not a docs pointer"),
    ("rear", "x", "docs/models/interface.md, \"The mesh\"", "not a docs pointer"),
])
def test_a_notice_is_one_short_line_with_a_code_and_a_docs_pointer(code, text, docs, words):
    with pytest.raises(ValueError, match=words):
        Notice(code, text, docs)


def test_metrics_text_reads_back():
    text = to_text([REAR, SIDE])
    assert text == ("[rear-meniscus-cells] the rear meniscus sits in 0.59 a cells (above 0.15 a) "
                    "(docs/models/interface.md#rear-meniscus-cells); [outflow-off-outlet] 55% of "
                    "the outflow left (through the side) (docs/models/interface.md)")
    assert from_text(text) == [REAR, SIDE]
    assert from_text("") == [] and from_text(None) == [] and to_text([]) == ""
    with pytest.raises(ValueError, match="not a notice"):
        from_text("the rear meniscus sits in 0.43 a cells (above 0.15 a): they lay wall films")


def test_a_batch_shows_each_code_once_and_counts_the_cases():
    lines: list[str] = []
    tally = NoticeTally(lines.append)
    tally.add("u10", to_text([REAR]))
    tally.add("u20", to_text([REAR, SIDE]))
    tally.add("u30", "")
    tally.add("u40", to_text([REAR]))
    assert lines == [f"warning  u10: {REAR}", f"warning  u20: {SIDE}"]
    assert tally.summary() == ("warnings [rear-meniscus-cells] 3 cases, [outflow-off-outlet] "
                               "1 case (each case's metrics.json lists its own)")
    assert NoticeTally(lines.append).summary() is None


def test_warnings_of_an_older_run_are_shown_once_shortened():
    lines: list[str] = []
    tally = NoticeTally(lines.append)
    old = "the rear meniscus sits in 0.43 a cells (above 0.15 a): they lay wall films " * 20
    tally.add("a", old)
    tally.add("b", old)
    assert len(lines) == 1 and len(lines[0]) < MAX_TEXT + 20
    assert tally.cases == {"unparsed": 2}


def test_every_warning_the_package_raises_is_a_notice_that_fits_at_extreme_values():
    """Built at values far past their limits (wider numbers), each source's notice is valid
    (the constructor checks length and form) and names its code and docs."""
    raised = [*mesh_warnings(tiny_geometry(ball_wall_steps=999.9)),
              *rear_cell_warnings(123.45), *rear_cell_warnings(123.45, follows=True),
              *front_cell_warnings(98765.0), *bare_track_warnings(1.0),
              *boundary_warnings(1.0, {"flooded_clearance_over_a": 0.0,
                                       "flooded_nearest_boundary": "upstream"}),
              *enclosure_warnings({"enclosed_bubbles": 99}, np.zeros((9, 9), bool))]
    assert [n.code for n in raised] == ["ball-wall-steps", "rear-meniscus-cells",
                                        "rear-meniscus-cells", "front-contact-line-cells",
                                        "supply-layers-broken", "outflow-off-outlet",
                                        "region-near-boundary", "closed-within-a-cell"]
    assert all(n.docs.startswith("docs/") for n in raised)
    for n in raised:   # each pointer names a page and one of its sections
        page, _, anchor = n.docs.partition("#")
        assert (ROOT / page).is_file() and anchor in _anchors(ROOT / page), n.docs
    assert from_text(to_text(raised)) == raised
    # and none below their limits
    assert not mesh_warnings(tiny_geometry(ball_wall_steps=BALL_WALL_STEPS_LIMIT))
    assert not rear_cell_warnings(REAR_CELL_WARNING)
    assert "mesh.follow.half_width" in rear_cell_warnings(0.5, follows=True)[0].text
    assert "mesh.refine" in rear_cell_warnings(0.5)[0].text
    assert not front_cell_warnings(FRONT_CELL_WARNING)
    cavity = np.zeros((9, 9), bool)
    assert not enclosure_warnings({"enclosed_bubbles": 0}, cavity)   # open wake: state II
    assert not enclosure_warnings({"enclosed_bubbles": 1}, None)     # no outlet model
    cavity[4, 4] = True                                               # the model's own cavity
    assert not enclosure_warnings({"enclosed_bubbles": 1}, cavity)
