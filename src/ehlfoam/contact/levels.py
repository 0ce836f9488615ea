"""The multigrid's data: the domain, the solver options, the dimensionless problem and one grid
level of the hierarchy with its FAS data (right-hand side, film correction, load target),
its relaxation sweep and its residual. The cycles that use them: :mod:`ehlfoam.contact.multigrid`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ehlfoam.contact.elastic import Deformation
from ehlfoam.contact.inlet import update_inlet
from ehlfoam.contact.lubricant import PressureLaws, coefficients, coefficients_parallel
from ehlfoam.contact.lubricant import limit_viscosity_step
from ehlfoam.contact.reynolds import relax, relax_parallel, residual, residual_parallel
from ehlfoam.contact.threads import PARALLEL_MIN_POINTS

__all__ = ["LOAD_TARGET", "Domain", "Level", "Problem", "SolverOptions"]

LOAD_TARGET = 2.0 * math.pi / 3.0


@dataclass(frozen=True)
class Domain:
    """Computational domain in units of a and the finest grid size (points per side)."""

    x_min: float
    x_max: float
    y_half: float
    nx: int
    ny: int

    @property
    def h(self) -> float:
        return (self.x_max - self.x_min) / (self.nx - 1)


@dataclass(frozen=True)
class SolverOptions:
    """Multigrid and convergence settings (dimensionless).

    nu1, nu2, gamma: sweeps before and after the coarse-grid correction; 2: W-cycles.
    switch, w_gs, w_ja: Gauss-Seidel where eps / h^2 >= switch, distributive Jacobi
        elsewhere; their under-relaxation factors.
    w_ja_high_L, high_L, w_ja_high_M, high_M: the distributive-Jacobi factor above Moes
        L = ``high_L`` (a sharp pressure spike: 0.5 stalls there, 0.2 does not) and above
        M = ``high_M`` (0.5 lets hc swing by 1 % from cycle to cycle at M 34,000; 0.3 does
        not); elsewhere 0.5 needs half the cycles of 0.2 (M 1000-4000).
    zebra: the odd lines first, then the even ones (parallel; else in order).
    coarsest_min_points: the coarsest grid has at most this many points a side.
    coarse_sweeps, coarse_rounds, h0_gain: the coarsest level is solved by
        ``coarse_rounds`` rounds of ``coarse_sweeps`` sweeps, each round followed by a step
        H0 += gain (load - target) (a quarter of ``h0_gain`` above Moes M 1000): with the
        coarse problem solved, the film constant is right after a cycle or two.
    fmg_cycles, fmg_max_cycles, fmg_change: full-multigrid start, see
        :meth:`MultigridSolver._fmg`.
    tol_load: relative load-balance error to reach.
    film_fraction, film_rel_min, film_rel_max, tol_residual, film_max_residual: the solve
        has converged once the load error is below ``tol_load``, a cycle changes the central
        and the minimum film by less than :meth:`MultigridSolver.film_tolerance` and the
        relative Reynolds residual sum|r| / sum|d(rho H)/dX| is below the larger of
        ``tol_residual`` and ``film_max_residual``: the film, not the residual, is what the
        precalc is for (at M above 10,000 a residual of 3e-5 still leaves hc 0.4 % off).
    residual_only: a residual below which the solve has converged whatever the film does
        (0: never; reference solves set it small).
    max_ln_eta_step: largest change of ln(eta / eta0) one relaxation sweep may make at a
        point (see :func:`limit_viscosity_step`); 0 switches the limiter off.
    limit_correction: hold the coarse-grid correction to the same viscosity-step limit as
        the sweeps (used once a solve stalls).
    stall_window, stall_ratio: the cycles stall when the best residual of the last
        ``stall_window`` cycles is not below ``stall_ratio`` times the best of the window
        before; the solve then goes on with :meth:`stalled` options (once).
    workers: threads of the solve (scipy.fft and the numba kernels); None: the caller's
        numba thread count (:func:`solve_threads`).
    fixed_coarse_theta: a starved inlet's coarse levels take the fine film content fixed
        instead of marching their own (the stalled options set it).
    """

    nu1: int = 2
    nu2: int = 2
    gamma: int = 2
    switch: float = 0.3
    w_gs: float = 0.4
    w_ja: float = 0.5
    w_ja_high_L: float = 0.2
    high_L: float = 15.0
    w_ja_high_M: float = 0.3
    high_M: float = 5000.0
    coarsest_min_points: int = 33
    coarse_sweeps: int = 5
    coarse_rounds: int = 10
    h0_gain: float = 0.05
    fmg_cycles: int = 2
    fmg_max_cycles: int = 8
    fmg_change: float = 0.2
    film_fraction: float = 0.1
    film_rel_min: float = 1e-4
    film_rel_max: float = 1e-3
    film_max_residual: float = 1e-3
    residual_only: float = 0.0
    max_cycles: int = 100
    tol_residual: float = 3e-5
    tol_load: float = 3e-5
    max_ln_eta_step: float = 2.0
    limit_correction: bool = False
    stall_window: int = 8
    stall_ratio: float = 0.7
    workers: int | None = None
    zebra: bool = True
    fixed_coarse_theta: bool = False

    def stalled(self) -> "SolverOptions":
        """Options for the rest of a stalled solve (large L: a limit cycle between the pressure
        spike's side lobes and the coarse-grid correction): half the distributive-Jacobi
        under-relaxation, five more fine sweeps after each coarse-grid correction, and the
        correction itself held to the viscosity-step limit. (A starved inlet's solve is watched
        for a second stall, which fixes the coarse film content: :meth:`_solve`.)"""
        return replace(self, w_ja=0.5 * self.w_ja, nu2=self.nu2 + 5, limit_correction=True,
                       stall_window=0)


@dataclass
class Problem:
    """The dimensionless problem: Reynolds coefficient, pressure laws, boundary options."""

    lam: float
    laws: PressureLaws
    p_floor: float = 0.0
    neumann_outlet: bool = False
    moes_M: float = 100.0
    moes_L: float = 0.0
    #: starved inlet (:mod:`ehlfoam.contact.inlet`): layer at x_min [a^2/R] or meniscus X [a]
    inlet_layer: float | None = None
    inlet_meniscus_x: float | None = None
    theta_x_max: float = 0.0

    @property
    def params(self) -> np.ndarray:
        """The pressure laws' parameter vector for the numba kernels."""
        return self.laws.kernel_params()


class Level:
    """One grid of the hierarchy with its FAS data."""

    def __init__(self, nx: int, ny: int, x0: float, y0: float, h: float, workers: int = 1):
        self.nx, self.ny, self.h = nx, ny, h
        self.x = x0 + h * np.arange(nx)
        self.y = y0 + h * np.arange(ny)
        self.rigid = 0.5 * self.x[None, :] ** 2 + 0.5 * self.y[:, None] ** 2
        self.workers = workers if nx * ny >= PARALLEL_MIN_POINTS else 1
        self.deform = Deformation(nx, ny, h, h, workers=self.workers)
        self._coefficients = coefficients_parallel if self.workers > 1 else coefficients
        self._residual = residual_parallel if self.workers > 1 else residual
        self._relax = relax_parallel if self.workers > 1 else relax
        self.K0 = np.ascontiguousarray(self.deform.kernel[0, :6])
        self.K1 = np.ascontiguousarray(self.deform.kernel[1, :6])
        self.P = np.zeros((ny, nx))
        self.f = np.zeros((ny, nx))
        self.tauW = np.zeros((ny, nx))
        self.load_target = LOAD_TARGET
        self.work = np.zeros((ny, nx))
        self.sweeps = 0  # relaxation sweeps done on this level (work accounting)
        self._coef = [np.empty((ny, nx)) for _ in range(5)]
        self._W_of: np.ndarray | None = None  # the pressure whose deformation is self._W
        self._W = np.zeros((ny, nx))
        self.theta = np.ones((ny, nx))  # film content (starved inlet), 1: a full gap
        self.dry = np.zeros((ny, nx), dtype=bool)  # held at P = p_floor (starved inlet)
        self.march = True  # theta marched here (else fixed: see SolverOptions)

    def load(self, P: np.ndarray) -> float:
        return self.h * self.h * float(P.sum())

    def deformation(self, P: np.ndarray) -> np.ndarray:
        """W(P) by DC-FFT, remembered for the last pressure (a sweep, the residual and the
        convergence check often ask for the same one)."""
        if self._W_of is None or not np.array_equal(self._W_of, P):
            self._W = self.deform(P)
            self._W_of = P.copy()
        return self._W

    def film(self, P: np.ndarray, H0: float) -> np.ndarray:
        return H0 + self.rigid + self.deformation(P) + self.tauW

    def coefficients(self, P: np.ndarray, H0: float, prob: Problem, H: np.ndarray | None = None):
        """(H, rho, drho, eps, deps, ln_eta) at pressure P (arrays owned by the level, valid
        until its next call); the film is computed unless given."""
        if H is None:
            H = self.film(P, H0)
        rho, drho, eps, deps, ln_eta = self._coef
        self._coefficients(P, H, prob.lam, prob.params, rho, drho, eps, deps, ln_eta)
        return H, rho, drho, eps, deps, ln_eta

    def residual(self, P: np.ndarray, H0: float, prob: Problem, f: np.ndarray | None = None,
                 raw: bool = False, H: np.ndarray | None = None):
        """(r, wedge, H) with r = f - L(P); unless ``raw``, r is zeroed where cavitation
        holds (P = 0, r > 0: the diverging gap would pull P below 0)."""
        H, rho, _, eps, _, _ = self.coefficients(P, H0, prob, H)
        r = np.zeros_like(P)
        wedge = np.zeros_like(P)
        f = self.f if f is None else f
        if not raw:
            update_inlet(self, P, H, rho, eps, f, prob)
        rhoH = rho * H * self.theta if prob.inlet_layer is not None else rho * H
        self._residual(P, rhoH, eps, f, self.h, self.h, r, wedge)
        if not raw:
            r[((P <= prob.p_floor) & (r > 0.0)) | self.dry] = 0.0
        return r, wedge, H

    def relax(self, H0: float, prob: Problem, opt: SolverOptions) -> None:
        self.sweeps += 1
        H, rho, drho, eps, deps, ln_eta = self.coefficients(self.P, H0, prob)
        P_old = self.P.copy() if opt.max_ln_eta_step > 0.0 else None
        update_inlet(self, self.P, H, rho, eps, self.f, prob)
        if prob.inlet_layer is not None:  # the wedge d(rho theta H)/dX
            rho, drho = rho * self.theta, drho * self.theta
        self._relax(self.P, H, rho, drho, eps, self.f, self.h, self.h, self.K0, self.K1,
                    opt.switch, opt.w_gs, opt.w_ja, prob.p_floor, prob.neumann_outlet,
                    self.work, deps, self.dry, True, opt.zebra)
        if P_old is not None:
            limit_viscosity_step(P_old, self.P, prob.laws, opt.max_ln_eta_step, ln_eta)
            if prob.neumann_outlet:
                self.P[:, -1] = self.P[:, -2]
