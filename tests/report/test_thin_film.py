"""A thin-film state as the report's pictures read a 3D case's fields
(ehlfoam.report.thin_film): one column per model cell outside the island, the gauge pressure
(the flooded cells' own, the cavities' cavitation pressure, ambient in the outer air), the
metrics' raster and pattern; the pressure map and the top view draw it."""

from __future__ import annotations

import numpy as np
import pytest

from ehlfoam.report.pressure import draw_pressure
from ehlfoam.report.thin_film import load_thin_film_fields
from ehlfoam.report.top_view import draw_top_view
from ehlfoam.thinfilm.problem import Grid
from ehlfoam.thinfilm.solution import ThinFilmSolution
from ehlfoam.thinfilm.state import save_state
from tests.tiny import tiny_geometry

A = 1e-4
P_CAV = -9e3


def write_state(case):
    """A ring of oil round the island at 2 kPa, a cavity behind the island at the
    cavitation pressure, on 0.25 a cells over tiny_geometry's domain."""
    d = 0.25 * A
    x = -1e-3 + d * (np.arange(80) + 0.5)
    y = d * (np.arange(40) + 0.5)
    X, Y = np.meshgrid(x, y)
    island = np.hypot(X, Y) < 1.5e-4
    h = np.where(island, np.nan, 1e-5)
    cavity = (X > 0) & (X < 3 * A) & (Y < A) & ~island
    flooded = (np.hypot(X, Y) < 6 * A) & ~island & ~cavity
    sol = ThinFilmSolution(
        grid=Grid(x=x, y=y, h=h, hx=h[:, 1:], hy=h[1:], h_side=h[-1], island=island),
        p=np.where(flooded, 2e3, np.nan), content=np.where(flooded, 1e-5, 0.0),
        flooded=flooded, time=0.25, steps=10, flux_in=0.0, flux_out=0.0, steady=True,
        island_radius=1.5e-4, fill=np.zeros(h.shape), cavity=cavity,
        cavitation_pressure=P_CAV)
    case.mkdir()
    save_state(sol, case / "state.npz")
    return sol


def test_a_thin_film_state_reads_as_the_fields_of_a_case(tmp_path):
    geom = tiny_geometry(a=A, solver="thin-film")
    assert load_thin_film_fields(tmp_path, geom) is None          # not run yet
    sol = write_state(tmp_path / "case")
    f = load_thin_film_fields(tmp_path / "case", geom)
    outside = ~sol.grid.island
    assert f.time == 0.25 and len(f.structure.base_x) == outside.sum() == len(f.pressure)
    np.testing.assert_array_equal(f.mid_gap(f.pressure), f.pressure)
    p = f.pressure
    assert set(np.unique(p)) == {P_CAV, 0.0, 2e3}
    assert (p[sol.cavity[outside]] == P_CAV).all() and (p[sol.flooded[outside]] == 2e3).all()
    assert f.pattern["state"] == "I" and f.pattern["bubble_enclosed"]
    assert f.pattern["bubble_length_over_a"] == pytest.approx(2.0, abs=0.06)
    view = draw_pressure(f, tmp_path / "pressure.png", title="tf")
    assert view.p_min == P_CAV and view.p_max == 2e3 and view.path.stat().st_size > 0
    top = draw_top_view(f.raster, f.pattern, tmp_path / "top.png", title="tf", time_s=f.time,
                        speed=geom.speed)
    assert top.bubble.any() and top.path.stat().st_size > 0
