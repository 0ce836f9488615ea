"""The sub-ambient (two-phase) pressure field behind the contact, solved with the film held.

The thesis's two-phase model lets the pressure fall below ambient where the gap diverges,
with a density that drops strongly there (:class:`~ehlfoam.contact.lubricant.PressureLaws`,
``twophase_p_scale``). Those pressures are bounded by vacuum, |p| <= p_ambient ~ 2e-4 pH, but
spread over several a^2 behind the contact: their elastic deformation varies by about 1 % of
the central film over the contact (:func:`subambient_deformation`). Here the contact's
solution (p >= 0 on the two-phase domain, zero-gradient outlet) is given: with its film H and
its pressurised zone (P > ``p_fixed``) held, the Reynolds equation with the two-phase density
is solved for P in the rest of the domain by Newton's method on a sparse Jacobian (scipy),
with P >= vacuum as an active-set constraint. Alone this is the one-way coupling; the coupled
option repeats it inside an outer iteration with the contact (:mod:`ehlfoam.contact.coupled`).

Nested iteration: the same problem on grids of every other point (film and p >= 0 field
injected) down to at most :data:`COARSEST_ROWS` rows; the coarsest is solved from the
flow-continuity start, each finer one from the bilinear interpolation of the coarser
solution, which leaves it a handful of Newton steps (a cubic interpolation measured worse:
16 steps instead of 8 on 1025 x 513). On the refined grids a step moves a
point at most :data:`INTERIOR_FRACTION` of its way to vacuum (the density, proportional to
the absolute pressure, never reaches 0 there, and no point is pushed onto the vacuum bound
only to be released a few at an iteration), and each step's linear system is solved by
GMRES preconditioned by its own sparse LU in a minimum-degree ordering of J + J^T without
pivoting (about 60 % of the fill and half the time of scipy's default column ordering with
partial pivoting on these grids; GMRES makes up for the missing pivoting in one or two
iterations). An earlier step's LU is no good preconditioner: points crossing ambient
change their density slope (the law's kink) by orders of magnitude from step to step. The
coarsest grid uses scipy's default LU, as the plain Newton solve did; every grid is solved
to ``tol``, so the result is the fine grid's own discrete solution.

Started from an earlier solution instead (``P_start``: the coupled option's later passes,
:mod:`ehlfoam.contact.coupled`, where the film has changed by a percent or less), the fine
grid is solved alone, every step's GMRES preconditioned by the first step's LU (refactored
only where the unknown points change or GMRES does not converge in a few iterations): the
same steps, one or two factorisations. (In the nested iteration an earlier step's LU saves
nothing: 8 of 9 fine steps on 513 x 257 still needed their own.)
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ehlfoam.contact.elastic import Deformation
from ehlfoam.contact.multigrid import Problem
from ehlfoam.contact.reynolds import residual
from ehlfoam.contact.transfer import prolong_bilinear

__all__ = ["COARSEST_ROWS", "INTERIOR_FRACTION", "SubAmbientResult", "solve_subambient",
           "subambient_deformation"]

#: The nested iteration's coarsest grid has at most this many rows (points along y).
COARSEST_ROWS = 129
#: On a refined grid a Newton step moves a point at most this fraction of the way to vacuum.
INTERIOR_FRACTION = 0.9
#: GMRES (preconditioned by the step's LU without pivoting): relative tolerance, restart
#: length, restarts.
KRYLOV_RTOL = 1e-6
KRYLOV_RESTART = 30
KRYLOV_RESTARTS = 2
#: GMRES preconditioned by an earlier step's LU gives up after this many iterations (then the
#: step's own LU)
REUSED_LU_ITERATIONS = 10


@dataclass
class SubAmbientResult:
    """The sub-ambient solve: P (units pH) on the finest grid, its convergence (max |residual|
    relative to max |wedge term|), the finest grid's Newton iterations and, per grid from the
    coarsest, ``levels``: shape (rows, columns), Newton iterations, LU factorisations, GMRES
    iterations, residual, converged, wall time [s]. ``P_contact``: the p >= 0 field it
    started from (units pH). ``deformation_max``: how much the sub-ambient pressures'
    elastic deformation varies over the Hertzian circle (units a^2/R, as the film), which the
    one-way coupling leaves out (:func:`subambient_deformation`)."""

    P: np.ndarray
    converged: bool
    iterations: int
    residual: float
    levels: list = field(default_factory=list)
    P_contact: np.ndarray | None = None
    deformation_max: float | None = None


def subambient_deformation(P: np.ndarray, h: float, x: np.ndarray, y: np.ndarray) -> float:
    """How much the elastic deformation of the sub-ambient part of ``P`` (units pH, on the
    uniform grid x, y of spacing ``h``, units a) varies over the Hertzian circle (units
    a^2/R, as the film): what the film there, held while the sub-ambient field is solved,
    would change by at most if it were coupled back (its uniform part the load balance
    absorbs)."""
    ny, nx = P.shape
    w = Deformation(nx, ny, h, h)(np.minimum(P, 0.0))
    inside = np.hypot(*np.meshgrid(x, y)) <= 1.0
    return float(np.ptp(w[inside])) if inside.any() else 0.0


def _coefficients(P, H, prob: Problem):
    rho, drho = prob.laws.rho(P)
    eps = rho * np.maximum(H, 0.0) ** 3 / (prob.laws.eta(P) * prob.lam)
    return rho, drho, eps


def _eps_slope(P, H, drho, prob: Problem):
    """d(eps)/dP through the density (the viscosity is eta0 below ambient): large in the
    two-phase region, where rho falls from 1 to 0 over p_ambient."""
    return drho * np.maximum(H, 0.0) ** 3 / (prob.laws.eta(P) * prob.lam)


def _jacobian(P, H, rho, drho, eps, h, unknown, deps):
    """Sparse d(L)/dP on the unknown points: the Poiseuille coefficients' density
    derivative ``deps`` included (without it the iteration is a Picard one where the
    pressure-driven flow matters: tens of iterations), the wedge term's exact."""
    ny, nx = P.shape
    idx = -np.ones(P.shape, dtype=np.int64)
    jj, ii = np.nonzero(unknown)
    idx[jj, ii] = np.arange(jj.size)
    rows, cols, vals = [], [], []

    def add(rr, cc_j, cc_i, v):
        col = idx[cc_j, cc_i]
        ok = col >= 0
        rows.append(rr[ok])
        cols.append(col[ok])
        vals.append(v[ok])

    r = idx[jj, ii]
    e0 = eps[jj, ii]
    ex_m = 0.5 * (eps[jj, ii - 1] + e0) / h**2
    ex_p = 0.5 * (eps[jj, np.minimum(ii + 1, nx - 1)] + e0) / h**2
    ey_m = 0.5 * (eps[jj - 1, ii] + e0) / h**2
    ey_p = 0.5 * (eps[jj + 1, ii] + e0) / h**2
    second = ii >= 2
    c1 = np.where(second, 1.5, 1.0)
    c2 = np.where(second, -2.0, -1.0)
    c3 = np.where(second, 0.5, 0.0)
    neumann = ii == nx - 2  # ghost P[:, -1] = P[:, -2]
    diag = -(ex_m + ex_p + ey_m + ey_p) + np.where(neumann, ex_p, 0.0) - c1 * H[jj, ii] * drho[jj, ii] / h
    add(r, jj, ii, diag)
    add(r, jj, ii - 1, ex_m - c2 * H[jj, ii - 1] * drho[jj, ii - 1] / h)
    i2 = np.maximum(ii - 2, 0)
    add(r, jj, i2, np.where(second, -c3 * H[jj, i2] * drho[jj, i2] / h, 0.0))
    add(r, jj, np.minimum(ii + 1, nx - 1), np.where(neumann, 0.0, ex_p))
    add(r, jj - 1, ii, ey_m)
    add(r, jj + 1, ii, ey_p)
    # eps at a face is the mean of its two points': each point's eps times the gradients
    ip = np.minimum(ii + 1, nx - 1)
    g_xm = (P[jj, ii - 1] - P[jj, ii]) / h**2
    g_xp = np.where(neumann, 0.0, (P[jj, ip] - P[jj, ii]) / h**2)
    g_ym = (P[jj - 1, ii] - P[jj, ii]) / h**2
    g_yp = (P[jj + 1, ii] - P[jj, ii]) / h**2
    add(r, jj, ii, 0.5 * deps[jj, ii] * (g_xm + g_xp + g_ym + g_yp))
    add(r, jj, ii - 1, 0.5 * deps[jj, ii - 1] * g_xm)
    add(r, jj, ip, 0.5 * deps[jj, ip] * g_xp)
    add(r, jj - 1, ii, 0.5 * deps[jj - 1, ii] * g_ym)
    add(r, jj + 1, ii, 0.5 * deps[jj + 1, ii] * g_yp)
    n = jj.size
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(n, n))


