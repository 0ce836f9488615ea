"""Lubricant properties and the pressure laws for viscosity and density (SI units).

The HVI60 table is the reference experiment's (van Emden 2017, thesis table 2.1); its
density is the project's assumed value. Between the tabulated temperatures ln(eta0) and
alpha are interpolated linearly in T; outside the table a named oil is refused.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit, prange

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

    def kernel_params(self) -> np.ndarray:
        """The laws as the parameter vector of the numba kernels (:func:`coefficients`)."""
        lub = self.lubricant
        roelands = self.viscosity != "barus"
        return np.array([
            self.p_hertz,
            1.0 if roelands else 0.0,
            lub.alpha,
            np.log(lub.eta0) - ROELANDS_LN_ETA_INF,
            lub.roelands_z if roelands else 0.0,
            0.0 if self.density == "incompressible" else 1.0,
            self.p_hertz / self.twophase_p_scale if self.twophase_p_scale is not None else 0.0,
        ])

    def evaluate(self, P: np.ndarray, H: np.ndarray | None = None, lam: float = 1.0):
        """(rho, drho, eps, deps, ln_eta) at dimensionless pressure P and film H (see
        :func:`coefficients`; without H, eps and deps are 0)."""
        P = np.ascontiguousarray(P, dtype=float)
        H = np.zeros_like(P) if H is None else np.ascontiguousarray(H, dtype=float)
        out = [np.empty_like(P) for _ in range(5)]
        P2, H2 = P.reshape(1, -1) if P.ndim != 2 else P, H.reshape(1, -1) if H.ndim != 2 else H
        coefficients(P2, H2, lam, self.kernel_params(), *(o.reshape(P2.shape) for o in out))
        return tuple(out)

    def ln_eta(self, P: np.ndarray) -> np.ndarray:
        """ln(eta / eta0) at dimensionless pressure P, capped at :data:`ETA_LN_CAP`
        (sub-ambient pressures use eta0): beyond e^300 the Poiseuille term is zero to machine
        precision anyway; the cap keeps an intermediate pressure overshoot from turning into
        inf * 0 = nan."""
        return self._viscosity(P)[0]

    def eta(self, P: np.ndarray) -> np.ndarray:
        """eta / eta0 at dimensionless pressure P (sub-ambient pressures use eta0)."""
        return np.exp(self.ln_eta(P))

    def dln_eta_dP(self, P: np.ndarray) -> np.ndarray:
        """d ln(eta / eta0) / dP at dimensionless pressure P (0 below ambient and beyond the
        cap :data:`ETA_LN_CAP`)."""
        return self._viscosity(P)[1]

    def max_dln_eta_dP(self, P_max: float) -> float:
        """The largest d ln(eta / eta0) / dP over 0 <= P <= ``P_max``: alpha pH for Barus and
        for Roelands with z <= 1 (its slope falls with pressure from alpha at ambient), else
        the largest on 1024 steps (monotone up to the cap; 1 % margin)."""
        lub = self.lubricant
        if self.viscosity == "barus" or lub.roelands_z <= 1.0:
            return lub.alpha * self.p_hertz
        return 1.01 * float(self.dln_eta_dP(np.linspace(0.0, max(P_max, 0.0), 1025)).max())

    def _viscosity(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        P = np.ascontiguousarray(P, dtype=float)
        ln_eta, dln = np.empty_like(P), np.empty_like(P)
        viscosity(P.reshape(-1), self.kernel_params(), ln_eta.reshape(-1), dln.reshape(-1))
        return ln_eta, dln

    def rho(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(rho / rho0, d(rho/rho0)/dP) at dimensionless pressure P."""
        rho, drho, _, _, _ = self.evaluate(P)
        return rho, drho


