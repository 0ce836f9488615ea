"""Full-approximation-scheme (FAS) multigrid solver of the dimensionless EHL point contact.

Unknowns: the pressure P on a uniform grid (Dirichlet P = 0 on the boundary, optionally a
zero-gradient outlet) and the film constant H0. Equations on every level:

    Reynolds  L(P) = f                         (:mod:`ehlfoam.contact.reynolds`)
    film      H = H0 + X^2/2 + Y^2/2 + W(P) + tauW   (W by DC-FFT, :mod:`ehlfoam.contact.elastic`)
    load      h^2 sum(P) = target

On the finest level f = 0, tauW = 0 and target = 2 pi / 3 (unless a load is held there,
:meth:`MultigridSolver.hold`: tauW is its deformation, the target less its load). The coarse
levels carry the FAS right-hand sides (restricted residual plus coarse operator of the
injected pressure), the FAS correction of the film (fine deformation minus coarse
deformation of the injected pressure) and of the load. H0 is relaxed against the load on the
coarsest level, whose problem is solved (rounds of sweeps and H0 steps). Full multigrid
(FMG) start from a Hertzian pressure on the coarsest level, each finer level cycled to its
own discretisation error; the finest level until its film has settled (see
:class:`SolverOptions`). The levels, the options and the problem:
:mod:`ehlfoam.contact.levels`; transfers: :mod:`ehlfoam.contact.transfer`; a starved inlet's
film content: :mod:`ehlfoam.contact.inlet`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.ndimage import minimum_filter

from ehlfoam.contact.elastic import hertz_pressure
from ehlfoam.contact.inlet import meniscus_mask
from ehlfoam.contact.levels import LOAD_TARGET, Domain, Level, Problem, SolverOptions
from ehlfoam.contact.lubricant import limit_viscosity_step
from ehlfoam.contact.threads import numba_threads, solve_threads
from ehlfoam.contact.transfer import (prolong_bilinear, prolong_cubic, restrict_full_weighting,
                                      restrict_pressure)

__all__ = ["LOAD_TARGET", "Domain", "Level", "MGResult", "MultigridSolver", "Problem",
           "SolverOptions", "limit_viscosity_step"]


@dataclass
class MGResult:
    """Converged (or not) finest-level solution and its convergence record."""

    P: np.ndarray
    H: np.ndarray
    H0: float
    x: np.ndarray
    y: np.ndarray
    converged: bool
    residual: float
    load_error: float
    cycles: int
    history: list = field(default_factory=list)
    wall_s: float = 0.0
    failure: str = ""
    #: cycle after which the stalled-solve options were used (None: never)
    stalled_at: int | None = None
    #: central film of each FMG level below the finest (its discretisation-error estimate)
    fmg_hc: list = field(default_factory=list)
    #: relaxation sweeps of all levels in units of one finest-level sweep
    work_units: float = 0.0
    #: film content of the finest level (starved inlet; 1 elsewhere), None if not kept
    theta: np.ndarray | None = None

    def centre_index(self) -> tuple[int, int]:
        """(row, column) of the grid point nearest the contact's centre."""
        return int(np.argmin(np.abs(self.y))), int(np.argmin(np.abs(self.x)))