def _flow_continuity_start(P0: np.ndarray, H: np.ndarray, p_fixed: float,
                           prob: Problem) -> np.ndarray:
    """Start of the Newton iteration: behind the pressurised zone of each line y = const the
    Couette flux rho H of its last pressurised point carried downstream unchanged (the
    pressure-driven flow is small there), rho = min(1, flux / H), the pressure from the
    two-phase density law. Without it the first Newton step sends much of the region to
    vacuum, from where the active set releases it a few points an iteration. The coarsest
    grid's start; the finer grids start from the coarser solution (with steps held inside
    the vacuum bound: plainly projected, that start took 76 iterations instead of 24 on
    513 x 257, all but a few releasing points from vacuum; held inside it, 9)."""
    P = P0.copy()
    slope = prob.laws.p_hertz / prob.laws.twophase_p_scale
    ny, nx = P.shape
    cols = np.arange(nx)
    for j in range(ny):
        pressed = np.nonzero(P0[j] > p_fixed)[0]
        if pressed.size == 0:
            continue
        i_r = pressed[-1] + 1
        if i_r >= nx:
            continue
        flux = H[j, i_r]
        behind = cols > i_r
        rho = np.minimum(1.0, flux / np.maximum(H[j, behind], 1e-300))
        P[j, behind] = np.maximum((rho - 1.0) / slope, 0.99 * prob.p_floor)
    return P


