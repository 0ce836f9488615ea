"""Hertz theory, Moes dimensionless groups and classic film-thickness formulas.

All inputs and outputs are SI unless the name says otherwise. The conventions are those of
the reference (``U = eta0 u / (E' R)`` with u the mean rolling speed, ``W = F / (E' R^2)``,
``G = alpha E'``, Moes ``M = W (2U)^-3/4``, ``L = G (2U)^1/4``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Contact:
    """Dry Hertzian circular contact and the EHL dimensionless groups.

    Attributes:
        load: normal load F [N].
        radius: reduced radius of curvature R [m].
        modulus: reduced modulus E' [Pa] (2/E' = (1-nu1^2)/E1 + (1-nu2^2)/E2).
        speed: mean rolling speed u [m/s].
        eta0: ambient viscosity [Pa s].
        alpha: pressure-viscosity coefficient [1/Pa].
    """

    load: float
    radius: float
    modulus: float
    speed: float
    eta0: float
    alpha: float

    @property
    def a(self) -> float:
        """Hertzian contact radius a = (3 F R / (2 E'))^(1/3) [m]."""
        return (3.0 * self.load * self.radius / (2.0 * self.modulus)) ** (1.0 / 3.0)

    @property
    def p_hertz(self) -> float:
        """Hertzian maximum pressure pH = 3 F / (2 pi a^2) [Pa]."""
        return 3.0 * self.load / (2.0 * math.pi * self.a**2)

    @property
    def U(self) -> float:
        return self.eta0 * self.speed / (self.modulus * self.radius)

    @property
    def W(self) -> float:
        return self.load / (self.modulus * self.radius**2)

    @property
    def G(self) -> float:
        return self.alpha * self.modulus

    @property
    def M(self) -> float:
        """Moes load parameter."""
        return self.W * (2.0 * self.U) ** -0.75

    @property
    def L(self) -> float:
        """Moes lubricant parameter."""
        return self.G * (2.0 * self.U) ** 0.25

    @property
    def lam(self) -> float:
        """Reynolds-equation coefficient lambda = 12 eta0 u R^2 / (a^3 pH) (dimensionless)."""
        return 12.0 * self.eta0 * self.speed * self.radius**2 / (self.a**3 * self.p_hertz)

    @property
    def film_scale(self) -> float:
        """Film thickness scale a^2 / R [m]: h = H a^2 / R."""
        return self.a**2 / self.radius

    def moes_film(self, h: float) -> float:
        """Moes dimensionless film h/R (2U)^-1/2 of a film h [m]."""
        return h / self.radius * (2.0 * self.U) ** -0.5


def contact_from_moes(M: float, L: float, *, modulus: float = 2.26e11, radius: float = 0.01,
                      eta0: float = 0.04, U: float = 1e-11) -> Contact:
    """An SI contact realising given Moes (M, L).

    A fixed reference steel-on-steel geometry and oil (E', R, eta0) and speed parameter U are
    used; the load follows from M and the pressure-viscosity coefficient from L (L = 0 gives
    an isoviscous oil).
    """
    W = M * (2.0 * U) ** 0.75
    G = L * (2.0 * U) ** -0.25
    return Contact(load=W * modulus * radius**2, radius=radius, modulus=modulus,
                   speed=U * modulus * radius / eta0, eta0=eta0, alpha=G / modulus)


def hamrock_dowson(c: Contact, k: float = 1.0) -> tuple[float, float]:
    """Hamrock-Dowson (1977) central and minimum film (hc, hmin) [m] for ellipticity k."""
    hc = 2.69 * c.U**0.67 * c.G**0.53 * c.W**-0.067 * (1 - 0.61 * math.exp(-0.73 * k))
    hmin = 3.63 * c.U**0.68 * c.G**0.49 * c.W**-0.073 * (1 - math.exp(-0.68 * k))
    return hc * c.radius, hmin * c.radius


def nijenbanning_moes_hc(M: float, L: float, D: float = 1.0) -> float:
    """Central film of Nijenbanning, Venner & Moes (Wear 176, 1994), Moes units.

    Returns H_c = hc/R (2U)^-1/2 for Moes M, L and the ratio of reduced radii D = Ry/Rx
    (D = 1: circular contact). The formula blends the four asymptotes: rigid-isoviscous
    (RI), elastic-isoviscous (EI), rigid-piezoviscous (RP) and elastic-piezoviscous (EP).
    """
    lnD = math.log(D)
    b = 1.0 + 0.006 * lnD + 0.63 * D ** (4.0 / 7.0)
    h_ri = 145.0 * (1.0 + 0.796 * D ** (14.0 / 15.0)) ** (-15.0 / 7.0) * D**-1 * M**-2
    h_ei = 3.18 * b ** (-14.0 / 25.0) * D ** (-1.0 / 15.0) * M ** (-2.0 / 15.0)
    h_rp = 1.29 * (1.0 + 0.691 * D) ** (-2.0 / 3.0) * L ** (2.0 / 3.0)
    h_ep = 1.48 * b ** (-7.0 / 20.0) * D ** (-1.0 / 24.0) * M ** (-1.0 / 12.0) * L**0.75
    s = 1.5 * (1.0 + math.exp(-1.2 * h_ei / h_ri))
    iso = (h_ri**1.5 + (h_ei**-4 + 0.1**4) ** (-3.0 / 8.0)) ** (2.0 * s / 3.0)
    if L > 0:
        piezo = (h_rp**-8 + h_ep**-8) ** (-s / 8.0)
    else:
        piezo = 0.0
    return (iso + piezo) ** (1.0 / s)


def moes_to_hertz_film(H_moes: float, M: float) -> float:
    """Convert a Moes film H_M to the Hertz-scaled film H = h R / a^2: H = H_M (3M/2)^-2/3."""
    return H_moes * (1.5 * M) ** (-2.0 / 3.0)
