"""Discrete Reynolds operator and its line relaxation (numba kernels).

Dimensionless steady Reynolds equation of the circular point contact in pure rolling
(Venner & Lubrecht, *Multilevel Methods in Lubrication*, 2000):

    d/dX(eps dP/dX) + d/dY(eps dP/dY) - d(rho H)/dX = f,   eps = rho H^3 / (eta lambda)

Second-order central differences for the Poiseuille terms, second-order upstream
differences for the wedge term (first order next to the inlet boundary). Arrays are indexed
``[j, i]`` with i along X (the rolling direction) and j along Y.

Relaxation: X-line relaxation that is Gauss-Seidel where the Poiseuille term dominates
(eps / h^2 >= switch) and distributive Jacobi (changes distributed as d - (neighbours)/4)
where it degenerates, each line a Newton step on a pentadiagonal system that includes the
near elastic influence coefficients along the line.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange


@njit(cache=True)
def _wedge_c(i):
    if i >= 2:
        return 1.5, -2.0, 0.5
    return 1.0, -1.0, 0.0


@njit(cache=True)
def _residual_at(P, rhoH, eps, f, j, i, hx2, hy2, hx):
    e0 = eps[j, i]
    exm = 0.5 * (eps[j, i - 1] + e0)
    exp_ = 0.5 * (eps[j, i + 1] + e0)
    eym = 0.5 * (eps[j - 1, i] + e0)
    eyp = 0.5 * (eps[j + 1, i] + e0)
    p0 = P[j, i]
    pois = (exm * (P[j, i - 1] - p0) + exp_ * (P[j, i + 1] - p0)) / hx2 + (
        eym * (P[j - 1, i] - p0) + eyp * (P[j + 1, i] - p0)
    ) / hy2
    c1, c2, c3 = _wedge_c(i)
    wedge = c1 * rhoH[j, i] + c2 * rhoH[j, i - 1]
    if c3 != 0.0:
        wedge += c3 * rhoH[j, i - 2]
    return f[j, i] - (pois - wedge / hx), wedge / hx


def _residual(P, rhoH, eps, f, hx, hy, r, wedge):
    """Residual r = f - L(P) and the wedge term at interior points (boundaries 0)."""
    ny, nx = P.shape
    hx2, hy2 = hx * hx, hy * hy
    r[:] = 0.0
    wedge[:] = 0.0
    for j in prange(1, ny - 1):
        for i in range(1, nx - 1):
            rr, ww = _residual_at(P, rhoH, eps, f, j, i, hx2, hy2, hx)
            r[j, i] = rr
            wedge[j, i] = ww
    return r


#: :func:`_residual` on one thread and on numba's threads (large grids)
residual = njit(cache=True)(_residual)
residual_parallel = njit(parallel=True, cache=True)(_residual)


@njit(cache=True)
def _penta_solve(a, b, c, d, e, rhs, x):
    """Solve a pentadiagonal system without pivoting.

    Row m: a[m] x[m-2] + b[m] x[m-1] + c[m] x[m] + d[m] x[m+1] + e[m] x[m+2] = rhs[m].
    The arrays are overwritten.
    """
    n = c.shape[0]
    for m in range(n - 1):
        piv = c[m]
        # eliminate x[m] from row m+1
        f1 = b[m + 1] / piv
        c[m + 1] -= f1 * d[m]
        d[m + 1] -= f1 * e[m]
        rhs[m + 1] -= f1 * rhs[m]
        b[m + 1] = 0.0
        if m + 2 < n:
            f2 = a[m + 2] / piv
            b[m + 2] -= f2 * d[m]
            c[m + 2] -= f2 * e[m]
            rhs[m + 2] -= f2 * rhs[m]
            a[m + 2] = 0.0
    x[n - 1] = rhs[n - 1] / c[n - 1]
    if n >= 2:
        x[n - 2] = (rhs[n - 2] - d[n - 2] * x[n - 1]) / c[n - 2]
    for m in range(n - 3, -1, -1):
        x[m] = (rhs[m] - d[m] * x[m + 1] - e[m] * x[m + 2]) / c[m]


@njit(cache=True, inline="always")
def _line(j, P, H, rho, drho, eps, rhoH, f, hx, K0, Kt, switch, w_gs, p_floor, neumann_out,
          D, deps, point_ja, a, b, c, d, e, rhs, x, gs, frozen, dry):
    """Relax X-line ``j`` (a Newton step on its pentadiagonal system): Gauss-Seidel points
    are updated, distributive-Jacobi changes stored in D. Returns the number of the
    latter."""
    ny, nx = P.shape
    n = nx - 2
    hx2 = hy2 = hx * hx
    n_ja = 0
    for m in range(n):
        i = m + 1
        rr, ww = _residual_at(P, rhoH, eps, f, j, i, hx2, hy2, hx)
        rhs[m] = rr
        # distributive Jacobi only where the distribution stays inside the pressurised
        # zone: near the cavitation boundary its zero-sum property would be clipped away
        gs[m] = eps[j, i] >= switch * hx2 or (
            P[j, i] <= p_floor or P[j, i - 1] <= p_floor or P[j, i + 1] <= p_floor
            or P[j - 1, i] <= p_floor or P[j + 1, i] <= p_floor)
        frozen[m] = (P[j, i] <= p_floor and rr > 0.0) or dry[j, i]
    for m in range(n):
        i = m + 1
        a[m] = 0.0
        b[m] = 0.0
        c[m] = 0.0
        d[m] = 0.0
        e[m] = 0.0
        if frozen[m]:
            c[m] = 1.0
            rhs[m] = 0.0
            continue
        e0 = eps[j, i]
        exm = 0.5 * (eps[j, i - 1] + e0) / hx2
        exp_ = 0.5 * (eps[j, i + 1] + e0) / hx2
        ey = 0.5 * (eps[j - 1, i] + 2.0 * e0 + eps[j + 1, i]) / hy2
        diag = -(exm + exp_) - ey
        if neumann_out and i == nx - 2:
            diag += exp_
        c1, c2, c3 = _wedge_c(i)
        for off in range(-2, 3):
            mc = m + off
            if mc < 0 or mc >= n or frozen[mc]:
                continue
            col = i + off
            v = 0.0
            if gs[mc]:
                if off == 0:
                    v += diag
                    # viscosity derivative of the own eps in the face coefficients
                    p0 = P[j, i]
                    lap = 0.5 * deps[j, i] * (
                        (P[j, i - 1] + P[j, i + 1] - 2.0 * p0) / hx2
                        + (P[j - 1, i] + P[j + 1, i] - 2.0 * p0) / hy2)
                    if lap < 0.0:
                        v += lap
                elif off == -1:
                    v += exm
                elif off == 1:
                    v += exp_
                v -= c1 * rho[j, i] * K0[abs(i - col)] / hx
                v -= c2 * rho[j, i - 1] * K0[abs(i - 1 - col)] / hx
                if c3 != 0.0:
                    v -= c3 * rho[j, i - 2] * K0[abs(i - 2 - col)] / hx
                # density derivative of the wedge term, first-order upwind: the
                # second-order (1.5, -2, 0.5) weights make the line system amplify
                # errors downstream where d(rho)/dP is large (two-phase region)
                if off == 0:
                    v -= H[j, i] * drho[j, i] / hx
                elif off == -1:
                    v += H[j, i - 1] * drho[j, i - 1] / hx
            elif off == 0 or not point_ja:
                # distribution: +1 at col, -1/4 at col +- 1 and at (j +- 1, col)
                if off == 0:
                    v += diag - 0.25 * (exm + exp_) - 0.25 * ey
                elif off == -1:
                    v += exm - 0.25 * diag
                elif off == 1:
                    v += exp_ - 0.25 * diag
                elif off == -2:
                    v -= 0.25 * exm
                else:
                    v -= 0.25 * exp_
                v -= c1 * rho[j, i] * Kt[abs(i - col)] / hx
                v -= c2 * rho[j, i - 1] * Kt[abs(i - 1 - col)] / hx
                if c3 != 0.0:
                    v -= c3 * rho[j, i - 2] * Kt[abs(i - 2 - col)] / hx
                # local density derivative of the wedge term (first-order upwind),
                # distributed
                for q in range(2):
                    cq = 1.0 if q == 0 else -1.0
                    iq = i - q
                    dq = iq - col
                    wq = 1.0 if dq == 0 else (-0.25 if (dq == 1 or dq == -1) else 0.0)
                    if wq != 0.0:
                        v -= cq * H[j, iq] * drho[j, iq] * wq / hx
            if off == -2:
                a[m] = v
            elif off == -1:
                b[m] = v
            elif off == 0:
                c[m] = v
            elif off == 1:
                d[m] = v
            else:
                e[m] = v
    _penta_solve(a, b, c, d, e, rhs, x)
    for m in range(n):
        i = m + 1
        if frozen[m]:
            continue
        if gs[m]:
            v = P[j, i] + w_gs * x[m]
            if v < p_floor:
                v = p_floor
            P[j, i] = v
        else:
            D[j, i] = x[m]
            n_ja += 1
    if neumann_out:
        P[j, nx - 1] = P[j, nx - 2]
    return n_ja


def _relax(P, H, rho, drho, eps, f, hx, hy, K0, K1, switch, w_gs, w_ja, p_floor, neumann_out, D,
           deps, dry, point_ja=True, zebra=False):
    """One X-line relaxation sweep; updates P in place.

    Args:
        P, H, rho, drho, eps, f: pressure, film, density and its P-derivative, Poiseuille
            coefficient, right-hand side; H, rho, drho, eps are frozen during the sweep.
        hx, hy: grid spacings (equal: the kernels assume a square grid).
        K0, K1: influence coefficients K[0, k], K[1, k] for k = 0..5 (along the line and
            the neighbouring line).
        switch: Gauss-Seidel where eps / hx^2 >= switch, distributive Jacobi elsewhere.
        w_gs, w_ja: under-relaxation factors.
        p_floor: cavitation pressure: P >= p_floor is enforced (complementarity; 0 for
            the classic p >= 0 condition, absolute zero for the two-phase model).
        neumann_out: zero-gradient outlet (P[:, -1] = P[:, -2]) instead of P = 0.
        D: work array (Jacobi changes).
        deps: d(eps)/dP through the viscosity (-eps d ln(eta)/dP). At Gauss-Seidel points
            its Poiseuille contribution enters the diagonal where it strengthens it (just
            behind the pressure spike, where the pressure falls steeply and eps grows by
            orders of magnitude within a cell, the frozen-eps Newton step overshoots).
        dry: points held at P = p_floor whatever their residual (a starved inlet: the
            film-content region, or upstream of a prescribed meniscus).
        zebra: the odd lines first, then the even ones (each half in parallel), instead
            of the lines in order.
    Returns:
        The number of distributive-Jacobi points in the sweep.
    """
    ny, nx = P.shape
    n = nx - 2
    rhoH = rho * H
    Kt = np.empty(6)
    for k in range(5):
        km = K0[abs(k - 1)]
        Kt[k] = K0[k] - 0.25 * (km + K0[k + 1] + 2.0 * K1[k])
    Kt[5] = 0.0
    D[:] = 0.0
    n_ja = 0
    if zebra:
        for first in range(1, 3):
            for jj in prange((ny - 1 - first + 1) // 2):
                j = first + 2 * jj
                n_ja += _line(j, P, H, rho, drho, eps, rhoH, f, hx, K0, Kt, switch, w_gs,
                              p_floor, neumann_out, D, deps, point_ja, np.empty(n),
                              np.empty(n), np.empty(n), np.empty(n), np.empty(n),
                              np.empty(n), np.empty(n), np.empty(n, dtype=np.bool_),
                              np.empty(n, dtype=np.bool_), dry)
    else:
        a, b, c, d, e = np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n)
        rhs, x = np.empty(n), np.empty(n)
        gs, frozen = np.empty(n, dtype=np.bool_), np.empty(n, dtype=np.bool_)
        for j in range(1, ny - 1):
            n_ja += _line(j, P, H, rho, drho, eps, rhoH, f, hx, K0, Kt, switch, w_gs, p_floor,
                          neumann_out, D, deps, point_ja, a, b, c, d, e, rhs, x, gs, frozen,
                          dry)
    if n_ja > 0:
        # the distribution d at (j, i) and -d/4 at its four neighbours (interior points
        # only), gathered point by point
        for j in prange(1, ny - 1):
            for i in range(1, nx - 1):
                dd = D[j, i] - 0.25 * (D[j, i - 1] + D[j, i + 1] + D[j - 1, i] + D[j + 1, i])
                if dd != 0.0 and not dry[j, i]:
                    v = P[j, i] + w_ja * dd
                    P[j, i] = v if v > p_floor else p_floor
        if neumann_out:
            for j in range(ny):
                P[j, nx - 1] = P[j, nx - 2]
    return n_ja


#: :func:`_relax` on one thread and on numba's threads (zebra ordering only)
relax = njit(cache=True)(_relax)
relax_parallel = njit(parallel=True, cache=True)(_relax)