class MultigridSolver:
    """FAS multigrid (FMG + W-cycles) for :class:`Problem` on :class:`Domain`."""

    def __init__(self, prob: Problem, dom: Domain, opt: SolverOptions | None = None):
        self.prob, self.dom = prob, dom
        self.opt = opt or SolverOptions()
        nx, ny = dom.nx, dom.ny
        h = dom.h
        sizes = [(nx, ny, h)]
        while (min(nx, ny) > self.opt.coarsest_min_points and (nx - 1) % 2 == 0
               and (ny - 1) % 2 == 0):
            nx, ny, h = (nx - 1) // 2 + 1, (ny - 1) // 2 + 1, 2 * h
            sizes.append((nx, ny, h))
        self.workers = solve_threads(self.opt.workers)
        self.levels = [Level(n1, n2, dom.x_min, -dom.y_half, hh, self.workers)
                       for n1, n2, hh in reversed(sizes)]
        self.H0 = 0.0
        #: a load held on the finest level (see :meth:`hold`): its deformation and load
        self.held_W: np.ndarray | None = None
        self.held_load = 0.0
        # the film constant reacts strongly to the load when heavily loaded: smaller steps
        self.h0_gain = self.opt.h0_gain * (0.25 if prob.moes_M > 1000.0 else 1.0)

    # --- cycle pieces -------------------------------------------------------------------
    def _enforce_bc(self, lv: Level) -> None:
        P = lv.P
        P[0, :] = P[-1, :] = 0.0
        P[:, 0] = 0.0
        if self.prob.neumann_outlet:
            P[:, -1] = P[:, -2]
        else:
            P[:, -1] = 0.0
        np.maximum(P, self.prob.p_floor, out=P)
        if self.prob.inlet_meniscus_x is not None:
            P[meniscus_mask(lv.x, lv.ny, self.prob.inlet_meniscus_x)] = self.prob.p_floor

    def _solve_coarsest(self) -> None:
        lv = self.levels[0]
        opt = self.opt
        for _ in range(opt.coarse_rounds):
            for _ in range(opt.coarse_sweeps):
                lv.relax(self.H0, self.prob, opt)
            self.H0 += self.h0_gain * (lv.load(lv.P) - lv.load_target)
        for _ in range(opt.coarse_sweeps):
            lv.relax(self.H0, self.prob, opt)

    def _cycle(self, k: int) -> None:
        if k == 0:
            self._solve_coarsest()
            return
        lv, co = self.levels[k], self.levels[k - 1]
        opt, prob = self.opt, self.prob
        for _ in range(opt.nu1):
            lv.relax(self.H0, prob, opt)
        r, _, H = lv.residual(lv.P, self.H0, prob)
        P_hat = restrict_pressure(lv.P, prob.p_floor)
        co.P = P_hat.copy()
        co.theta, co.march = lv.theta[::2, ::2].copy(), not opt.fixed_coarse_theta  # fine's
        co.dry = co.theta < 1.0
        # film FAS correction: the coarse film of P_hat is the fine film at the coarse points
        H_hat = H[::2, ::2]
        co.tauW = H_hat - self.H0 - co.rigid - co.deform(P_hat)
        zero_f = np.zeros_like(P_hat)
        r_hat, _, _ = co.residual(P_hat, self.H0, prob, f=zero_f, raw=True, H=H_hat)  # -L_H(P_hat)
        co.f = -r_hat + restrict_full_weighting(r)
        co.load_target = lv.load_target + co.load(P_hat) - lv.load(lv.P)
        for _ in range(opt.gamma if k > 1 else 1):
            self._cycle(k - 1)
        corr = prolong_bilinear(co.P - P_hat)
        # no correction inside the cavitated region, nor on its boundary
        corr[~minimum_filter(lv.P > prob.p_floor, size=3, mode="constant", cval=False)] = 0.0
        P_before = lv.P.copy() if opt.limit_correction else None
        lv.P += corr
        self._enforce_bc(lv)
        if P_before is not None:
            limit_viscosity_step(P_before, lv.P, prob.laws, opt.max_ln_eta_step)
        for _ in range(opt.nu2):
            lv.relax(self.H0, prob, opt)

    def _stalled(self, history: list) -> bool:
        """Whether the last cycles stalled (see :class:`SolverOptions`)."""
        w = self.opt.stall_window
        if w <= 0 or len(history) < 2 * w + 1:
            return False
        res = [h[1] for h in history]
        return min(res[-w:]) > self.opt.stall_ratio * min(res[-2 * w:-w])

    def measure(self, k: int | None = None) -> tuple[float, float, np.ndarray]:
        """(relative residual, relative load error, film) of level ``k`` (default: finest)."""
        lv = self.levels[-1 if k is None else k]
        r, wedge, H = lv.residual(lv.P, self.H0, self.prob)
        denom = float(np.abs(wedge).sum()) or 1.0
        res = float(np.abs(r).sum()) / denom
        load_err = abs(lv.load(lv.P) - lv.load_target) / lv.load_target
        return res, load_err, H

    def work_units(self) -> float:
        """Relaxation sweeps done so far on all levels, in finest-level sweeps (each weighted
        by its points)."""
        top = self.levels[-1]
        return sum(lv.sweeps * lv.nx * lv.ny for lv in self.levels) / (top.nx * top.ny)

    def _centre(self, k: int) -> tuple[int, int]:
        lv = self.levels[k]
        return int(np.argmin(np.abs(lv.y))), int(np.argmin(np.abs(lv.x)))

    # --- driver ---------------------------------------------------------------------------
    def hold(self, P_held: np.ndarray | None) -> None:
        """Hold a given pressure field (units pH, finest grid; None: none) as an external load
        in the next solves: its elastic deformation is added to the finest level's film (the
        coarse levels get it through their FAS film correction) and its load is taken off the
        finest level's load target, so that the solved P plus ``P_held`` carries the load.
        The two-phase option's sub-ambient field, coupled back
        (:mod:`ehlfoam.contact.coupled`)."""
        if P_held is None or not np.any(P_held):
            self.held_W, self.held_load = None, 0.0
            return
        top = self.levels[-1]
        self.held_W = top.deform(P_held)
        self.held_load = top.load(P_held)

    def solve(self, H0_guess: float, P_init: np.ndarray | None = None,
              fmg_hc: list | None = None) -> MGResult:
        """Solve from a Hertzian start by FMG, or from ``P_init`` (finest grid) by cycles,
        on :attr:`workers` threads. ``fmg_hc``: the FMG levels' central films of an earlier
        solve of the same problem, for the film tolerance of a solve from ``P_init``
        (:meth:`film_tolerance`; default: none, the loosest)."""
        with numba_threads(self.workers):
            return self._solve(H0_guess, P_init, fmg_hc)

    def _fmg(self) -> list[float]:
        """Full multigrid start: the coarsest level from a Hertzian pressure, then each finer
        level from the cubic interpolation of the coarser one, cycled until its central film
        changes by less than ``fmg_change`` times the discretisation error that the two
        levels estimate (|hc_k - hc_k-1| / 3, second order), at least ``fmg_cycles`` and at
        most ``fmg_max_cycles`` cycles. The finest level is left interpolated (the caller
        cycles it). Returns the central film of each level below the finest."""
        opt = self.opt
        self.fmg_counts = []
        lv0 = self.levels[0]
        X, Y = np.meshgrid(lv0.x, lv0.y)
        lv0.P = hertz_pressure(X, Y)
        self._enforce_bc(lv0)
        self._solve_coarsest()
        j, i = self._centre(0)
        hc = [float(lv0.film(lv0.P, self.H0)[j, i])]
        for k in range(1, len(self.levels)):
            lv = self.levels[k]
            lv.P = prolong_cubic(self.levels[k - 1].P)
            lv.f[:] = 0.0
            lv.tauW[:] = 0.0
            lv.load_target = LOAD_TARGET
            self._enforce_bc(lv)
            if k == len(self.levels) - 1:
                break
            j, i = self._centre(k)
            last = None
            for n in range(opt.fmg_max_cycles):
                self._cycle(k)
                H = lv.film(lv.P, self.H0)
                now = (float(H[j, i]), float(H.min()))
                if (n + 1 >= opt.fmg_cycles and last is not None and np.all(np.isfinite(now))
                        and max(abs(now[0] - last[0]), abs(now[1] - last[1]))
                        < opt.fmg_change * abs(now[0] - hc[-1]) / 3.0):
                    break
                last = now
            hc.append(now[0])
            self.fmg_counts.append(n + 1)
        return hc

    def film_tolerance(self, hc: float, hc_coarse: float | None) -> float:
        """Largest cycle-to-cycle change of the central and minimum film (units a^2/R) at
        which the finest level counts as converged: ``film_fraction`` of its discretisation
        error estimated from the FMG levels (|hc - hc_coarse| / 3), held between
        ``film_rel_min`` and ``film_rel_max`` times hc (``film_rel_max`` without a coarse
        estimate)."""
        opt = self.opt
        top = opt.film_rel_max * abs(hc)
        if hc_coarse is None or not np.isfinite(hc_coarse):
            return top
        tol = opt.film_fraction * abs(hc - hc_coarse) / 3.0
        return float(np.clip(tol, opt.film_rel_min * abs(hc), top))

    def _solve(self, H0_guess: float, P_init: np.ndarray | None = None,
               fmg_hc_given: list | None = None) -> MGResult:
        t0 = time.perf_counter()
        base_opt = self.opt
        if self.prob.moes_L > base_opt.high_L:
            self.opt = replace(base_opt, w_ja=base_opt.w_ja_high_L)
        elif self.prob.moes_M > base_opt.high_M:
            self.opt = replace(base_opt, w_ja=base_opt.w_ja_high_M)
        opt = self.opt
        self.H0 = H0_guess
        history = []
        if P_init is not None:
            self.levels[-1].P = P_init.copy()
            self._enforce_bc(self.levels[-1])
            fmg_hc = list(fmg_hc_given or [])
        else:
            fmg_hc = self._fmg()
        top_lv = self.levels[-1]  # the held load (FMG and a fresh start leave it out)
        top_lv.tauW = np.zeros_like(top_lv.P) if self.held_W is None else self.held_W.copy()
        top_lv.load_target = LOAD_TARGET - self.held_load
        top = len(self.levels) - 1
        lv = self.levels[-1]
        j, i = self._centre(top)
        converged = False
        failure = ""
        cycles = 0
        stalled_at = None
        film_ok = 0
        res, load_err, H = self.measure()
        films = [(float(H[j, i]), float(H.min()))]
        history.append((0, res, load_err, self.H0, time.perf_counter() - t0, *films[-1]))
        while True:
            if not np.isfinite(res) or not np.all(np.isfinite(lv.P)):
                failure = "non-finite pressure or residual"
                break
            if load_err < opt.tol_load and (
                    res < opt.residual_only
                    or (film_ok and res < max(opt.tol_residual, opt.film_max_residual))):
                converged = True
                break
            if cycles >= opt.max_cycles:
                break
            if self._stalled(history[stalled_at or 0:]):  # a starved inlet's may stall twice
                if stalled_at is None:
                    stalled_at, window = cycles, opt.stall_window
                    self.opt = opt = replace(opt.stalled(), stall_window=window
                                             if self.prob.inlet_layer is not None else 0)
                else:
                    self.opt = opt = replace(opt, fixed_coarse_theta=True, stall_window=0)
            self._cycle(top)
            cycles += 1
            res, load_err, H = self.measure()
            films.append((float(H[j, i]), float(H.min())))
            tol = self.film_tolerance(films[-1][0], fmg_hc[-1] if fmg_hc else None)
            change = max(abs(films[-1][0] - films[-2][0]), abs(films[-1][1] - films[-2][1]))
            film_ok = film_ok + 1 if change < tol else 0
            history.append((cycles, res, load_err, self.H0, time.perf_counter() - t0,
                            *films[-1]))
        self.opt = base_opt  # the stalled options hold for this solve only
        if not converged and not failure:
            failure = (f"not converged after {cycles} cycles: residual {res:.3g} "
                       f"(tol {max(opt.tol_residual, opt.film_max_residual):g}), load error "
                       f"{load_err:.3g} (tol {opt.tol_load:g}), film settled: {bool(film_ok)}")
        return MGResult(P=lv.P.copy(), H=H, H0=self.H0, x=lv.x.copy(), y=lv.y.copy(),
                        work_units=self.work_units(),
                        converged=converged, residual=res, load_error=load_err, cycles=cycles,
                        history=history, wall_s=time.perf_counter() - t0, failure=failure,
                        stalled_at=stalled_at, fmg_hc=fmg_hc, theta=lv.theta.copy())
