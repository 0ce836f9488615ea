"""The flooded region in the thin-film limit: Reynolds flow inside capillary menisci.

The least model of the oil around the contact: the gap-averaged (Reynolds) flow of the oil
between two walls rolling at (u, 0), held by a meniscus whose capillary pressure is
Young-Laplace's across the gap, fed and drained only by the oil layers the walls carry. It
answers in seconds to minutes where the 3D interface cases take hours, on cells of any size,
so its flooded width can be converged on its own grid.

On a uniform grid of square cells over the half domain y >= 0 (symmetry on y = 0), each cell
holds oil c [m] per unit area, 0 <= c <= h. A full cell (c = h) is **flooded**: its pressure p
is unknown and it neither gains nor loses oil. Any other cell is **open**: air in the middle of
the gap, the oil as layers on the walls, and, next to the flooded region, the bulk of the
meniscus. The meniscus sits in the open cell as far as that bulk fills it (its **fill**, the
oil beyond the layers the walls carry, over the room for it: the supply's layers ahead of
the contact, the films elsewhere), theta = 1/2 + fill cells from the flooded cell's centre,
and its pressure is Young-Laplace's at the gap h_m there, p_cap = -2 sigma cos(theta) / h_m
(gauge against the ambient air); so the meniscus, its pressure and the flooded cell's
conductance to it move smoothly as a cell fills (``meniscus_position``). The fluxes
through a face, lo -> hi (:class:`~ehlfoam.thinfilm.operators.Operators`):

- flooded to flooded: Couette u h (x faces) and Poiseuille -h^3 / (12 eta) dp/dn;
- flooded to open or open to flooded: the same, Poiseuille over the distance theta to the
  meniscus at p_cap, except that from an open cell into a flooded one downstream the walls
  carry what the open cell holds, u c, in place of u h;
- open to open (x faces only): the walls carry the layers on, u c, but a cell touching the
  flooded region holds bulk oil that a receding meniscus does not give up whole: it passes
  at most u f, with f = 2 * 1.34 Ca^(2/3) (h / 2) / (1 + 3.35 Ca^(2/3)) Landau-Levich's
  films on both walls (Ca = eta u / sigma; Aussillous and Quere's fit) times
  ``film_factor``, laid of the gap at the receding meniscus;
- none through the island (the unmeshed contact, as in the CFD cases) or across y = 0; the
  supply u * (layers) enters the first column on the track; the last column and the side
  are open to the ambient air.

It is marched in time to a steady state: each step solves p on the flooded cells (sparse,
scipy; a flooded cell's outflow is zero, or returns oil it holds beyond its gap), moves the
oil, and an open cell that fills becomes flooded while a flooded cell that the region drains
(it draws more from an open neighbour than that holds: air comes in) becomes open. The oil is
conserved to round-off; the step is a quarter of a cell's transit at u (the nominal balance
holds 173.6 / 173.7 / 173.7 nl at a quarter, an eighth and a sixteenth; with the menisci at
the open cells' centres it moved by 6-16 % at each halving of the step, as they jumped a
cell at a time). The nominal problem has two balanced states, reached from above and from a
puddle: 170.1 and 161.4 nl, 15.80 and 15.55 a wide on 0.05 a cells
(docs/models/thin-film.md#what-it-gives-the-nominal-case-8-mms-8-um-layers).

With a cavitation pressure (``cavitation_pressure``, gauge) the model has an outlet: a
flooded cell whose pressure would fall below it opens to gas, the gas the flooded region
encloses (a cavity, the bubble behind the contact) is at it, and the walls carry the oil of
a cavity's cells, their film content, on at u, all of it (:mod:`ehlfoam.thinfilm.cavity`).
With a gas balance (``gas``) each cavity's pressure is that of the air it holds, exchanged
with the oil step by step (:mod:`ehlfoam.thinfilm.gas`, :attr:`Marcher.gas`).

This is the mass-conserving cavitation model of lubrication (Elrod-Adams; Jakobsson,
Floberg and Olsson's conditions) with two changes that make it a model of this flow: the
boundary pressure is the meniscus's Young-Laplace pressure instead of a cavitation pressure,
and a receding meniscus keeps all but Landau-Levich's films, where JFO lets the walls carry
off all the oil at the rupture boundary. Every meniscus has Young-Laplace's static
pressure unless ``receding_meniscus`` gives the meniscus that the walls leave the dynamic
pressure of one laying films ("bretherton": Park and Homsy's Hele-Shaw result) or a given
factor on the static one (a number), falling off with the angle at which the walls leave it. It
neglects the in-plane curvature of the meniscus (sigma / R beside 2 sigma / h: about 1 %),
the air's pressure drop, gravity and inertia (Re ~ 0.01) and the films' own orientation (a
meniscus at an angle to u lays the films of the normal speed). Off the track the walls come
in dry and advance into the region with a moving contact line; ``advancing_angle`` gives
such a meniscus its apparent (dynamic) angle, by default the static one. SI units
throughout.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from ehlfoam.thinfilm.flux_kernels import advance_oil
from ehlfoam.thinfilm.gas import CavityGas
from ehlfoam.thinfilm.operators import Operators, Step
from ehlfoam.thinfilm.problem import Grid, ThinFilmProblem
from ehlfoam.thinfilm.solution import (ThinFilmSolution, connected_region, gas_on,
                                       oil_fraction_on)

__all__ = ["REST_HALVINGS", "REST_OVERFILL", "Marcher", "solve_thin_film"]

#: With the walls at rest, a sub-step is halved until no open cell would end it holding more
#: than this share of its gap beyond full (:meth:`Marcher._at_rest`).
REST_OVERFILL = 0.02
#: ... at most this many times (a sub-step no shorter than 2^-12 of the step).
REST_HALVINGS = 12


class Marcher:
    """A march of one problem, a step at a time, for a caller that decides when to stop (the
    run of a thin-film case, :mod:`ehlfoam.run.thin_film`; :func:`solve_thin_film` is the
    march to a balance). ``start``: a solution (on any grid) whose oil fractions replace the
    initial puddle; ``courant``: the step over a cell's transit at u; ``transit_length``
    [m]: the length whose transit at u is one record of :attr:`history` (by default the
    domain's length).

    It keeps the oil in the domain exactly: the supply it took in and what left through the
    outlet and the side since its start [m3, half domain] (:attr:`oil_in`,
    :attr:`oil_out_outlet`, :attr:`oil_out_side`), step by step, and what left through the
    outlet on each row (:attr:`oil_out_rows`, the profile the contact leaves behind).
    :meth:`set_supply` changes the supply between steps (a cycle's next pass).

    ``speed_at``: the walls' speed [m/s] at the march's time [s] (a stop,
    :func:`ehlfoam.spec.stop.wall_speed_at`); each step takes it at the step's middle and
    scales every flux the walls drive by it (Couette, the supply, the films a receding
    meniscus lays, the gas's exchange), the step staying the one of ``prob.speed``, the
    speed the march starts at; with the walls at rest it is taken in sub-steps that resolve
    the capillary flow (:meth:`_at_rest`). None: ``prob.speed`` throughout."""

    def __init__(self, prob: ThinFilmProblem, *, start: ThinFilmSolution | None = None,
                 courant: float = 0.25, transit_length: float | None = None,
                 speed_at: Callable[[float], float] | None = None):
        if not 0 < courant <= 1:
            raise ValueError(f"courant = {courant!r} is out of range: must be in (0, 1]")
        if not prob.speed > 0:
            raise ValueError(f"speed = {prob.speed!r} m/s is out of range: a march must "
                             "start with the walls rolling (> 0 m/s); speed_at slows them")
        self.speed_at = speed_at
        self.prob = prob
        self.grid = grid = Grid.build(prob)
        self.ops = Operators(prob, grid)
        self.h = h = np.nan_to_num(grid.h)
        d, u = grid.cell, prob.speed
        if start is None:
            X, Y = np.meshgrid(grid.x, grid.y)
            self.c = np.where((np.hypot(X, Y) < prob.initial_radius) & ~grid.island, h, 0.0)
        else:   # a full cell may hold more: it returns it
            self.c = oil_fraction_on(start, grid) * h
        self.dt = courant * d / u
        self.transit = (transit_length or (prob.x_range[1] - prob.x_range[0])) / u
        self.steps_per_transit = max(1, int(round(self.transit / self.dt)))
        self.q_in = float(self.ops.q_supply.sum())
        self.oil_start = self.oil()
        self.oil_in = self.oil_out_outlet = self.oil_out_side = 0.0
        self.oil_out_rows = np.zeros(len(grid.y))       # the outlet's, row by row [m3]
        self.flooded = (self.c >= h * (1.0 - 1e-9)) & ~grid.island
        self.p = np.full(self.c.shape, np.nan)
        self.steps = 0
        self.history: list[dict] = []
        self._out = self._dry = self._cavitated = self._in = 0.0
        self.gas = None if prob.gas is None else CavityGas(prob.gas, h, grid.hx, grid.hy, d, u)
        if self.gas is not None and start is not None and start.gas is not None:
            self.gas.n = gas_on(start, grid, self.cavity())   # the air of its bubbles
            self.gas.start = self.gas.held()

    def set_supply(self, layers: tuple[np.ndarray, np.ndarray]) -> None:
        """From the next step on, the walls bring in the lateral profiles ``layers`` (disc,
        ball) [m] on the grid's rows (:attr:`ThinFilmProblem.supply_layers`); the oil,
        the step and the accounts go on."""
        self.prob = replace(self.prob, supply_layers=(np.asarray(layers[0], float),
                                                      np.asarray(layers[1], float)))
        self.ops = Operators(replace(self.prob, speed=self.ops.u), self.grid)
        self.q_in = float(self.ops.q_supply.sum())

    @property
    def speed(self) -> float:
        """The walls' speed of the last step [m/s] (of the first before any)."""
        return self.ops.u

    def _follow_speed(self) -> None:
        """The walls' speed of the coming step (``speed_at`` at its middle): the operators
        and the gas's exchange rebuilt for it when it changed."""
        u = max(0.0, float(self.speed_at(self.time + 0.5 * self.dt)))
        if u == self.ops.u:
            return
        self.ops = Operators(replace(self.prob, speed=u), self.grid)
        self.q_in = float(self.ops.q_supply.sum())
        if self.gas is not None:
            self.gas.u = u

    @property
    def time(self) -> float:
        """Time marched [s]."""
        return self.steps * self.dt

    def oil(self) -> float:
        """The oil in the domain [m3, half domain]: every cell's content."""
        return float(self.c.sum()) * self.grid.cell ** 2

    def step(self) -> None:
        """One step; a transit's record is added to :attr:`history` after each
        ``steps_per_transit`` steps. With the walls at rest (a stop) the step is marched in
        sub-steps that resolve the capillary flow (:meth:`_at_rest`)."""
        if self.speed_at is not None:
            self._follow_speed()
        if self.ops.u > 0:
            self._advance(self._solve(self.dt), self.dt)
        else:
            self._at_rest()
        self.steps += 1
        if self.steps % self.steps_per_transit == 0:
            self.history.append(self._record())

    def _solve(self, dt: float) -> Step:
        """The step of ``dt`` [s] from the state now (:meth:`Operators.step`), nothing moved."""
        gas, c_old = self.gas, self.c
        return self.ops.step(self.flooded, c_old, dt,
                             None if gas is None else
                             lambda cav: gas.pressure(cav, c_old) - gas.k.ambient)

    def _at_rest(self) -> None:
        """The step with the walls at rest: only capillarity moves the oil, on a time scale
        of its own (6 eta d^2 / (sigma h) to fill a cell: some 1e-4 s on 0.2 a cells where
        the gap is 20 um), far shorter than a step sized by the rolling speed. The step is
        taken in sub-steps, each halved (at most ``REST_HALVINGS`` times) until no open cell
        would end it holding more than ``REST_OVERFILL`` of its gap beyond full; with a
        step too long, cells that flood overshoot by up to 1.5 times their gap, return it
        the next step and flood again, and a pocket of gas that the capillary pull should carry
        to the wider gap stays where it is."""
        left = self.dt
        while left > 1e-9 * self.dt:
            sub = left
            open_before = ~self.flooded & ~self.grid.island
            for halvings in range(REST_HALVINGS + 1):
                s = self._solve(sub)
                over = np.where(open_before, self.c + s.dc - self.h, 0.0)
                if halvings == REST_HALVINGS or not np.any(over > REST_OVERFILL * self.h):
                    break
                sub /= 2.0
            self._advance(s, sub)
            left -= sub

    def _advance(self, s: Step, dt: float) -> None:
        """Move the oil and the gas by the solved step ``s`` of ``dt`` [s] and book it."""
        gas = self.gas
        c_old, flooded_old = self.c, self.flooded
        self.c, self.flooded = advance_oil(self.c, s.dc, self.h, s.opened, s.cavitated,
                                           self.grid.island)
        if gas is not None:
            new, outer = self.ops.open_cells(self.flooded)   # a gas balance: a p_cav too
            gas.advance(s.cavity, c_old, new, outer, self.c,
                        flooded_old & ~s.opened & ~s.cavitated, dt)
        self.p = s.p
        self.oil_in += self.q_in * dt
        self._in += self.q_in * dt
        self.oil_out_outlet += s.q_outlet * dt
        self.oil_out_rows += s.outlet_rows * dt
        self.oil_out_side += s.q_side * dt
        self._out += (s.q_outlet + s.q_side) * dt
        self._dry += int(np.count_nonzero(s.opened))
        self._cavitated += int(np.count_nonzero(s.cavitated))

    def _record(self) -> dict:
        """The transit just marched: its time [s], the region's oil [m3, half domain], its
        flooded cells, outflow over supply, width [m], the flooded cells that ran dry within
        a step and those that opened to gas, and the cavities' cells now."""
        grid, d = self.grid, self.grid.cell
        region = connected_region(self.flooded, grid.island)
        rows = np.nonzero(region.any(axis=1))[0]
        rec = {"time_s": self.time,
               "oil_m3": float(np.sum(np.where(region, self.h, 0.0))) * d * d,
               "flooded_cells": int(region.sum()),
               "outflow_over_supply": self._out / self._in if self._in > 0 else 0.0,
               "width_m": float(2 * (grid.y[rows[-1]] + d / 2)) if rows.size else 0.0,
               "cells_opened_dry": int(self._dry),
               "cells_opened_to_gas": int(self._cavitated),
               "cavity_cells": int(self.cavity().sum())}
        if self.gas is not None:
            rec.update(gas_held_mol=self.gas.held(),
                       gas_pressure_Pa=self.gas.last.get("pressure_Pa", float("nan")),
                       **self.gas.budget)
        self._out = self._dry = self._cavitated = self._in = 0.0
        return rec

    def cavity(self) -> np.ndarray:
        """The open cells the flooded region encloses now, at the cavitation pressure (none
        without one)."""
        return self.ops.cavities(self.flooded)

    def balanced(self, tolerance: float, window: int) -> bool:
        """Over the last ``window`` transits the mean outflow is within ``tolerance`` of the
        supply and the region's oil changed by less than ``tolerance`` of itself."""
        h = self.history
        if tolerance <= 0 or len(h) <= window:
            return False
        change = abs(h[-1]["oil_m3"] - h[-1 - window]["oil_m3"])
        out = np.mean([r["outflow_over_supply"] for r in h[-window:]])
        return (change <= tolerance * h[-1]["oil_m3"] and abs(out - 1.0) <= tolerance
                and self.gas_settled(tolerance, window))

    def gas_settled(self, tolerance: float, window: int) -> bool:
        """With a gas balance: over the last ``window`` transits the air the cavities hold
        changed by less than ``tolerance`` of itself (or they hold none); True without one.
        The gas fills a bubble over tens of transits, slower than the oil settles."""
        h = self.history
        if self.gas is None:
            return True
        if len(h) <= window:
            return False
        now, then = h[-1]["gas_held_mol"], h[-1 - window]["gas_held_mol"]
        return abs(now - then) <= tolerance * max(now, then)

    def mass_balance_error(self) -> float:
        """The oil gained less what came in and went out since the start, over what came in
        (round-off: the model conserves the oil); 0 before anything came in."""
        residual = self.oil() - self.oil_start - self.oil_in + self.oil_out_outlet \
            + self.oil_out_side
        return abs(residual) / self.oil_in if self.oil_in > 0 else 0.0

    def solution(self, steady: bool = False) -> ThinFilmSolution:
        """The state now, as a :class:`ThinFilmSolution`."""
        h = self.history
        cavity = self.cavity()
        return ThinFilmSolution(
            grid=self.grid, p=np.where(self.flooded, self.p, np.nan), content=self.c,
            flooded=self.flooded, time=self.time, steps=self.steps, flux_in=self.q_in,
            flux_out=h[-1]["outflow_over_supply"] * self.q_in if h else 0.0,
            steady=steady, island_radius=self.prob.island_radius, history=list(h),
            mass_balance_error=self.mass_balance_error(),
            fill=np.where(self.flooded, 0.0, self.ops.fill(self.c, cavity))
            if self.ops.sub_cell else None,
            cavity=cavity, cavitation_pressure=self.prob.cavitation_pressure,
            gas=None if self.gas is None else self.gas.n.copy(),
            gas_pressure=None if self.gas is None else
            self.gas.pressure(cavity, self.c) - self.gas.k.ambient)


def solve_thin_film(prob: ThinFilmProblem, transits_max: float = 60.0,
                    tolerance: float = 0.01, transit_length: float | None = None,
                    start: ThinFilmSolution | None = None, courant: float = 0.25,
                    progress: Callable[[dict], None] | None = None,
                    window: int = 5) -> ThinFilmSolution:
    """March ``prob`` until steady or for ``transits_max`` transits (a transit:
    ``transit_length`` [m] at u, by default the domain's length). Steady: over the last
    ``window`` transits the mean outflow is within ``tolerance`` of the supply and the
    region's oil changed by less than ``tolerance`` of itself (0: march on to the end); the
    outflow of single transits swings by some 5 % about a slow fill, which one transit's
    reading took for a balance. ``start``: a solution (on any
    grid) whose oil fractions replace the initial puddle. ``courant``: the step over a cell's
    transit at u. ``progress`` is called with each transit's record."""
    m = Marcher(prob, start=start, courant=courant, transit_length=transit_length)
    steady = False
    while m.steps < transits_max * m.steps_per_transit:
        m.step()
        if m.steps % m.steps_per_transit:
            continue
        if progress:
            progress(m.history[-1])
        if m.balanced(tolerance, window):
            steady = True
            break
    return m.solution(steady)