def _factor(J: sp.csc_matrix):
    """Sparse LU of J as a preconditioner: minimum degree on J + J^T without pivoting (about
    60 % of the fill and half the time of scipy's default column ordering with partial
    pivoting on these five-point-like systems; less accurate, which GMRES makes up for)."""
    try:
        return spla.splu(J, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                         options=dict(SymmetricMode=True))
    except RuntimeError:  # a zero pivot
        return spla.splu(J)


def _gmres(J: sp.csr_matrix, b: np.ndarray, lu, restart: int = KRYLOV_RESTART,
           restarts: int = KRYLOV_RESTARTS) -> tuple[np.ndarray | None, int]:
    """GMRES on J x = b preconditioned by ``lu``: (x or None if not converged, iterations)."""
    count = [0]

    def tick(_):
        count[0] += 1

    x, info = spla.gmres(J, b, M=spla.LinearOperator(J.shape, lu.solve), rtol=KRYLOV_RTOL,
                         restart=restart, maxiter=restarts, callback=tick,
                         callback_type="pr_norm")
    return (x if info == 0 else None), count[0]


def _newton(P: np.ndarray, P0: np.ndarray, H: np.ndarray, h: float, prob: Problem,
            free: np.ndarray, tol: float, max_iter: int, refined: bool,
            keep_lu: float = 0.0) -> tuple:
    """Damped Newton from P on the ``free`` points. ``refined``: a start interpolated from a
    coarser solution (steps held inside the vacuum bound; each step's system by GMRES
    preconditioned by its own LU without pivoting, :func:`_factor`); else each step's own
    LU (scipy's default, partial pivoting) and a plain projection onto P >= vacuum.
    ``keep_lu`` (refined only): while the residual is below it, GMRES preconditioned by the
    last LU as long as the unknown points are the same and it converges in
    :data:`REUSED_LU_ITERATIONS` (a start close to the solution, ``inf``: the coupled
    option's later passes, one or two LUs instead of four to six); a new LU where not (0:
    always; in the nested iteration a reused LU measured no faster). Returns (P, converged,
    iterations, residual, factorisations, GMRES iterations)."""
    r = np.zeros_like(P)
    wedge = np.zeros_like(P)
    f0 = np.zeros_like(P)
    lu, lu_of = None, None

    def evaluate(P):
        rho, drho, eps = _coefficients(P, H, prob)
        residual(P, rho * H, eps, f0, h, h, r, wedge)
        # active set: at vacuum where the equation would pull P lower still
        unknown = free & ~((P <= prob.p_floor) & (r > 0.0))
        merit = float(np.sqrt(np.sum(r[unknown] ** 2)))
        return rho, drho, eps, unknown, merit

    def project(trial, base):
        if refined:  # at most INTERIOR_FRACTION of the way to vacuum
            trial = np.maximum(trial, base + INTERIOR_FRACTION * (prob.p_floor - base))
        trial = np.maximum(trial, prob.p_floor)
        if prob.neumann_outlet:
            trial[:, -1] = trial[:, -2]
        return trial

    rho, drho, eps, unknown, merit = evaluate(P)
    scale = float(np.abs(wedge[free]).max()) or 1.0
    n_lu, n_krylov = 0, 0
    res = np.inf
    for it in range(max_iter + 1):
        res = float(np.abs(r[unknown]).max()) / scale if unknown.any() else 0.0
        if res < tol or it == max_iter:
            break
        J = _jacobian(P, H, rho, drho, eps, h, unknown, _eps_slope(P, H, drho, prob))
        b = r[unknown]
        x = None
        if refined and res < keep_lu and lu is not None and np.array_equal(lu_of, unknown):
            # an earlier step's LU: refactored if GMRES does not converge in a few iterations
            x, n = _gmres(J, b, lu, REUSED_LU_ITERATIONS, 1)
            n_krylov += n
        if refined and x is None:
            lu = None  # released before the next factorisation (one LU in memory at a time)
            try:
                lu, lu_of = _factor(J.tocsc()), unknown.copy()
                x, n = _gmres(J, b, lu)
            except RuntimeError:  # singular: the direct solve below says so
                lu, x, n = None, None, 0
            n_lu, n_krylov = n_lu + 1, n_krylov + n
            if not keep_lu:
                lu = None
        if x is None:  # a direct solve: scipy's LU with partial pivoting
            n_lu += 1
            try:
                x = spla.splu(J.tocsc()).solve(b)
            except RuntimeError:  # singular (an unconverged contact): stop, not converged
                break
        step = np.zeros_like(P)
        step[unknown] = x
        # backtracking on the residual norm (the density law has a kink at ambient)
        for damping in (1.0, 0.5, 0.25, 0.125, 0.0625):
            trial = project(P + damping * step, P)
            t_rho, t_drho, t_eps, t_unknown, t_merit = evaluate(trial)
            if t_merit < merit:
                break
        P, rho, drho, eps, unknown, merit = trial, t_rho, t_drho, t_eps, t_unknown, t_merit
    return P, bool(res < tol), it, res, n_lu, n_krylov


