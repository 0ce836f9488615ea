"""An oil bridge between the rolling walls on y = 0: where its menisci rest, in theory.

The references the strip cases (:mod:`ehlfoam.case.strip`) are measured against, in the
gap-averaged (Reynolds) limit of a bridge that does not vary across y:

- a meniscus receding from walls that move at u lays, on both walls together, Landau-Levich's
  share of the gap (:func:`~ehlfoam.thinfilm.problem.landau_levich`); a bridge fed at u * film
  rests where those films carry the feed away, at the gap film / LL (:func:`x_at_gap`);
- with both walls moving at -u towards a reservoir at ambient pressure, the bridge's
  pressure falls from the reservoir to its meniscus by the walls' drag,
  int 12 eta u / h^2 dx (:func:`bridge_balance`), which at rest equals the meniscus's
  capillary jump sigma (cos theta + cos(theta + beta)) / h (beta: the ball's slope there);
  so where the meniscus rests says the apparent angle theta it has a gap's size away from
  the wall (:func:`angle_at_meniscus`, :func:`meniscus_for_angle`), which Cox-Voinov relates
  to the static angle and a slip length (:func:`cox_voinov`).

SI units: lengths in m, pressures in Pa, angles in degrees where named ``_deg``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from scipy.integrate import cumulative_trapezoid
from scipy.optimize import brentq

from ehlfoam.spec.case import CaseSpec
from ehlfoam.spec.ladder import cox_voinov

__all__ = ["BridgeBalance", "angle_at_meniscus", "bridge_balance", "cox_voinov",
           "meniscus_for_angle", "x_at_gap"]

Gap = Callable[[np.ndarray, np.ndarray], np.ndarray]


class BridgeBalance(NamedTuple):
    """The bridge on y = 0 at 4001 points: x [m], gap h [m], its slope dh/dx [-] and the
    pressure [Pa, positive] the walls' drag takes off from the reservoir to each x."""

    x: np.ndarray
    h: np.ndarray
    slope: np.ndarray
    drop: np.ndarray


def bridge_balance(spec: CaseSpec, gap: Gap, x_in: float, x_out: float,
                   precursor: float = 0.0) -> BridgeBalance:
    """The balance of a bridge from the reservoir at x_in to x_out [m] with both walls at -u:
    its pressure drop int 12 eta u / h^2 dx; with a precursor layer [m] on each wall, whose oil
    the bridge passes on to the reservoir, int 12 eta u (h - 2 precursor) / h^3 dx. With a
    Navier slip length lambda on both walls (physics.wall_slip_length) the walls' drag is a
    plug that carries no shear, and the pressure drives (1 + 6 lambda / h) times the flux it
    drives between no-slip walls, so the drop is that much smaller."""
    x = np.linspace(x_in, x_out, 4001)
    h = gap(x, np.zeros_like(x))
    slip = 1.0 + 6.0 * spec.physics.wall_slip_length / h
    drop = cumulative_trapezoid(12.0 * spec.oil_viscosity * spec.speed * (h - 2 * precursor)
                                / (h**3 * slip), x, initial=0.0)
    return BridgeBalance(x, h, np.gradient(h, x), drop)


def meniscus_for_angle(spec: CaseSpec, balance: BridgeBalance, theta_deg: float) -> float:
    """Where [m] the bridge's meniscus rests for the apparent angle theta [deg]: the first x
    where the drag's drop reaches the capillary jump; NaN if it nowhere does."""
    t = np.radians(theta_deg)
    jump = (spec.physics.surface_tension * (np.cos(t) + np.cos(t + np.arctan(balance.slope)))
            / balance.h)
    k = np.flatnonzero(balance.drop >= jump)
    return float(balance.x[k[0]]) if len(k) else float("nan")


def angle_at_meniscus(spec: CaseSpec, balance: BridgeBalance, x_m: float) -> float:
    """The apparent angle [deg] that holds the bridge's meniscus at rest at x_m [m]; NaN where
    no angle from 0 to a right angle with the ball does."""
    hm, beta, dp = (np.interp(x_m, balance.x, v)
                    for v in (balance.h, np.arctan(balance.slope), balance.drop))
    sigma = spec.physics.surface_tension

    def g(t: float) -> float:
        return sigma * (np.cos(t) + np.cos(t + beta)) / hm - dp
    lo, hi = 0.0, np.pi / 2 - beta
    return float(np.degrees(brentq(g, lo, hi))) if g(lo) * g(hi) < 0 else float("nan")


def x_at_gap(gap: Gap, h: float, x_lo: float, x_hi: float) -> float:
    """The x [m] on y = 0 between x_lo and x_hi [m] where the gap is h [m] (where a receding
    meniscus laying films of LL h rests); NaN where the gap does not pass h there, or h is
    NaN (no film measured)."""
    def g(x: float) -> float:
        return float(gap(np.array([x]), np.array([0.0]))[0]) - h
    if not np.isfinite(h) or not g(x_lo) * g(x_hi) <= 0:
        return float("nan")
    return float(brentq(g, x_lo, x_hi, xtol=1e-12))
