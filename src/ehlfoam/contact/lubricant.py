"""Lubricant properties and the pressure laws for viscosity and density (SI units).

The HVI60 table is the reference experiment's (van Emden 2017, thesis table 2.1); its
density is the project's assumed value. Between the tabulated temperatures ln(eta0) and
alpha are interpolated linearly in T; outside the table a named oil is refused.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Roelands reference constants (Roelands 1966): eta_inf = 6.31e-5 Pa s (ln -> -9.67), p0.
ROELANDS_LN_ETA_INF = -9.67
ROELANDS_P0_PA = 1.96e8
#: Largest ln(eta / eta0) evaluated (see PressureLaws.eta).
ETA_LN_CAP = 300.0
#: Dowson-Higginson density constants (Pa).
DH_A_PA = 5.9e8
DH_B = 1.34

#: Tabulated oils: temperature (C) -> (eta0 [Pa s], alpha [1/Pa]); rho0 [kg/m3].
OIL_TABLES: dict[str, dict] = {
    "HVI60": {
        "T_C": (25.0, 40.0, 60.0),
        "eta0_Pa_s": (44.7e-3, 21.6e-3, 10.2e-3),
        "alpha_1_Pa": (2.25e-8, 2.13e-8, 1.97e-8),
        "rho0_kg_m3": 870.0,  # assumed (not in the source)
    },
}


@dataclass(frozen=True)
class Lubricant:
    """Newtonian lubricant at one temperature.

    Attributes:
        eta0: ambient-pressure dynamic viscosity [Pa s].
        alpha: pressure-viscosity coefficient [1/Pa].
        rho0: ambient-pressure density [kg/m3].
        name: label for reports.
    """

    eta0: float
    alpha: float
    rho0: float
    name: str = "custom"

    @property
    def roelands_z(self) -> float:
        """Roelands index z chosen so that d ln(eta)/dp = alpha at p = 0."""
        return self.alpha * ROELANDS_P0_PA / (np.log(self.eta0) - ROELANDS_LN_ETA_INF)


def table_range(name: str) -> tuple[float, float]:
    """Temperature range [C] covered by a tabulated oil."""
    t = OIL_TABLES[name]["T_C"]
    return float(min(t)), float(max(t))


def lubricant_from_table(name: str, temperature_C: float) -> Lubricant:
    """Interpolate a tabulated oil at ``temperature_C`` (ln eta0 and alpha linear in T)."""
    tab = OIL_TABLES[name]
    t = np.asarray(tab["T_C"])
    eta0 = float(np.exp(np.interp(temperature_C, t, np.log(tab["eta0_Pa_s"]))))
    alpha = float(np.interp(temperature_C, t, tab["alpha_1_Pa"]))
    return Lubricant(eta0=eta0, alpha=alpha, rho0=float(tab["rho0_kg_m3"]), name=name)


@dataclass(frozen=True)
class PressureLaws:
    """Dimensionless viscosity and density as functions of P = p / pH.

    Attributes:
        p_hertz: Hertzian pressure pH [Pa] (scales P).
        lubricant: the oil.
        viscosity: "roelands" or "barus".
        density: "dowson-higginson" or "incompressible".
        twophase_p_scale: for the two-phase model, the pressure scale p_s [Pa] of the density
            drop below ambient: rho/rho0 = max(0, 1 + p / p_s) for gauge p < 0, i.e. with
            p_s = p_ambient a gas-oil mixture whose density is proportional to the absolute
            pressure (ideal gas, isothermal), zero at vacuum; None = no two-phase.
    """

    p_hertz: float
    lubricant: Lubricant
    viscosity: str = "roelands"
    density: str = "dowson-higginson"
    twophase_p_scale: float | None = None

    def ln_eta(self, P: np.ndarray) -> np.ndarray:
        """ln(eta / eta0) at dimensionless pressure P, capped at :data:`ETA_LN_CAP`
        (sub-ambient pressures use eta0)."""
        p = np.maximum(P, 0.0) * self.p_hertz
        lub = self.lubricant
        if self.viscosity == "barus":
            ln_eta = lub.alpha * p
        else:
            a = np.log(lub.eta0) - ROELANDS_LN_ETA_INF
            ln_eta = a * ((1.0 + p / ROELANDS_P0_PA) ** lub.roelands_z - 1.0)
        # beyond e^300 the Poiseuille term is zero to machine precision anyway; the cap keeps
        # an intermediate pressure overshoot from turning into inf * 0 = nan
        return np.minimum(ln_eta, ETA_LN_CAP)

    def eta(self, P: np.ndarray) -> np.ndarray:
        """eta / eta0 at dimensionless pressure P (sub-ambient pressures use eta0)."""
        return np.exp(self.ln_eta(P))

    def dln_eta_dP(self, P: np.ndarray) -> np.ndarray:
        """d ln(eta / eta0) / dP at dimensionless pressure P (0 below ambient and beyond the
        cap :data:`ETA_LN_CAP`)."""
        p = np.maximum(P, 0.0) * self.p_hertz
        lub = self.lubricant
        if self.viscosity == "barus":
            slope = np.full_like(p, lub.alpha * self.p_hertz)
        else:
            a = np.log(lub.eta0) - ROELANDS_LN_ETA_INF
            z = lub.roelands_z
            slope = a * z * (1.0 + p / ROELANDS_P0_PA) ** (z - 1.0) * self.p_hertz / ROELANDS_P0_PA
        return np.where((P > 0.0) & (self.ln_eta(P) < ETA_LN_CAP), slope, 0.0)

    def rho(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(rho / rho0, d(rho/rho0)/dP) at dimensionless pressure P."""
        ph = self.p_hertz
        p = np.maximum(P, 0.0) * ph
        if self.density == "incompressible":
            rho = np.ones_like(p)
            drho = np.zeros_like(p)
        else:
            rho = (DH_A_PA + DH_B * p) / (DH_A_PA + p)
            drho = ph * (DH_B - 1.0) * DH_A_PA / (DH_A_PA + p) ** 2
        if self.twophase_p_scale is not None:
            neg = P < 0.0
            slope = ph / self.twophase_p_scale
            if np.any(neg):
                rho = np.where(neg, np.maximum(1.0 + P * slope, 0.0), rho)
                drho = np.where(neg, slope, drho)
        return rho, drho
