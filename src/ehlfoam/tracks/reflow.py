"""Reflow of an oil layer on a wall across its track: capillary levelling, SI units.

A layer h(y, t) [m] on a wall (the disc's track, the ball's), uniform along the track and
free on top, levels under its surface tension sigma [N/m] in the lubrication limit (the
thin-film equation of a free layer on a no-slip wall, the model of van Zoelen, Venner and
Lugt for the redistribution of thin layers on a running track):

    h_t + d/dy( h^3 / (3 eta) (sigma h_yyy + f) ) = 0,

with an optional body force f [N/m3] along +y (the centrifugal rho u^2 / r on the disc's
track, radially out; it needs the full width, ``symmetric=False``).

Finite volumes on uniform cells of width dy: the flux through each face is the face's
mobility (h_face + h_p)^3 / (3 eta), h_face the mean of its two cells, times sigma times the
jump of the cells' curvature h_yy across it, plus the body force. h_p (``precursor``) keeps
a little mobility where the wall is dry, the usual regularisation of the contact-line
paradox; it carries no oil. The ends are closed (mirror cells: zero slope and zero flux),
so the symmetry plane y = 0 is one of them and the far end sits where the layer no longer
moves (a domain wide enough).

Backward Euler in time, Newton's method on each step with the exact banded Jacobian (scipy):
the equation is stiff (a cell's levelling time 3 eta dy^4 / (sigma h^3) is microseconds to
seconds). Every Newton update has a zero sum (the Jacobian's columns sum to one: each face's
flux leaves one cell and enters the next), so the layer's volume is kept to round-off
whatever the Newton iterations did. A step whose Newton iteration fails is halved. A cell
that a step leaves below zero (a fourth-order equation has no maximum principle: at the foot
of a layer on dry wall, some 1e-3 of the layer) is set to zero and its deficit taken from the
positive cells in proportion, the volume kept; the largest such undershoot is reported.

Known answers (tests/tracks/test_reflow.py): a small sinusoidal perturbation of wavenumber
k on a layer h0 decays at sigma h0^3 k^4 / (3 eta); a small ridge on a layer spreads as the
linear equation's kernel, its width growing as t^(1/4).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import solve_banded

__all__ = ["ReflowResult", "levelling_rate", "levelling_time", "reflow"]


def levelling_rate(h0: float, k: float, sigma: float, eta: float) -> float:
    """The decay rate [1/s] of a small sinusoidal perturbation of wavenumber k [1/m] on a
    layer h0 [m]: sigma h0^3 k^4 / (3 eta) (linear theory)."""
    return sigma * h0**3 * k**4 / (3.0 * eta)


def levelling_time(h0: float, length: float, sigma: float, eta: float) -> float:
    """The time [s] a layer h0 [m] takes to level a feature of lateral size ``length``
    [m]: 3 eta L^4 / (sigma h0^3)."""
    return 3.0 * eta * length**4 / (sigma * h0**3)


@dataclass(frozen=True)
class ReflowResult:
    """The layer after the reflow [m], the steps taken (halved ones included), the largest
    undershoot below zero that was taken back [m] and the volume change relative to the
    start (round-off)."""

    h: np.ndarray
    steps: int
    undershoot: float
    volume_error: float


def reflow(h: np.ndarray, dy: float, duration: float, sigma: float, eta: float, *,
           precursor: float = 1e-9, body_force: float = 0.0, steps: int = 60,
           growth: float = 1.15, newton_tol: float = 1e-10,
           max_newton: int = 30) -> ReflowResult:
    """The layer ``h`` [m] on uniform cells of width ``dy`` [m] after ``duration`` [s] of
    capillary levelling (module docstring): surface tension ``sigma`` [N/m], viscosity
    ``eta`` [Pa s], ``precursor`` [m], ``body_force`` along +y [N/m3]. ``steps`` backward
    Euler steps, each ``growth`` times the one before (1: equal steps; the first ones short,
    where the fine features level fast). Raises ValueError naming a bad argument."""
    h = np.array(h, dtype=float)
    checks = {"dy": (dy, dy > 0, "> 0 m"), "duration": (duration, duration >= 0, ">= 0 s"),
              "sigma": (sigma, sigma > 0, "> 0 N/m"), "eta": (eta, eta > 0, "> 0 Pa s"),
              "precursor": (precursor, precursor >= 0, ">= 0 m"),
              "steps": (steps, steps >= 1, ">= 1"), "growth": (growth, growth >= 1, ">= 1"),
              "h": ("...", h.ndim == 1 and h.size >= 3 and np.isfinite(h).all()
                    and (h >= 0).all(), "finite, >= 0 m, at least 3 cells")}
    for name, (value, ok, valid) in checks.items():
        if not ok:
            raise ValueError(f"{name} = {value!r} is out of range: must be {valid}")
    volume = float(h.sum())
    if duration == 0 or volume == 0:
        return ReflowResult(h, 0, 0.0, 0.0)
    ops = _Operators(h.size, dy, sigma, eta, precursor, body_force)
    if growth == 1.0:
        dts = [duration / steps] * steps
    else:
        first = duration * (growth - 1.0) / (growth**steps - 1.0)
        dts = list(first * growth ** np.arange(steps))
    t, taken, worst = 0.0, 0, 0.0
    queue = list(reversed(dts))
    while queue:
        dt = queue.pop()
        if t + dt > duration:
            dt = duration - t
        new = ops.step(h, dt, newton_tol, max_newton)
        taken += 1
        if new is None and dt > duration * 1e-9:
            queue += [dt / 2, dt / 2]                  # halve it
            continue
        if new is None:
            raise RuntimeError(f"the reflow's Newton iteration did not converge at t = {t:g} "
                               f"s with a step of {dt:g} s")
        low = float(new.min())
        if low < 0:                                    # take the undershoot back, volume kept
            worst = max(worst, -low)
            pos = np.clip(new, 0.0, None)
            new = pos * (new.sum() / pos.sum())
        h, t = new, t + dt
    return ReflowResult(h, taken, worst, abs(float(h.sum()) - volume) / volume)


class _Operators:
    """The discrete operator on n cells with closed (mirror) ends, its Jacobian in banded
    form (five diagonals: a face's flux reads four cells, a cell's balance two faces)."""

    def __init__(self, n: int, dy: float, sigma: float, eta: float, precursor: float,
                 body_force: float):
        self.n, self.dy = n, dy
        self.c = sigma / (3.0 * eta)                    # [N/(m Pa s)] = [m/s]
        self.f = body_force / sigma                     # [1/m2]: in units of h_yyy
        self.hp = precursor
        # h_yyy on face f (between cells f and f + 1): the coefficients of h_{f+k},
        # k = -1..2, the mirror cells h_-1 = h_0 and h_n = h_{n-1} folded in
        g = np.tile(np.array([-1.0, 3.0, -3.0, 1.0]) / dy**3, (n - 1, 1))
        g[0, 1] += g[0, 0]
        g[0, 0] = 0.0
        g[-1, 2] += g[-1, 3]
        g[-1, 3] = 0.0
        self.g = g

    def _yyy(self, h: np.ndarray) -> np.ndarray:
        hp = np.concatenate([h[:1], h, h[-1:]])          # with the mirror cells
        return (hp[3:] - 3.0 * hp[2:-1] + 3.0 * hp[1:-2] - hp[:-3]) / self.dy**3

    def step(self, h0: np.ndarray, dt: float, tol: float, max_newton: int
             ) -> np.ndarray | None:
        """One backward Euler step from ``h0``; None if Newton's method does not converge."""
        n, r_dt = self.n, dt / self.dy
        h = h0.copy()
        scale = max(float(np.abs(h0).max()), 1e-300)
        for _ in range(max_newton):
            hf = 0.5 * (h[:-1] + h[1:]) + self.hp
            drive = self._yyy(h) + self.f
            F = self.c * hf**3 * drive                   # [m2/s] through the n - 1 faces
            net = np.zeros(n)
            net[:-1] += F
            net[1:] -= F
            r = h - h0 + r_dt * net
            # dF_f / dh_{f+k}, k = -1..2
            X = (self.c * hf**3)[:, None] * self.g
            X[:, 1:3] += (1.5 * self.c * hf**2 * drive)[:, None]
            ab = np.zeros((5, n))                        # ab[2 - d, i + d] = J[i, i + d]
            ab[2] = 1.0
            for k in range(-1, 3):                       # cell i = f gains +F_f
                i = np.arange(n - 1)
                j = i + k
                ok = (j >= 0) & (j < n)
                ab[2 + i[ok] - j[ok], j[ok]] += r_dt * X[ok, k + 1]
                ab[3 + i[ok] - j[ok], j[ok]] -= r_dt * X[ok, k + 1]   # f + 1 loses it
            dh = solve_banded((2, 2), ab, -r)
            if not np.isfinite(dh).all():
                return None
            h = h + dh
            if np.abs(dh).max() <= tol * scale:
                return h
        return None
