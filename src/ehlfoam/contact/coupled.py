"""The two-phase option fully coupled: the contact and its sub-ambient field solved together.

The one-way solve (:mod:`ehlfoam.contact.twophase`) holds the film of the p >= 0 contact
while it solves the sub-ambient pressures, so their elastic deformation is missing from that
film and their (negative) load from the load balance. Coupled, a block Gauss-Seidel
(fixed-point) iteration over the two solves converges to the solution of both together:

1. the contact by multigrid (p >= 0 part), the sub-ambient field of the last Newton solve
   held as a given load (:meth:`~ehlfoam.contact.multigrid.MultigridSolver.hold`): its
   deformation is in the film on every level and its load counts in the load balance; the
   multigrid restarts from its last pressure and film constant;
2. the sub-ambient field by Newton with the new film, started from the last one (on the
   finest grid only, no nested iteration after the first pass);

until the film of the last Newton solve is H0 + rigid shape + the deformation of the total
pressure to ``tol`` times the central film anywhere on the domain. The held field is the
sub-ambient solve's change of the pressure: its solved values minus the contact's on the
points it solves for (the contact's P there is 0 or below ``p_fixed``). At the converged
state the film of the last Newton solve is rigid shape + H0 + deformation of the total
pressure to the tolerance, and the total pressure carries the load to about the multigrid's
load tolerance (the held field's last change is ~1e-6 of the load)
(:func:`coupling_errors`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ehlfoam.contact.elastic import Deformation
from ehlfoam.contact.multigrid import MGResult, MultigridSolver, Problem
from ehlfoam.contact.twophase import SubAmbientResult, solve_subambient

__all__ = ["COUPLING_TOL", "MAX_OUTER", "Coupling", "couple", "coupling_errors"]

#: The outer iteration stops once the film error (:func:`coupling_errors`) is below this
#: times hc anywhere on the domain.
COUPLING_TOL = 1e-3
#: Outer iterations at most.
MAX_OUTER = 10


@dataclass
class Coupling:
    """How well a two-phase solution satisfies the coupled equations, and the outer iteration
    that reached it. ``film_error``: max |H - (H0 + rigid + W(P_total))| over the domain,
    over hc; ``load_error``: (h^2 sum P_total - 2 pi / 3) / (2 pi / 3) (signed); ``outer``:
    one record per outer pass (film change over hc, multigrid cycles, Newton iterations,
    converged, wall [s]); ``converged``: the outer iteration reached its tolerance (one-way:
    True, no passes)."""

    mode: str
    film_error: float
    load_error: float
    outer: list = field(default_factory=list)
    converged: bool = True
    tol: float = COUPLING_TOL


def coupling_errors(P: np.ndarray, H: np.ndarray, H0: float, x: np.ndarray, y: np.ndarray,
                    hc: float, deform: Deformation | None = None) -> tuple[float, float]:
    """(film error over hc, relative load error) of the total pressure ``P`` (units pH, on
    the uniform grid x, y, units a) with the film ``H`` and film constant ``H0`` (units
    a^2/R): see :class:`Coupling`. ``deform``: the grid's DC-FFT operator (default: a new
    one)."""
    h = float(x[1] - x[0])
    ny, nx = P.shape
    rigid = 0.5 * x[None, :] ** 2 + 0.5 * y[:, None] ** 2
    film = H0 + rigid + (deform or Deformation(nx, ny, h, h))(P)
    target = 2.0 * math.pi / 3.0
    return (float(np.abs(H - film).max()) / hc,
            (h * h * float(P.sum()) - target) / target)


def couple(solver: MultigridSolver, first: MGResult, prob: Problem, h: float,
           tol: float = COUPLING_TOL, max_outer: int = MAX_OUTER, p_fixed: float = 1e-3,
           ) -> tuple[MGResult, SubAmbientResult, list, bool]:
    """The outer iteration from the contact solve ``first`` (p >= 0, by ``solver``, which is
    reused; its held load is cleared on return). It has converged once the film of the last
    Newton solve differs from H0 + rigid + the deformation of the total pressure (the
    coupling's own residual: the deformation of the held field's last change) by less than
    ``tol`` times hc anywhere (:func:`coupling_errors`): the cycle-to-cycle noise of the
    multigrid's converged film, which inside the contact can exceed that tolerance, does not
    enter it.

    Args:
        prob: the two-phase problem of the sub-ambient solve (see
            :func:`~ehlfoam.contact.twophase.solve_subambient`).
        h: grid spacing (units a).
        tol: the film error (over hc) at which the iteration has converged.
        max_outer: passes at most.
        p_fixed: points of the contact's P above this are held by the sub-ambient solve
            (units pH).
    Returns:
        (the last contact solve, the last sub-ambient solve, one record per pass, converged):
        each record the pass's film error and load error (:func:`coupling_errors`), its
        film change from the previous pass at the centre and at the minimum (over hc), the
        multigrid cycles, the Newton iterations and LU factorisations and its wall time [s].
    """
    mg = first
    t0 = time.perf_counter()
    sub = solve_subambient(mg.P, mg.H, h, prob, p_fixed=p_fixed)
    centre = mg.centre_index()
    deform = solver.levels[-1].deform
    outer: list[dict] = []
    converged = False
    try:
        for k in range(1, max_outer + 1):
            if not (mg.converged and sub.converged):
                break
            solver.hold(np.where(sub.P_contact > p_fixed, 0.0, sub.P - sub.P_contact))
            t1 = time.perf_counter()
            nxt = solver.solve(mg.H0, P_init=mg.P, fmg_hc=first.fmg_hc)
            sub = solve_subambient(nxt.P, nxt.H, h, prob, p_fixed=p_fixed, P_start=sub.P)
            hc = float(nxt.H[centre])
            film_err, load_err = coupling_errors(sub.P, nxt.H, nxt.H0, nxt.x, nxt.y, hc, deform)
            ok = bool(nxt.converged and sub.converged)
            outer.append(dict(iteration=k, film_error_over_hc=film_err, load_error=load_err,
                              hc_change_over_hc=(hc - float(mg.H[centre])) / hc,
                              hmin_change_over_hc=float(nxt.H.min() - mg.H.min()) / hc,
                              cycles=nxt.cycles, newton_iterations=sub.iterations,
                              factorisations=sum(lv["factorisations"] for lv in sub.levels),
                              converged=ok, wall_s=time.perf_counter() - t1))
            mg = nxt
            if ok and film_err < tol:
                converged = True
                break
    finally:
        solver.hold(None)
    mg.wall_s = time.perf_counter() - t0 + first.wall_s
    return mg, sub, outer, converged
