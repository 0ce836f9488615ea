"""The sub-ambient (two-phase) pressure field behind the contact, one-way coupled.

The thesis's two-phase model lets the pressure fall below ambient where the gap diverges,
with a density that drops strongly there (:class:`~ehlfoam.contact.lubricant.PressureLaws`,
``twophase_p_scale``). Those pressures are bounded by vacuum, |p| <= p_ambient ~ 2e-4 pH:
their elastic deformation (~1e-4 of the Hertzian one) cannot move the film. So the contact
is solved first with p >= 0 on the two-phase domain (zero-gradient outlet); then, with the
film H and the pressurised zone (P > ``p_fixed``) held, the Reynolds equation with the
two-phase density is solved for P in the rest of the domain by Newton's method on a sparse
Jacobian (scipy), with P >= vacuum as an active-set constraint.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ehlfoam.contact.multigrid import Problem
from ehlfoam.contact.reynolds import residual


@dataclass
class SubAmbientResult:
    P: np.ndarray
    converged: bool
    iterations: int
    residual: float


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
    vacuum, from where the active set releases it a few points an iteration.
    (Starting from the solution on the grid of every other point, interpolated, measured
    worse: 76 iterations instead of 24 on 513 x 257.)"""
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


def solve_subambient(P0: np.ndarray, H: np.ndarray, h: float, prob: Problem,
                     p_fixed: float = 1e-3, tol: float = 1e-8, max_iter: int = 200,
                     P_start: np.ndarray | None = None) -> SubAmbientResult:
    """Newton solve of the sub-ambient pressure with the pressurised zone and the film held.

    Args:
        P0: the p >= 0 solution on the two-phase domain (units pH), zero-gradient outlet.
        P_start: the start of the free points (default: :func:`_flow_continuity_start`).
        H: its film (units a^2/R), held fixed.
        h: grid spacing (units a).
        prob: the two-phase problem (density law with ``twophase_p_scale``, ``p_floor`` at
            vacuum, ``neumann_outlet``).
        p_fixed: points with P0 above this are held (units pH).
        tol: convergence on max |residual| relative to max |wedge term|.
    """
    ny, nx = P0.shape
    if P_start is None:
        P = _flow_continuity_start(P0, H, p_fixed, prob)
    else:  # the free points from P_start, the pressurised zone from P0
        P = np.where(P0 > p_fixed, P0, np.maximum(P_start, prob.p_floor))
    interior = np.zeros(P.shape, dtype=bool)
    interior[1:-1, 1:-1] = True  # with a zero-gradient outlet the last column is a ghost
    free = interior & (P0 <= p_fixed)
    r = np.zeros_like(P)
    wedge = np.zeros_like(P)
    f0 = np.zeros_like(P)
    def evaluate(P):
        rho, drho, eps = _coefficients(P, H, prob)
        residual(P, rho * H, eps, f0, h, h, r, wedge)
        # active set: at vacuum where the equation would pull P lower still
        unknown = free & ~((P <= prob.p_floor) & (r > 0.0))
        merit = float(np.sqrt(np.sum(r[unknown] ** 2)))
        return rho, drho, eps, unknown, merit

    def project(P):
        P = np.maximum(P, prob.p_floor)
        if prob.neumann_outlet:
            P[:, -1] = P[:, -2]
        return P

    res = np.inf
    rho, drho, eps, unknown, merit = evaluate(P)
    scale = float(np.abs(wedge[free]).max()) or 1.0
    for it in range(1, max_iter + 1):
        res = float(np.abs(r[unknown]).max()) / scale if unknown.any() else 0.0
        if res < tol:
            return SubAmbientResult(P=P, converged=True, iterations=it - 1, residual=res)
        J = _jacobian(P, H, rho, drho, eps, h, unknown, _eps_slope(P, H, drho, prob))
        step = np.zeros_like(P)
        step[unknown] = spla.spsolve(J.tocsc(), r[unknown])
        # backtracking on the residual norm (the density law has a kink at ambient)
        for damping in (1.0, 0.5, 0.25, 0.125, 0.0625):
            trial = project(P + damping * step)
            t_rho, t_drho, t_eps, t_unknown, t_merit = evaluate(trial)
            if t_merit < merit:
                break
        P, rho, drho, eps, unknown, merit = trial, t_rho, t_drho, t_eps, t_unknown, t_merit
    res = float(np.abs(r[unknown]).max()) / scale if unknown.any() else 0.0
    return SubAmbientResult(P=P, converged=res < tol, iterations=max_iter, residual=res)
