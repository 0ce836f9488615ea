"""The two-phase option's sub-ambient field by nested iteration (:mod:`ehlfoam.contact.twophase`):
the same discrete solution as the direct Newton solve from the flow-continuity start, in fewer
Newton steps on the fine grid."""

from __future__ import annotations

import numpy as np
import pytest

from ehlfoam.contact.multigrid import Problem
from ehlfoam.contact.solver import solve
from ehlfoam.contact.spec import P_AMBIENT_PA, make_spec
from ehlfoam.contact.twophase import _hierarchy, solve_subambient


@pytest.fixture(scope="module")
def direct():
    """257 x 129 at 1 m/s, one-way: at most COARSEST_ROWS rows, so solved directly (flow
    start)."""
    return solve(make_spec(load=20, speed=1.0, temperature=40, grid=129, cavitation="twophase",
                           twophase_coupling="one-way"))


def _problem(r) -> Problem:
    c = r.contact
    return Problem(lam=c.lam, laws=r.spec.laws(), p_floor=-P_AMBIENT_PA / c.p_hertz,
                   neumann_outlet=True, moes_M=c.M, moes_L=c.L)


def _cavity_end(x: np.ndarray, p_row: np.ndarray, below: float) -> float:
    neg = np.nonzero((x >= 1.0) & (p_row < below))[0]
    end = neg[0]
    while end + 1 < len(x) and p_row[end + 1] < below:
        end += 1
    return float(x[end])


def test_nested_iteration_matches_the_direct_solve(direct):
    sub = direct.subambient
    assert sub.converged and [lv["shape"] for lv in sub.levels] == [[129, 257]]
    nested = solve_subambient(sub.P_contact, direct.mg.H, direct.domain.h, _problem(direct),
                              coarsest_rows=65)
    assert [lv["shape"] for lv in nested.levels] == [[65, 129], [129, 257]]
    assert nested.converged and all(lv["converged"] for lv in nested.levels)
    # started from the coarse solution, the fine grid needs fewer Newton steps
    assert nested.iterations < sub.iterations
    # the same discrete solution: both converged to 1e-8 of the wedge term
    floor = P_AMBIENT_PA / direct.contact.p_hertz
    assert np.abs(nested.P - sub.P).max() < 1e-4 * floor
    j, _ = direct.centre_index()
    x, ps = direct.mg.x, direct.spec.twophase_p_scale / direct.contact.p_hertz
    for below in (0.0, -0.5 * ps):
        assert _cavity_end(x, nested.P[j], below) == _cavity_end(x, sub.P[j], below)


def test_hierarchy_injects_down_to_the_coarsest_rows():
    P0 = np.arange(257 * 513, dtype=float).reshape(257, 513)
    grids = _hierarchy(P0, 2.0 * P0, 0.01, coarsest_rows=65)
    assert [g[0].shape for g in grids] == [(65, 129), (129, 257), (257, 513)]
    assert [g[2] for g in grids] == pytest.approx([0.04, 0.02, 0.01])
    assert np.array_equal(grids[0][0], P0[::4, ::4]) and np.array_equal(grids[0][1], 2 * P0[::4, ::4])
    # an odd number of intervals stops the coarsening
    assert len(_hierarchy(P0[:, :512], P0[:, :512], 0.01, coarsest_rows=65)) == 1


def test_a_singular_newton_system_is_reported_not_raised():
    """An unconverged contact (two cycles) can leave the sub-ambient Jacobian singular: the
    solve then says so in its failure instead of raising (a batch's warm-up solve did)."""
    r = solve(make_spec(load=20, speed=0.02, temperature=25, grid=65, cavitation="twophase",
                        max_cycles=2))
    s = r.summary()
    assert not r.converged and not r.subambient.converged
    assert "sub-ambient Newton not converged" in s["failure"]
    assert s["subambient_levels"][-1]["converged"] is False


def test_the_one_way_coupling_leaves_out_a_film_change_it_bounds(direct):
    """The sub-ambient pressures' elastic deformation, which the held film leaves out: its
    range over the Hertzian circle from the DC-FFT of their sub-ambient part (the direct
    sum's on a small grid), none without one, and at 1 m/s a small fraction of the central
    film (|p| <= ambient, ~1e-4 pH)."""
    from ehlfoam.contact.elastic import deformation_direct
    from ehlfoam.contact.twophase import subambient_deformation

    rng = np.random.default_rng(3)
    P = rng.normal(size=(21, 41))
    P[0, :] = P[:, 0] = 0.0
    x, y = np.linspace(-2.0, 2.0, 41), np.linspace(-1.0, 1.0, 21)
    inside = np.hypot(*np.meshgrid(x, y)) <= 1.0
    w = deformation_direct(np.minimum(P, 0.0), 0.1, 0.1)
    assert subambient_deformation(P, 0.1, x, y) == pytest.approx(float(np.ptp(w[inside])),
                                                                 rel=1e-9)
    assert subambient_deformation(np.abs(P), 0.1, x, y) == 0.0
    share = direct.summary()["subambient_deformation_over_hc"]
    assert 0.0 < share < 0.01
