"""The starved inlet of the EHL precalc: film content (Elrod-Adams type) or a moved meniscus.

Two ways to say how much oil reaches the contact (dimensionless, Venner-Lubrecht units: x, y
in a, films in a^2/R):

* an inlet layer ``H_oil``: the oil carried in through the domain's inlet x = x_min, both
  surfaces together, as a gap height. Where the pressure is zero the gap is only partly
  filled: a fraction theta (the film content) of it holds oil, and the Couette flux
  rho theta H u is conserved along x (Reynolds' equation with the wedge term
  d(rho theta H)/dX; theta = 1 wherever the pressure builds). At the inlet
  theta = min(1, H_oil / H). Upstream of X = ``theta_x_max`` (0: the contact centre) the
  film content is the unknown at every zero-pressure point; downstream, the classic
  Reynolds cavitation of the flooded solver holds.
* a meniscus at X = ``x_meniscus``: the pressure is held at zero upstream of it (the inlet
  boundary moved downstream), theta = 1 everywhere.

The film content is marched along each X-line, from the inlet downstream, from the discrete
Reynolds equation at the zero-pressure points (the same upstream-weighted wedge as
:mod:`ehlfoam.contact.reynolds`), so that the residual is zero there; a point whose content
would exceed 1 is left to the pressure relaxation. Points with theta < 1 are held at
P = 0 (``dry``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["march_theta", "meniscus_mask", "meniscus_x_on_centreline", "update_inlet"]


@njit(cache=True)
def march_theta(P, rhoH, eps, f, hx, q_in, i_end, p_floor, theta, dry):
    """Film content theta and the dry mask of one level, in place.

    Args:
        P, rhoH, eps, f: pressure, rho H (theta not included), Poiseuille coefficient and the
            right-hand side (FAS) on the level, indexed [j, i].
        hx: grid spacing (units a).
        q_in: the inlet flux rho theta H at X = x_min (rho = 1 there: H_oil).
        i_end: the march covers the columns 0 .. i_end - 1; theta = 1 beyond.
        p_floor: the cavitation pressure (a point above it is pressurised: theta = 1).
        theta, dry: outputs (float, bool arrays of P's shape).
    """
    ny, nx = P.shape
    hx2 = hx * hx
    for j in range(ny):
        for i in range(nx):
            theta[j, i] = 1.0
            dry[j, i] = False
    for j in range(ny):
        t0 = q_in / rhoH[j, 0]
        theta[j, 0] = t0 if t0 < 1.0 else 1.0
        q_m1 = theta[j, 0] * rhoH[j, 0]
        q_m2 = q_m1
        for i in range(1, i_end):
            if P[j, i] > p_floor:
                q = rhoH[j, i]
            else:
                pois = 0.0
                if 0 < j < ny - 1:
                    e0 = eps[j, i]
                    pois = (0.5 * (eps[j, i - 1] + e0) * (P[j, i - 1] - P[j, i])
                            + 0.5 * (eps[j, i + 1] + e0) * (P[j, i + 1] - P[j, i])
                            + 0.5 * (eps[j - 1, i] + e0) * (P[j - 1, i] - P[j, i])
                            + 0.5 * (eps[j + 1, i] + e0) * (P[j + 1, i] - P[j, i])) / hx2
                    pois -= f[j, i]
                # the wedge c1 q_i + c2 q_i-1 + c3 q_i-2 = hx (Poiseuille - f): residual 0
                if i >= 2:
                    q = (hx * pois + 2.0 * q_m1 - 0.5 * q_m2) / 1.5
                else:
                    q = hx * pois + q_m1
                t = q / rhoH[j, i]
                if t < 1.0:
                    if t < 0.0:
                        t = 0.0
                    theta[j, i] = t
                    dry[j, i] = True
                    q = t * rhoH[j, i]
                else:
                    q = rhoH[j, i]
            q_m2 = q_m1
            q_m1 = q


def meniscus_mask(x: np.ndarray, ny: int, x_meniscus: float) -> np.ndarray:
    """The points upstream of the meniscus X < ``x_meniscus`` (units a) on a level with
    X-axis ``x`` and ``ny`` rows: held at P = 0."""
    return np.broadcast_to(x[None, :] < x_meniscus - 1e-12, (ny, x.size)).copy()


def meniscus_x_on_centreline(x: np.ndarray, y: np.ndarray, P: np.ndarray,
                             theta: np.ndarray | None) -> float | None:
    """The inlet meniscus on Y = 0 (units a): the first X from the inlet where the gap is
    full (theta = 1) and stays full up to the first pressurised point, or the first
    pressurised point when theta is not given. None if the line never pressurises."""
    j = int(np.argmin(np.abs(y)))
    pressurised = np.nonzero(P[j] > 0.0)[0]
    if pressurised.size == 0:
        return None
    first = int(pressurised[0])
    if theta is None:
        return float(x[first])
    k = first
    while k > 0 and theta[j, k - 1] >= 1.0:
        k -= 1
    return float(x[k])


def update_inlet(level, P, H, rho, eps, f, prob) -> None:
    """A multigrid level's film content ``level.theta`` and dry points ``level.dry`` at
    pressure P (film H, density rho, Poiseuille coefficient eps, right-hand side f) for the
    problem's starved inlet; nothing for a flooded one, and the layer's theta only where the
    level marches (``level.march``; a coarse level of a cycle may keep the fine's)."""
    if prob.inlet_layer is not None and level.march:
        march_theta(P, rho * H, eps, f, level.h, prob.inlet_layer,
                    int(np.searchsorted(level.x, prob.theta_x_max)), prob.p_floor,
                    level.theta, level.dry)
    elif prob.inlet_meniscus_x is not None:
        level.dry = meniscus_mask(level.x, level.ny, prob.inlet_meniscus_x)