def _free(P0: np.ndarray, p_fixed: float) -> np.ndarray:
    """The unknown points: interior (with a zero-gradient outlet the last column is a ghost)
    and not pressurised."""
    free = np.zeros(P0.shape, dtype=bool)
    free[1:-1, 1:-1] = True
    return free & (P0 <= p_fixed)


def _hierarchy(P0: np.ndarray, H: np.ndarray, h: float, coarsest_rows: int) -> list:
    """(P0, H, h) on the finest grid and the grids of every other point (injection) down to
    at most ``coarsest_rows`` rows, coarsest first."""
    grids = [(P0, H, h)]
    while True:
        p, hh, s = grids[-1]
        ny, nx = p.shape
        if ny <= coarsest_rows or (ny - 1) % 2 or (nx - 1) % 2:
            break
        grids.append((p[::2, ::2].copy(), hh[::2, ::2].copy(), 2.0 * s))
    return grids[::-1]


def solve_subambient(P0: np.ndarray, H: np.ndarray, h: float, prob: Problem,
                     p_fixed: float = 1e-3, tol: float = 1e-8, max_iter: int = 200,
                     P_start: np.ndarray | None = None,
                     coarsest_rows: int = COARSEST_ROWS) -> SubAmbientResult:
    """Newton solve of the sub-ambient pressure with the pressurised zone and the film held,
    by nested iteration over the grids of every other point (see the module docstring).

    Args:
        P0: the p >= 0 solution on the two-phase domain (units pH), zero-gradient outlet.
        H: its film (units a^2/R), held fixed.
        h: grid spacing (units a).
        prob: the two-phase problem (density law with ``twophase_p_scale``, ``p_floor`` at
            vacuum, ``neumann_outlet``).
        p_fixed: points with P0 above this are held (units pH).
        tol: convergence on max |residual| relative to max |wedge term|, on every grid.
        max_iter: Newton iterations per grid at most.
        P_start: a start of the free points on the finest grid (units pH; then no coarser
            grids): default the nested iteration.
        coarsest_rows: the coarsest grid has at most this many rows (a grid this small or
            smaller is solved directly, from the flow-continuity start).
    """
    grids = [(P0, H, h)] if P_start is not None else _hierarchy(P0, H, h, coarsest_rows)
    levels: list[dict] = []
    P = None
    for k, (p0, hh, s) in enumerate(grids):
        t0 = time.perf_counter()
        if k == 0 and P_start is None:
            start, refined = _flow_continuity_start(p0, hh, p_fixed, prob), False
        else:
            start = P_start if k == 0 else prolong_bilinear(P)
            start, refined = np.where(p0 > p_fixed, p0, np.maximum(start, prob.p_floor)), True
        if prob.neumann_outlet:
            start[:, -1] = start[:, -2]
        P, ok, its, res, n_lu, n_krylov = _newton(start, p0, hh, s, prob, _free(p0, p_fixed),
                                                  tol, max_iter, refined,
                                                  keep_lu=np.inf if P_start is not None
                                                  else 0.0)
        levels.append(dict(shape=list(p0.shape), iterations=its, factorisations=n_lu,
                           krylov_iterations=n_krylov, residual=res, converged=ok,
                           wall_s=time.perf_counter() - t0))
        if not ok and k < len(grids) - 1:
            # a coarse grid failed: the finest from the flow-continuity start instead
            P, ok, its, res, n_lu, n_krylov = _newton(
                _flow_continuity_start(P0, H, p_fixed, prob), P0, H, h, prob,
                _free(P0, p_fixed), tol, max_iter, False)
            levels.append(dict(shape=list(P0.shape), iterations=its, factorisations=n_lu,
                               krylov_iterations=n_krylov, residual=res, converged=ok,
                               wall_s=time.perf_counter() - t0))
            break
    last = levels[-1]
    return SubAmbientResult(P=P, converged=bool(last["converged"]),
                            iterations=last["iterations"], residual=last["residual"],
                            levels=levels, P_contact=P0)
