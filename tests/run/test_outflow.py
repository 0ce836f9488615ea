"""What a 3D case leaves behind the contact (ehlfoam.run.outflow, issue 75): the oil through
its outlet binned into lateral rows is the layer the walls carry away, and summed it is the
outlet outflow the monitor records. A tiny real OpenFOAM case."""

from __future__ import annotations

import csv
import os
import shutil
import signal

import numpy as np
import pytest

from ehlfoam.case.geometry import load_geometry
from ehlfoam.case.writer import write_case
from ehlfoam.run import fields as case_fields
from ehlfoam.run.monitor import run_case
from ehlfoam.run.outflow import outlet_layers
from ehlfoam.spec.case import make_case_spec
from tests.tiny import SMALL


@pytest.mark.openfoam
def test_a_3d_case_s_outflow_as_layers_closes_on_its_outlet_outflow(tmp_path):
    case = tmp_path / "case"
    write_case(make_case_spec({**SMALL, "name": "outflow",
                               "run": {**SMALL["run"], "end_time": 2e-3}}), case)
    m = run_case(case, wall_limit=120)
    assert m["status"] == "finished", m
    a, speed = load_geometry(case).a, 0.02
    row = 0.25 * a
    layers = outlet_layers(case, row, 40)
    out = m["oil_outflow_by_boundary_m3_s"]["outlet"]
    assert out > 0 and (layers >= 0).all()
    # both sides of the track: twice the half's rows
    assert 2.0 * speed * row * layers.sum() == pytest.approx(out, rel=1e-9)
    carrying = np.nonzero(layers > 1e-3 * layers.max())[0]
    assert carrying[-1] * row < 5.0 * a       # within the domain's side
    assert outlet_layers(case, 2 * row, 20).sum() * 2 == pytest.approx(layers.sum(), rel=1e-12)
    # the run wrote them (0.1 a rows, half on each wall)
    assert _written_outflow(case, a, speed) == pytest.approx(out, rel=1e-5)
    # a later write cut short in its flux (a solver killed while it wrote) is passed over,
    # not parsed (foamlib backtracks for minutes on a list cut short): the last whole one
    t_last, last = case_fields.time_folders(case)[-1]
    cut = case / f"{2 * t_last:g}"
    shutil.copytree(last, cut)
    data = (last / "alphaPhi0.oil").read_bytes()
    (cut / "alphaPhi0.oil").write_bytes(data[:len(data) // 2])
    assert np.array_equal(outlet_layers(case, row, 40), layers)
    with pytest.raises(ValueError, match="incomplete"):
        case_fields.sample(cut, case_fields.Structure.load(case), load_geometry(case))


def _written_outflow(case, a: float, speed: float) -> float:
    """The outflow [m3/s] the case's outflow.csv says (its 0.1 a rows, both sides of the
    track), its disc and ball layers equal (pure rolling)."""
    with open(case / "outflow.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    disc = np.array([float(r["disc_layer_m"]) for r in rows])
    ball = np.array([float(r["ball_layer_m"]) for r in rows])
    assert disc == pytest.approx(ball, rel=1e-5)
    return 2.0 * speed * 0.1 * a * float((disc + ball).sum())


@pytest.mark.openfoam
def test_an_interrupted_run_and_its_resumption_each_write_outflow_csv(tmp_path):
    """outflow.csv is written at the end of every run, not only a finished one: a run
    stopped by SIGTERM (status interrupted) leaves the layers of its last write, and the run
    that goes on from it (extended) writes them again at its own last write."""
    case = tmp_path / "case"
    write_case(make_case_spec({**SMALL, "name": "outflow-resumed",
                               "run": {**SMALL["run"], "end_time": 0.05}}), case)
    geom = load_geometry(case)
    a, speed = geom.a, 0.02

    def terminate_once_past_the_start(sample, geom):
        # while the monitor watches (its SIGTERM handler set): a SIGTERM as from `kill`
        if sample.time > 0 and signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL:
            os.kill(os.getpid(), signal.SIGTERM)

    m = run_case(case, wall_limit=120, on_sample=terminate_once_past_the_start)
    assert (m["status"], m["end_reason"]) == ("interrupted", "interrupted"), m
    stopped = m["simulated_time_s"]
    assert 0 < stopped < 0.05
    out = m["oil_outflow_by_boundary_m3_s"]["outlet"]
    assert out > 0 and _written_outflow(case, a, speed) == pytest.approx(out, rel=1e-5)
    (case / "outflow.csv").unlink()
    m = run_case(case, wall_limit=120, extend_transits=0.01)
    assert (m["status"], m["end_reason"]) == ("finished", "end_time"), m
    assert m["simulated_time_s"] == pytest.approx(stopped + 0.01 * geom.transit_time,
                                                  abs=geom.max_delta_t)
    resumed = m["oil_outflow_by_boundary_m3_s"]["outlet"]
    assert _written_outflow(case, a, speed) == pytest.approx(resumed, rel=1e-5)
