"""The walls' stop in a real (tiny) OpenFOAM case (issue 76 part 5): the disc, the ball, the
island and the supply slow as wall_speed_at says, read back from the velocity OpenFOAM wrote
at each time before, during and after the ramp; the steady-state test does not end the run
before the stop's end; the report's stop pictures take a frame from each written time."""

from __future__ import annotations

import numpy as np
import pytest
from foamlib import FoamFieldFile

from ehlfoam.case.geometry import load_geometry
from ehlfoam.case.writer import write_case
from ehlfoam.report.case_report import report_case
from ehlfoam.report.stop import make_stop_pictures
from ehlfoam.errors import SpecError
from ehlfoam.run import fields as case_fields
from ehlfoam.run.monitor import run_case
from ehlfoam.spec import make_case_spec
from ehlfoam.spec.stop import wall_speed_at
from tests.tiny import SMALL

STOP = {"at": 3e-4, "duration": 3e-4, "after": 3e-4}


def _values(folder, patch):
    v = FoamFieldFile(folder / "U").boundary_field[patch]["value"]
    return np.atleast_2d(np.asarray(v, float))


@pytest.mark.openfoam
@pytest.mark.parametrize("scene", ["interface", "gas-release"])   # supply uniform / per face
def test_the_walls_of_a_3d_case_slow_to_rest_as_the_stop_says(tmp_path, scene):
    run = {k: v for k, v in SMALL["run"].items() if k != "end_time"}
    spec = make_case_spec({**SMALL, "scene": scene, "run": run, "stop": STOP})
    case = tmp_path / "stop"
    write_case(spec, case)
    m = run_case(case, wall_limit=120)
    assert (m["status"], m["end_reason"]) == ("finished", "end_time"), m.get("log_tail")
    assert m["simulated_time_s"] == pytest.approx(9e-4, rel=1e-6)
    mapped = case / "constant" / "boundaryData"
    assert (mapped / "island").is_dir()
    assert (mapped / "supply").is_dir() == (scene == "gas-release")
    times = case_fields.time_folders(case)
    t0, first = times[0]
    assert t0 < STOP["at"]
    u = spec.wall_speed
    base = {p: _values(first, p) for p in ("disc", "ball", "island", "supply")}
    assert base["disc"][0] == pytest.approx([u, 0, 0])
    phases = {"before": 0, "during": 0, "after": 0}
    for t, folder in times[1:]:
        k = wall_speed_at(spec.stop, 1.0, t)
        phases["before" if k == 1 else "after" if k == 0 else "during"] += 1
        for patch, v0 in base.items():
            v = np.broadcast_to(_values(folder, patch), v0.shape)   # "uniform" at rest
            assert v == pytest.approx(k * v0, abs=1e-6 * u), (patch, t)   # 8 digits written
    assert min(phases.values()) >= 2, phases
    assert np.abs(base["island"]).max() > 0.5 * u and np.abs(base["ball"]).max() > 0.5 * u
    # the report's stop pictures: a frame a written time, labelled from the stop
    gif, png, recs = make_stop_pictures(case, load_geometry(case), spec.stop, spec.speed,
                                        tmp_path, written=True)
    assert gif.is_file() and png.is_file()
    assert [r["time_s"] for r in recs] == pytest.approx([t for t, _ in times])
    for r in recs:
        assert r["from_stop_s"] == pytest.approx(r["time_s"] - STOP["at"])
        assert r["wall_speed_m_s"] == pytest.approx(wall_speed_at(spec.stop, u, r["time_s"]))
        assert r["state"] in ("I", "II") and r["flooded_length_over_a"] > 0
    # the case report draws the stop's GIF and not the same written times again
    report_case(case)
    assert (case / "report" / "stop.gif").is_file()
    assert not (case / "report" / "transient.gif").exists()


def test_a_stop_with_slip_walls_or_still_walls_is_refused():
    with pytest.raises(SpecError, match=r"physics\.wall_slip_length = 1e-06 m in scene = "
                                        r"'interface'"):
        make_case_spec({"stop": {"at": 0.01}, "physics": {"wall_slip_length": 1e-6}})
    with pytest.raises(SpecError, match=r"needs walls_moving = true"):
        make_case_spec({"stop": {"at": 0.01}, "walls_moving": False})
