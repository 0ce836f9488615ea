"""A thin-film case with a sudden stop end to end (issue 76 part 5): `ehlfoam run` marches it
to stop.after past rest whatever the steady-state test would say, slowing the walls as
wall_speed_at says, keeps a frame every stop.frame_interval, and `ehlfoam report` draws
them as a GIF and a strip. OpenFOAM is never called."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ehlfoam.cli.main import main
from ehlfoam.spec.stop import Stop, wall_speed_at
from ehlfoam.thinfilm.state import load_state
from tests.run.test_thin_film import NO_FOAM, SET

STOP = {"at": 0.003, "duration": 0.002, "after": 0.005, "frame_interval": 0.001,
        "frames_from": 0.003}


@pytest.fixture(autouse=True)
def no_openfoam(monkeypatch):
    for key, value in NO_FOAM.items():
        monkeypatch.setenv(key, value)


def test_a_stopping_case_runs_past_rest_keeps_its_frames_and_reports_a_gif(tmp_path):
    from PIL import Image

    case = tmp_path / "stop"
    stop = ["--set", "stop=" + "{" + ", ".join(f"{k} = {v}" for k, v in STOP.items()) + "}"]
    assert main(["case", "--out", str(case), *SET, *stop]) == 0
    assert main(["run", str(case), "--quiet"]) == 0
    m = json.loads((case / "metrics.json").read_text())
    end = STOP["at"] + STOP["duration"] + STOP["after"]
    dt = m["simulated_time_s"] / m["time_steps"]
    assert (m["status"], m["end_reason"]) == ("finished", "end_time")
    assert end <= m["simulated_time_s"] < end + dt
    frames = sorted((case / "frames").glob("*.npz"))
    times = np.array([load_state(f).time for f in frames])
    nominal = np.arange(len(frames)) * STOP["frame_interval"]   # from t = 0: at - frames_from
    assert len(frames) == int(end / STOP["frame_interval"] + 1e-9) + 1
    assert np.all((times >= nominal - 1e-12) & (times <= nominal + dt + 1e-12))
    assert times[0] == 0.0                             # the start itself
    speeds = wall_speed_at(Stop(**STOP), 0.02, times)
    assert speeds[0] == 0.02 and speeds[-1] == 0.0 and (0 < speeds).sum() > 3
    assert main(["report", str(case)]) == 0
    gif = Image.open(case / "report" / "stop.gif")
    assert gif.n_frames == len(frames)
    assert (case / "report" / "stop_frames.png").is_file()
    html = (case / "report" / "index.html").read_text()
    assert "stop.gif" in html and "The stop: " in html