# --- numba kernels: the laws evaluated point by point, in one pass --------------------------
@njit(cache=True, inline="always")
def _viscosity_at(P, params):
    """(ln(eta / eta0), d ln(eta / eta0) / dP) at one dimensionless pressure: Barus or
    Roelands, eta0 below ambient, capped at :data:`ETA_LN_CAP` (slope 0 there)."""
    ph = params[0]
    p = max(P, 0.0) * ph
    if params[1] == 0.0:
        lne = params[2] * p
        dln = params[2] * ph
    else:
        base = 1.0 + p / ROELANDS_P0_PA
        pw = base ** params[4]
        lne = params[3] * (pw - 1.0)
        dln = params[3] * params[4] * pw / base * ph / ROELANDS_P0_PA
    if lne >= ETA_LN_CAP:
        return ETA_LN_CAP, 0.0
    if P <= 0.0:
        dln = 0.0
    return lne, dln


@njit(cache=True, inline="always")
def ln_eta_at(P, params):
    """ln(eta / eta0) at one dimensionless pressure."""
    return _viscosity_at(P, params)[0]


@njit(cache=True)
def viscosity(P, params, ln_eta, dln):
    """ln(eta / eta0) and its P-derivative at every point of the 1-D array P."""
    for k in range(P.shape[0]):
        ln_eta[k], dln[k] = _viscosity_at(P[k], params)


def _coefficients(P, H, lam, params, rho, drho, eps, deps, ln_eta):
    """Density, its P-derivative, the Poiseuille coefficient eps = rho max(H, 0)^3 /
    (eta lambda), its viscosity derivative deps = -eps d ln(eta)/dP and ln(eta / eta0) at
    every point, written into the output arrays (the laws of the :class:`PressureLaws` whose
    :meth:`~PressureLaws.kernel_params` is ``params``)."""
    ny, nx = P.shape
    ph = params[0]
    slope2 = params[6]
    for j in prange(ny):
        for i in range(nx):
            Pv = P[j, i]
            lne, dln = _viscosity_at(Pv, params)
            if params[5] == 0.0:
                r, dr = 1.0, 0.0
            else:
                p = max(Pv, 0.0) * ph
                r = (DH_A_PA + DH_B * p) / (DH_A_PA + p)
                dr = ph * (DH_B - 1.0) * DH_A_PA / ((DH_A_PA + p) * (DH_A_PA + p))
            if slope2 != 0.0 and Pv < 0.0:
                r = max(1.0 + Pv * slope2, 0.0)
                dr = slope2
            h = max(H[j, i], 0.0)
            e = r * h * h * h / (np.exp(lne) * lam)
            rho[j, i] = r
            drho[j, i] = dr
            eps[j, i] = e
            deps[j, i] = -e * dln
            ln_eta[j, i] = lne


#: :func:`_coefficients` on one thread and on numba's threads (large grids)
coefficients = njit(cache=True)(_coefficients)
coefficients_parallel = njit(parallel=True, cache=True)(_coefficients)


def limit_viscosity_step(P_old: np.ndarray, P: np.ndarray, laws: PressureLaws,
                         max_step: float, ln_eta_old: np.ndarray | None = None) -> None:
    """Damp a relaxation sweep where it would change the viscosity by more than a factor
    e^max_step; updates the dimensionless pressure ``P`` in place (``ln_eta_old``: the laws'
    ln(eta / eta0) at ``P_old`` where known).

    The line systems hold eps = rho H^3 / (eta lambda) frozen, so where the pressure-viscosity
    product alpha pH is large (Moes L >= 20) a step of a few tenths in P changes eta by orders
    of magnitude and the next sweep overshoots: the pressure spike runs away to
    exp(alpha p) overflow. Scaling the step at such points to |d ln(eta)| = max_step keeps the
    fixed point (the limiter is inactive once the steps are small) and only slows the first
    sweeps of a large-L solve.
    """
    dP_max = float(np.max(np.abs(P - P_old)))
    if dP_max * laws.max_dln_eta_dP(max(float(P.max()), float(P_old.max()))) <= max_step:
        return  # no point can have changed ln(eta) by more than max_step
    if ln_eta_old is None:
        ln_eta_old = laws.ln_eta(P_old)
    d_ln_eta = np.abs(laws.ln_eta(P) - ln_eta_old)
    big = d_ln_eta > max_step
    if np.any(big):
        dP = P[big] - P_old[big]
        P[big] = P_old[big] + dP * (max_step / d_ln_eta[big])
