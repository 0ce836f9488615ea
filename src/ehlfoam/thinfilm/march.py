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

import numpy as np

from ehlfoam.thinfilm.operators import Operators
from ehlfoam.thinfilm.problem import Grid, ThinFilmProblem
from ehlfoam.thinfilm.solution import ThinFilmSolution, connected_region, oil_fraction_on


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
    grid = Grid.build(prob)
    d, u = grid.cell, prob.speed
    h = np.nan_to_num(grid.h)
    ops = Operators(prob, grid)
    if start is None:
        X, Y = np.meshgrid(grid.x, grid.y)
        c = np.where((np.hypot(X, Y) < prob.initial_radius) & ~grid.island, h, 0.0)
    else:
        c = oil_fraction_on(start, grid) * h              # a full cell may hold more: it returns it
    dt = courant * d / u
    transit = (transit_length or (prob.x_range[1] - prob.x_range[0])) / u
    steps_per_transit = max(1, int(round(transit / dt)))
    q_in = float(ops.q_supply.sum())
    oil_start = float(c.sum()) * d * d
    oil_in = oil_out = out_this_transit = 0.0
    dry_this_transit = 0
    history: list[dict] = []
    steady = False
    step = 0
    flooded = (c >= h * (1.0 - 1e-9)) & ~grid.island
    p = np.full(c.shape, np.nan)
    while step < transits_max * steps_per_transit:
        p, dc, q_out, opened = ops.step(flooded, c, dt)
        c = c + dc
        flooded = (c >= h * (1.0 - 1e-9)) & ~opened & ~grid.island
        step += 1
        oil_in += q_in * dt
        oil_out += q_out * dt
        out_this_transit += q_out * dt
        dry_this_transit += int(opened.sum())
        if step % steps_per_transit:
            continue
        region = connected_region(flooded, grid.island)
        rows = np.nonzero(region.any(axis=1))[0]
        rec = {"time_s": step * dt, "oil_m3": float(np.sum(np.where(region, h, 0.0))) * d * d,
               "flooded_cells": int(region.sum()),
               "outflow_over_supply": out_this_transit / (q_in * steps_per_transit * dt)
               if q_in > 0 else 0.0,
               "width_m": float(2 * (grid.y[rows[-1]] + d / 2)) if rows.size else 0.0,
               "cells_opened_dry": dry_this_transit}
        history.append(rec)
        out_this_transit, dry_this_transit = 0.0, 0
        if progress:
            progress(rec)
        if tolerance > 0 and len(history) > window:
            change = abs(rec["oil_m3"] - history[-1 - window]["oil_m3"])
            out = np.mean([r["outflow_over_supply"] for r in history[-window:]])
            if change <= tolerance * rec["oil_m3"] and abs(out - 1.0) <= tolerance:
                steady = True
                break
    oil_end = float(c.sum()) * d * d
    return ThinFilmSolution(
        grid=grid, p=np.where(flooded, p, np.nan), content=c, flooded=flooded,
        time=step * dt, steps=step, flux_in=q_in,
        flux_out=history[-1]["outflow_over_supply"] * q_in if history else 0.0,
        steady=steady, island_radius=prob.island_radius, history=history,
        mass_balance_error=abs(oil_end - oil_start - oil_in + oil_out) / oil_in
        if oil_in > 0 else 0.0,
        fill=np.where(flooded, 0.0, ops.fill(c)) if ops.sub_cell else None)
