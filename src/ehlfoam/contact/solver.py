"""Solve a :class:`~ehlfoam.contact.spec.PrecalcSpec`: domain and grid choice, load continuation,
and the SI result (summary numbers, fields, the gap).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np

from ehlfoam.contact.formulas import Contact, moes_to_hertz_film, nijenbanning_moes_hc
from ehlfoam.contact.inlet import meniscus_x_on_centreline
from ehlfoam.contact.multigrid import Domain, MGResult, MultigridSolver, Problem, SolverOptions
from ehlfoam.contact.spec import P_AMBIENT_PA, PrecalcSpec
from ehlfoam.contact.coupled import Coupling, couple, coupling_errors
from ehlfoam.contact.twophase import SubAmbientResult, solve_subambient, subambient_deformation

#: When a direct (FMG) start fails, the solve starts again from a solution at a Moes M of
#: at most this (speed ramp).
CONTINUATION_M = 5000.0
#: Multigrid cycles spent on each intermediate step of the speed ramp.
RAMP_CYCLES = 4


#: Moes M from which the default grid is 2049 points a side: 1025 leaves hc 2 % short of its
#: grid-converged value near M = 8000 (0.8 % at 3900, 3.4 % at 13,000, 9 % at 34,000).
FINE_GRID_M = 8000.0
#: The largest estimated grid error of hc (:attr:`PrecalcResult.hc_grid_error`) that the
#: precalc passes without a warning: the estimate assumes second order where the solver
#: shows 2.5 at M 3900, so 3 % estimated is about 2 % true (769 points: 2.0 % estimated,
#: 1.5 % true; 1025: 0.9 and 0.8 %).
GRID_ERROR_WARN = 0.03


def default_grid(M: float) -> int:
    """Grid points per side that keep hc within about 2 % of the grid-converged value
    (measured up to M = 34,000, where 2049 leaves 2.2 %)."""
    if M < 300.0:
        return 513
    return 1025 if M < FINE_GRID_M else 2049


def domain_for(spec: PrecalcSpec, M: float, n: int) -> Domain:
    """Computational domain in units of a (two-phase: the thesis's x in [-2, 6], y in [-2, 2])."""
    if spec.cavitation == "twophase":
        return Domain(-2.0, 6.0, 2.0, 2 * n - 1, n)
    if M < 300.0:
        return Domain(-4.5, 1.5, 3.0, n, n)
    if M < 1000.0:
        return Domain(-2.5, 1.5, 2.0, n, n)
    # heavily loaded: the inlet zone is a fraction of a; spend the points near the contact
    return Domain(-1.8, 1.2, 1.5, n, n)


def starved_domain(spec: PrecalcSpec, dom: Domain) -> Domain:
    """The domain of a starved solve: ``dom``, its inlet moved upstream (square cells kept)
    when a prescribed meniscus lies less than 0.25 a inside it."""
    if spec.inlet_meniscus is None or -1.0 - spec.inlet_meniscus > dom.x_min + 0.25:
        return dom
    x_min = -1.0 - spec.inlet_meniscus - 0.25
    return Domain(x_min, dom.x_max, 0.5 * (dom.x_max - x_min), dom.nx, dom.ny)


@dataclass(frozen=True)
class Start:
    """A neighbouring solution to start a solve from (another speed, temperature or load):
    its dimensionless pressure P (units pH) on axes x, y (units a), film constant H0
    (units a^2/R) and Moes M, L."""

    x: np.ndarray
    y: np.ndarray
    P: np.ndarray
    H0: float
    M: float
    L: float

    @classmethod
    def from_result(cls, result: "PrecalcResult") -> "Start":
        mg, c = result.mg, result.contact
        return cls(mg.x, mg.y, mg.P, mg.H0, c.M, c.L)

    def pressure_on(self, dom: Domain) -> np.ndarray:
        """P interpolated (bilinear, in units of a) onto the grid of ``dom``; 0 outside."""
        from scipy.interpolate import RegularGridInterpolator

        x = np.linspace(dom.x_min, dom.x_max, dom.nx)
        y = np.linspace(-dom.y_half, dom.y_half, dom.ny)
        f = RegularGridInterpolator((self.y, self.x), self.P, bounds_error=False, fill_value=0.0)
        Y, X = np.meshgrid(y, x, indexing="ij")
        return f(np.stack([Y, X], axis=-1))


def h0_guess(M: float, L: float) -> float:
    """Film constant H0 (units a^2/R) of the NVM central film: Hc - 1 (the Hertzian
    deformation at the centre is 1)."""
    return moes_to_hertz_film(nijenbanning_moes_hc(M, max(L, 1e-9)), M) - 1.0


@dataclass
class PrecalcResult:
    """A solved contact: the spec, the contact data, the fields and the convergence record."""

    spec: PrecalcSpec
    contact: Contact
    domain: Domain
    mg: MGResult
    wall_s: float
    continuation: list
    subambient: SubAmbientResult | None = None
    #: the two-phase option's coupling: its outer iteration and how well the coupled
    #: equations hold (:class:`~ehlfoam.contact.coupled.Coupling`)
    coupling: Coupling | None = None
    #: the same contact fully flooded, on the same grid (starved inlet only)
    flooded: "PrecalcResult | None" = None

    @property
    def converged(self) -> bool:
        return self.mg.converged

    def centre_index(self) -> tuple[int, int]:
        return self.mg.centre_index()

    @property
    def H_central(self) -> float:
        j, i = self.centre_index()
        return float(self.mg.H[j, i])

    @property
    def hc_grid_error(self) -> float | None:
        """The relative discretisation error of hc that the grid and the full multigrid's
        next-coarser level estimate, |hc - hc_coarse| / (3 hc) (second order): at M 3900
        0.9 / 2.0 / 3.8 % on 1025 / 769 / 513 points against 0.8 / 1.5 / 3.5 % from the
        Richardson value, at M 34,000 on 2049 points 3.5 against 2.2 %; on a grid too
        coarse for the film it falls short (257 at M 3900: 6 % against 15 %). None without
        a full multigrid start (a solve from a neighbour's solution)."""
        if not self.mg.fmg_hc or not self.H_central:
            return None
        return abs(self.H_central - self.mg.fmg_hc[-1]) / (3.0 * abs(self.H_central))

    def cavity_length_over_a(self, below: float = 0.0) -> float:
        """Length (units a) of the region behind the contact on y = 0 where the gauge
        pressure is below ``below`` [Pa], from x = a to its downstream end."""
        j, _ = self.centre_index()
        x, p = self.mg.x, self.mg.P[j] * self.contact.p_hertz
        neg = np.where((x >= 1.0) & (p < below))[0]
        if neg.size == 0:
            return 0.0
        end = neg[0]
        while end + 1 < len(x) and p[end + 1] < below:
            end += 1
        return float(x[end] - 1.0)

    def starved_summary(self) -> dict:
        """The starved film against the flooded one, and the inlet meniscus on y = 0 (its
        distance upstream of x = -a, units a; None where the centreline never pressurises)."""
        ff, mg, scale = self.flooded, self.mg, self.contact.film_scale
        x_m = meniscus_x_on_centreline(mg.x, mg.y, mg.P, mg.theta
                                       if self.spec.inlet_layer is not None else None)
        out = {"hc_flooded_m": ff.H_central * scale, "hmin_flooded_m": float(ff.mg.H.min()) * scale,
               "hc_over_hc_flooded": self.H_central / ff.H_central,
               "hmin_over_hmin_flooded": float(mg.H.min()) / float(ff.mg.H.min()),
               "inlet_meniscus_over_a": None if x_m is None else -1.0 - x_m,
               "flooded_converged": bool(ff.converged)}
        if self.spec.inlet_layer is not None:
            out["inlet_layer_over_hc_flooded"] = self.spec.inlet_layer / out["hc_flooded_m"]
        return out

    def summary(self) -> dict:
        """The JSON contract (SI units, plus dimensionless groups)."""
        c = self.contact
        scale = c.film_scale
        p = self.mg.P * c.p_hertz
        out = {
            "a_m": c.a,
            "p_hertz_Pa": c.p_hertz,
            "M": c.M,
            "L": c.L,
            "lambda": c.lam,
            "hc_m": self.H_central * scale,
            "hc_grid_error": self.hc_grid_error,
            "hmin_m": float(self.mg.H.min()) * scale,
            "p_max_Pa": float(p.max()),
            "p_min_Pa": float(p.min()),
            "h0_m": self.mg.H0 * scale,
            "converged": bool(self.converged),
            "residual": self.mg.residual,
            "load_error": self.mg.load_error,
            "cycles": self.mg.cycles,
            # cycle from which the stalled-solve relaxation was used (None: never)
            "stalled_at_cycle": self.mg.stalled_at,
            "grid": [self.domain.nx, self.domain.ny],
            "domain_over_a": [self.domain.x_min, self.domain.x_max, -self.domain.y_half,
                              self.domain.y_half],
            "wall_s": self.wall_s,
            "hc_nvm_m": moes_to_hertz_film(nijenbanning_moes_hc(c.M, c.L), c.M) * scale
            if c.L > 0 else None,
            "failure": self.mg.failure or None,
            "continuation_M": self.continuation,
            "spec": self.spec.model_dump(),
        }
        if self.flooded is not None:
            out.update(self.starved_summary())
        if self.spec.cavitation == "twophase":
            length = self.cavity_length_over_a()
            out["cavity_length_over_a"] = length
            out["cavity_reaches_outlet"] = bool(length >= self.domain.x_max - 1.0 - self.domain.h)
            # where more than half the mixture's volume is gas (rho < rho0 / 2)
            out["cavity_half_density_length_over_a"] = self.cavity_length_over_a(
                -0.5 * self.spec.twophase_p_scale)
            if self.coupling is not None:
                cp = self.coupling
                out["twophase_coupling"] = cp.mode
                # max |H - (H0 + rigid + W(total P))| over hc, and the total P's load error
                out["coupling_film_error_over_hc"] = cp.film_error
                out["coupling_load_error"] = cp.load_error
                out["coupling_outer_iterations"] = len(cp.outer)
                out["coupling_outer"] = cp.outer
            if self.subambient is not None:
                out["subambient_newton_iterations"] = self.subambient.iterations
                # the film change over the contact the one-way coupling leaves out, at most, over hc
                if self.subambient.deformation_max is not None:
                    out["subambient_deformation_over_hc"] = (self.subambient.deformation_max
                                                             / self.H_central)
                # the nested iteration, coarsest grid first: [nx, ny], Newton iterations,
                # LU factorisations, wall time [s]
                out["subambient_levels"] = [
                    dict(grid=lv["shape"][::-1], newton_iterations=lv["iterations"],
                         factorisations=lv["factorisations"], converged=lv["converged"],
                         wall_s=lv["wall_s"]) for lv in self.subambient.levels]
        return out


def _worse(a: MGResult, b: MGResult) -> bool:
    """Whether attempt ``a`` is worse than ``b``: non-finite, or unconverged with a larger
    residual."""
    if not np.all(np.isfinite(a.P)) or not np.isfinite(a.residual):
        return True
    return not a.converged and a.residual > b.residual


def _ramp(solver, prob, opt, c, factor: float, start: float, h0_guess):
    """Step M up by ``factor`` from at most ``start`` to the contact's M, each step from the
    previous pressure and film constant; returns the M values and the last result."""
    steps = max(1, math.ceil(math.log(c.M / min(c.M, start)) / math.log(factor) - 1e-9))
    M_start = c.M / factor**steps
    ramp = [M_start * factor**k for k in range(steps + 1)]
    P, H0, result = None, h0_guess(M_start), None
    for k, M_k in enumerate(ramp):
        lam_k = c.lam * (M_k / c.M) ** (-4.0 / 3.0)  # M ~ u^-3/4 at fixed load
        solver.prob = replace(prob, lam=lam_k, moes_M=M_k)
        solver.opt = opt if k == steps else replace(opt, max_cycles=RAMP_CYCLES)
        result = solver.solve(H0, P_init=P)
        if not np.all(np.isfinite(result.P)):
            break
        P, H0 = result.P, result.H0
    solver.opt = opt
    return ramp, result


def solve(spec: PrecalcSpec, options: SolverOptions | None = None,
          start: Start | None = None, flooded: PrecalcResult | None = None,
          domain: Domain | None = None) -> PrecalcResult:
    """Solve the EHL contact of ``spec``: full multigrid from a Hertzian start, then cycles
    to convergence (:class:`~ehlfoam.contact.multigrid.MultigridSolver`); or, given a
    neighbouring solution ``start`` (not for the two-phase option), cycles from its pressure
    and its film constant shifted by the NVM films' difference, falling back to the full
    multigrid start if that does not converge.

    A starved inlet (``spec.inlet_layer`` or ``spec.inlet_meniscus``) is solved beside the
    same contact fully flooded on the same grid (``flooded``: that solve, if already done);
    ``domain`` overrides the domain's choice.

    Only when that direct start fails is the solution reached by a speed ramp: M is stepped
    up by factors of at most 2 from M <= :data:`CONTINUATION_M` / 4, each step starting
    from the previous pressure and film constant.
    """
    t0 = time.perf_counter()
    c = spec.contact()
    n = spec.grid or default_grid(c.M)
    dom = domain or domain_for(spec, c.M, n)
    starved = spec.inlet_layer is not None or spec.inlet_meniscus is not None
    if starved:
        dom = starved_domain(spec, dom)
        if flooded is None or flooded.domain != dom:  # the same grid and domain only
            flooded = solve(spec.model_copy(update=dict(inlet_layer=None, inlet_meniscus=None)),
                            options, start, domain=dom)
    opt = options or SolverOptions(max_cycles=spec.max_cycles, tol_residual=spec.tol_residual,
                                   tol_load=spec.tol_load)
    twophase = spec.cavitation == "twophase"
    # two-phase: sub-ambient pressures allowed down to absolute zero (gauge -p_ambient)
    p_floor = -P_AMBIENT_PA / c.p_hertz if twophase else 0.0
    prob = Problem(lam=c.lam, laws=spec.laws(), p_floor=p_floor, neumann_outlet=twophase,
                   moes_M=c.M, moes_L=c.L,
                   inlet_layer=None if spec.inlet_layer is None
                   else spec.inlet_layer / c.film_scale,
                   inlet_meniscus_x=None if spec.inlet_meniscus is None
                   else -1.0 - spec.inlet_meniscus)
    solver = MultigridSolver(prob, dom, opt)

    def h0_at(M: float) -> float:
        return h0_guess(M, c.L)

    if twophase:
        # the contact first, p >= 0 on the two-phase domain; then the sub-ambient field
        prob = replace(prob, p_floor=0.0, laws=replace(prob.laws, twophase_p_scale=None))
        solver.prob = prob
    ramp: list[float] = []
    result = None
    if start is not None and not twophase:
        result = solver.solve(start.H0 + h0_guess(c.M, c.L) - h0_guess(start.M, start.L),
                              P_init=start.pressure_on(dom))
        if not result.converged:
            solver = MultigridSolver(prob, dom, opt)
            result = None
    direct = result = result or solver.solve(h0_at(c.M))
    if not result.converged:
        # a ramp by factors of 2 from M <= CONTINUATION_M / 4; if it blows up, a gentler one
        # (factors of sqrt 2 from M <= CONTINUATION_M / 8)
        for factor, m_start in ((2.0, CONTINUATION_M / 4),
                                (math.sqrt(2.0), CONTINUATION_M / 8)):
            solver = MultigridSolver(prob, dom, opt)  # fresh: no state of a failed attempt
            ramp, attempt = _ramp(solver, prob, opt, c, factor, m_start, h0_at)
            if not _worse(attempt, result):
                result = attempt
            if attempt.converged:
                break
        if _worse(result, direct):
            result, ramp = direct, []  # the ramp did not help: keep the direct attempt
    subambient = coupling = None
    if twophase and np.all(np.isfinite(result.P)):
        sub_prob = replace(prob, p_floor=p_floor, laws=spec.laws())
        if spec.twophase_coupling == "coupled":
            result, subambient, outer, coupled_ok = couple(solver, result, sub_prob, dom.h)
        else:
            subambient = solve_subambient(result.P, result.H, dom.h, sub_prob)
            outer, coupled_ok = [], True
        result.P = subambient.P
        if outer:  # the last pass measured the solution returned
            film_err, load_err = outer[-1]["film_error_over_hc"], outer[-1]["load_error"]
        else:
            film_err, load_err = coupling_errors(result.P, result.H, result.H0, result.x,
                                                 result.y, float(result.H[result.centre_index()]),
                                                 solver.levels[-1].deform)
        coupling = Coupling(spec.twophase_coupling, film_err, load_err, outer, coupled_ok)
        if not coupled_ok and result.converged and subambient.converged:
            result.converged = False
            result.failure = (f"two-phase coupling not converged in {len(outer)} outer "
                              f"iterations (film error {film_err:.3g} of hc, tolerance "
                              f"{coupling.tol:g})" if outer else
                              "two-phase coupling not converged")
        subambient.deformation_max = subambient_deformation(result.P, dom.h, result.x,
                                                            result.y)
        if not subambient.converged:
            result.converged = False
            result.failure = (f"sub-ambient Newton not converged after {subambient.iterations} "
                              f"iterations (residual {subambient.residual:.3g})")
    return PrecalcResult(spec=spec, contact=c, domain=dom, mg=result,
                         wall_s=time.perf_counter() - t0, continuation=ramp,
                         subambient=subambient, coupling=coupling,
                         flooded=flooded if starved else None)
