"""The run's warnings: oil off the outlet, a region near an open boundary, coarse cells at
the rear meniscus, a supply track left bare."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from foamlib import FoamFieldFile

from ehlfoam.case.geometry import load_geometry
from ehlfoam.case.writer import write_case
from ehlfoam.run.fields import Structure, read_alpha, time_folders
from ehlfoam.run.monitor import run_case
from ehlfoam.run.warnings import (BARE_TRACK_WARNING, CLEARANCE_WARNING, OFF_OUTLET_WARNING,
                                  REAR_CELL_WARNING, bare_track, bare_track_warnings,
                                  boundary_warnings, rear_cell_warnings, rear_meniscus_cell)
from ehlfoam.spec.case import load_case_spec, make_case_spec
from tests.tiny import SMALL


def test_a_region_spilling_over_the_side_is_flagged_and_one_inside_is_not():
    from ehlfoam.run.fields import off_outlet_share
    # the coarse level at size_far 0.2 a reaching the 8 a side: 53-61 % off the outlet
    spilling = off_outlet_share({"outlet": 0.45, "side": 0.55, "inlet": 0.0})
    [warning] = boundary_warnings(spilling)
    assert warning.text.startswith("55% of the outflow left through the side or upstream")
    assert "domain.side" in warning.text
    assert boundary_warnings(off_outlet_share({"outlet": 0.996, "side": 0.004})) == []
    assert boundary_warnings(OFF_OUTLET_WARNING) == []
    assert boundary_warnings(None) == []


def test_a_region_near_an_open_boundary_is_flagged():
    # a film-resolving run's rear meniscus at 13.5 a against the 14 a outlet
    [warning] = boundary_warnings(0.0, {"flooded_clearance_over_a": 0.5,
                                        "flooded_nearest_boundary": "outlet"})
    assert warning.text.startswith("the flooded region is 0.50 a from the outlet boundary")
    assert "domain.downstream" in warning.text
    [warning] = boundary_warnings(None, {"flooded_clearance_over_a": 0.2,
                                         "flooded_nearest_boundary": "side"})
    assert "domain.side" in warning.text
    assert boundary_warnings(0.0, {"flooded_clearance_over_a": CLEARANCE_WARNING,
                                   "flooded_nearest_boundary": "side"}) == []
    assert boundary_warnings(0.0, {"flooded_clearance_over_a": None,
                                   "flooded_nearest_boundary": None}) == []
    # both at once: spilled over the side and still touching it
    assert len(boundary_warnings(0.55, {"flooded_clearance_over_a": 0.0,
                                        "flooded_nearest_boundary": "side"})) == 2


def test_the_cells_at_the_rear_meniscus_are_read_off_the_spec_and_coarse_ones_flagged():
    """The default medium level's rear meniscus (11 a behind the contact on y = 0) sits in its
    far-field cells; examples/cases/nominal_films.toml's box puts 0.1 a cells there; an open
    wake has no rear meniscus."""
    root = Path(__file__).resolve().parents[2] / "examples" / "cases"
    nominal, films = (load_case_spec(root / n) for n in ("nominal.toml", "nominal_films.toml"))
    closed = {"state": "I", "flooded_x_max_over_a": 11.0}
    far = rear_meniscus_cell(nominal, closed)
    assert far == pytest.approx(nominal.mesh.level()["size_far"])
    assert rear_meniscus_cell(films, closed) == pytest.approx(0.1)
    # nearer the contact the cells shrink with the distance from it, below the far size
    assert rear_meniscus_cell(nominal, {**closed, "flooded_x_max_over_a": 3.0}) < far
    assert rear_meniscus_cell(nominal, {**closed, "state": "II"}) is None
    assert rear_meniscus_cell(nominal, {"state": "I", "flooded_x_max_over_a": None}) is None
    assert rear_meniscus_cell(nominal, None) is None
    [warning] = rear_cell_warnings(far)
    assert warning.text.startswith(f"the rear meniscus sits in {far:.2f} a cells")
    assert "mesh.refine" in warning.text and "nominal_films.toml" in warning.text
    assert rear_cell_warnings(0.1) == []
    assert rear_cell_warnings(REAR_CELL_WARNING) == []
    assert rear_cell_warnings(None) == []


@pytest.mark.openfoam
def test_a_supply_track_left_bare_upstream_of_the_region_is_measured_and_flagged(tmp_path):
    """A tiny real case's 3 um layers arrive whole: none of the track's columns upstream of
    its puddle is bare and the run does not warn. With the oil taken out of half those
    columns (as layers broken into drops leave them), half reads bare and the run warns."""
    case = tmp_path / "case"
    spec = make_case_spec({**SMALL, "name": "bare"})
    write_case(spec, case)
    m = run_case(case, wall_limit=120)
    assert m["status"] == "finished", m
    assert m["supply_track_bare_fraction"] == 0.0
    assert "supply-layers-broken" not in (m["warnings"] or "")
    geom, structure = load_geometry(case), Structure.load(case)
    # the columns it reads: on the track, half an a clear of the puddle's upstream end
    front = (m["flooded_x_min_over_a"] - 0.5) * geom.a
    read = np.flatnonzero((structure.base_x < front) & (np.abs(structure.base_y)
                                                        < 0.8 * spec.supply.track_half_width))
    assert len(read) >= 6
    last = time_folders(case)[-1][1]
    alpha = read_alpha(last / "alpha.oil", structure)
    alpha[np.isin(structure.base_cell, read[::2])] = 0.0
    FoamFieldFile(last / "alpha.oil").internal_field = alpha
    share = bare_track(spec, geom, structure, case, m)
    assert share == pytest.approx(len(read[::2]) / len(read)) and share > BARE_TRACK_WARNING
    [warning] = bare_track_warnings(share)
    assert warning.code == "supply-layers-broken"
    assert warning.text.startswith(f"{share:.0%} of the supply track upstream of the region")
    # only a supply of layers has a track to read
    flooded = make_case_spec({**SMALL, "supply": {**SMALL["supply"], "mode": "flooded"}})
    assert bare_track(flooded, geom, structure, case, m) is None
    assert bare_track_warnings(BARE_TRACK_WARNING) == [] and bare_track_warnings(None) == []
