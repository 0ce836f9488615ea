"""The flooded region in the thin-film limit: Reynolds flow inside capillary menisci.

The least model of the oil around the contact: the gap-averaged (Reynolds) flow of the oil
between two walls rolling at (u, 0), held by a meniscus whose capillary pressure is
Young-Laplace's across the gap, fed and drained only by the oil layers the walls carry. It
answers in seconds to minutes where the 3D interface cases take hours, on cells of any size,
so its flooded width can be converged on its own grid (``ehlfoam thin-film``).

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
through a face, lo -> hi:

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
puddle: 170.1 and 161.4 nl, 15.80 and 15.55 a wide on 0.05 a cells (docs/cases.md).

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
from dataclasses import dataclass, field
from typing import Literal, NamedTuple

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.linalg import spsolve


def landau_levich(eta: float, u: float, sigma: float) -> float:
    """Both walls' films over the gap [-] behind a meniscus receding at u between two walls
    (r = h / 2; Aussillous and Quere's fit of Landau-Levich)."""
    c = (eta * u / sigma) ** (2.0 / 3.0)
    return 2.0 * 1.34 * c * 0.5 / (1.0 + 3.35 * c)


@dataclass(frozen=True)
class ThinFilmProblem:
    """One thin-film problem, SI units.

    Attributes:
        gap: h(x, y) [m] for arrays x, y [m] (contact centre at the origin, rolling along +x).
        speed: u of both walls [m/s].
        viscosity: oil viscosity [Pa s].
        surface_tension: [N/m].
        contact_angle: static contact angle of the oil on both walls [deg].
        supply: oil carried in on the track, both walls together [m].
        track_half_width: half-width of the track [m].
        x_range: the domain along x [m]; it spans 0 <= y <= y_max [m].
        island_radius: the contact's island, no flow inside it [m].
        cell: cell size [m].
        initial_radius: radius of the flooded puddle at t = 0 [m].
        film_factor: multiplies Landau-Levich's films (1: the model).
        closed_side: the side y = y_max is a symmetry plane too, not open to the air (a
            strip of a problem that does not vary along y).
        receding_meniscus: the capillary pressure of a meniscus that the walls leave
            (at the region's rear): "static", Young-Laplace's
            -2 sigma cos(theta) / h like every other; "bretherton", that of a meniscus laying
            films (Park and Homsy 1984, Hele-Shaw): -(2 sigma / h) (1 + 3.8 Ca^(2/3)), with
            no contact angle (the walls behind it are wet), at the rear where the walls leave
            it square on; at Ca = 0.006 that draws 16 % harder than the static one. A number
            in [0.5, 2]: that factor on the static pressure there (to measure how much the
            region hangs on it). Either way the factor falls off as n^(2/3) where the walls
            leave the meniscus at an angle (n the x part of its outward normal; the films'
            Ca n) and is 1 where they run along it or into it.
        normal_length: the length [m] over which the flooded cells are smoothed (Gaussian
            standard deviation) for that normal; None: 1.5 cells. A length fixed in metres
            keeps the normal, and so the pull, the same on every grid; 1.5 cells of 0.1 a
            let single cells flipping at the meniscus swing n, and n^(2/3) is steep at small
            n, by pressures the size of those that shape the region (tens of Pa): the rear
            meniscus drained within a step and shed its oil in streaks.
        advancing_angle: the apparent contact angle [deg] of a meniscus the walls advance
            into from dry ground (off the track, where no supply layer meets it), where they
            meet it square on; None: the static angle. Cox-Voinov's theta^3 - theta_s^3 grows
            with the capillary number of the contact line's speed, so at an angle theta^3
            takes the share n of the step from theta_s^3 (n: the x part of the meniscus's
            inward normal, from the region smoothed over ``normal_length``). In a strip of
            interFoam with dry walls advancing at the nominal Ca = 0.0058 the meniscus
            settles at 44-51 deg on in-plane cells within some 15 wall cells, and holds no
            suction at all on coarser ones (:mod:`ehlfoam.case.strip`).
        meniscus_position: where a meniscus sits in the open cell beside a flooded one:
            "sub-cell", as far into it as the cell's bulk oil fills it (its oil beyond the
            layers or films the walls carry, over the rest of its gap), so that the
            meniscus, its pressure (at the gap there) and the flooded cell's conductance to
            it move smoothly as the cell fills; "cell", at the cell's centre, so that they
            jump a cell at a time as cells flood and open (the first version: its balance
            moved by 6-16 % at each halving of the step).
    """

    gap: Callable[[np.ndarray, np.ndarray], np.ndarray]
    speed: float
    viscosity: float
    surface_tension: float
    contact_angle: float
    supply: float
    track_half_width: float
    x_range: tuple[float, float]
    y_max: float
    island_radius: float
    cell: float
    initial_radius: float
    film_factor: float = 1.0
    closed_side: bool = False
    receding_meniscus: Literal["static", "bretherton"] | float = "static"
    normal_length: float | None = None
    advancing_angle: float | None = None
    meniscus_position: Literal["sub-cell", "cell"] = "sub-cell"

    def __post_init__(self) -> None:
        span = min(self.y_max / 2, (self.x_range[1] - self.x_range[0]) / 8)
        checks = {
            "speed": (self.speed, self.speed > 0, "> 0 m/s"),
            "viscosity": (self.viscosity, self.viscosity > 0, "> 0 Pa s"),
            "surface_tension": (self.surface_tension, self.surface_tension > 0, "> 0 N/m"),
            "contact_angle": (self.contact_angle, 0 <= self.contact_angle < 90,
                              "in [0, 90) deg"),
            "supply": (self.supply, self.supply >= 0, ">= 0 m"),
            "track_half_width": (self.track_half_width, self.track_half_width > 0, "> 0 m"),
            "island_radius": (self.island_radius, self.island_radius >= 0, ">= 0 m"),
            "x_range": (self.x_range, self.x_range[0] < -self.island_radius
                        and self.x_range[1] > self.island_radius, "around the island"),
            "y_max": (self.y_max, self.y_max > self.island_radius, "beyond the island"),
            "cell": (self.cell, 0 < self.cell <= span, f"in (0, {span:.3g}] m: two cells "
                                                      "across, eight along the domain"),
            "film_factor": (self.film_factor, self.film_factor > 0, "> 0"),
            "receding_meniscus": (self.receding_meniscus,
                                  self.receding_meniscus in ("static", "bretherton")
                                  or (isinstance(self.receding_meniscus, (int, float))
                                      and not isinstance(self.receding_meniscus, bool)
                                      and 0.5 <= self.receding_meniscus <= 2.0),
                                  "'static', 'bretherton' or a factor in [0.5, 2]"),
            "advancing_angle": (self.advancing_angle, self.advancing_angle is None
                                or self.contact_angle <= self.advancing_angle < 90,
                                f"None or in [{self.contact_angle:g}, 90) deg: the static "
                                "angle up to a right angle"),
            "normal_length": (self.normal_length, self.normal_length is None
                              or 0.5 * self.cell <= self.normal_length <= span,
                              f"None or in [{0.5 * self.cell:.3g}, {span:.3g}] m: half a "
                              "cell to the span of the cell's check"),
        }
        for name, (value, ok, valid) in checks.items():
            if not ok:
                raise ValueError(f"{name} = {value!r} is out of range: must be {valid}")

    @property
    def film(self) -> float:
        """Films a receding meniscus leaves on both walls, over the gap [-]."""
        return self.film_factor * landau_levich(self.viscosity, self.speed,
                                                self.surface_tension)


@dataclass
class Grid:
    """Cell centres x (nx,), y (ny,) [m], gaps at the cells and faces, the island."""

    x: np.ndarray
    y: np.ndarray
    h: np.ndarray        # (ny, nx), NaN in the island
    hx: np.ndarray       # (ny, nx - 1) on the x faces, NaN on the island's
    hy: np.ndarray       # (ny - 1, nx) on the y faces
    h_side: np.ndarray   # (nx,) on y = y_max
    island: np.ndarray   # (ny, nx) bool

    @property
    def cell(self) -> float:
        return float(self.x[1] - self.x[0])

    @classmethod
    def build(cls, prob: ThinFilmProblem) -> "Grid":
        d = prob.cell
        nx = int(round((prob.x_range[1] - prob.x_range[0]) / d))
        ny = int(round(prob.y_max / d))
        x = prob.x_range[0] + d * (np.arange(nx) + 0.5)
        y = d * (np.arange(ny) + 0.5)
        island = np.hypot(*np.meshgrid(x, y)) < prob.island_radius
        xf = prob.x_range[0] + d * np.arange(1, nx)
        yf = d * np.arange(1, ny)
        return cls(x=x, y=y, h=_gap(prob.gap, *np.meshgrid(x, y), island),
                   hx=_gap(prob.gap, *np.meshgrid(xf, y), island[:, 1:] | island[:, :-1]),
                   hy=_gap(prob.gap, *np.meshgrid(x, yf), island[1:] | island[:-1]),
                   h_side=_gap(prob.gap, x, np.full(nx, prob.y_max), np.zeros(nx, bool)),
                   island=island)


@dataclass
class ThinFilmSolution:
    """The state at the end of a march: the grid, p [Pa] (NaN where open), the oil c [m],
    ``flooded`` (bool, ny x nx), the time marched [s], the supply and the flux leaving the
    domain [m3/s] over the last transit (half domain), ``steady``, the record of each transit
    (time, the region's oil [m3, half domain], flooded cells, outflow / supply, width [m],
    the flooded cells that ran dry within a step: a sound march opens a few at most, and
    hundreds mean the step or the pull's normal drives the menisci unstably)
    and the oil mass balance error over the march (the oil gained less what came in and
    went out, over what came in); with sub-cell menisci, ``fill``: how far into each open
    cell its meniscus reaches (0-1)."""

    grid: Grid
    p: np.ndarray
    content: np.ndarray
    flooded: np.ndarray
    time: float
    steps: int
    flux_in: float
    flux_out: float
    steady: bool
    island_radius: float
    history: list[dict] = field(default_factory=list)
    mass_balance_error: float = 0.0
    fill: np.ndarray | None = None

    def region(self) -> np.ndarray:
        """The flooded cells connected to the island: the flooded region, bool (ny, nx)."""
        return connected_region(self.flooded, self.grid.island)

    def oil_fraction_at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The oil over the gap, c / h (0-1), of the cell holding each point (x, y) [m]:
        1 in the flooded cells, the films' share behind the menisci, in the island that of the
        nearest cell outside it (a 3D mesh's cells at the island's rim may lie in an island
        cell of this grid); NaN off the grid (beyond its x range or y_max). The grid is a half
        domain: y is taken as |y|."""
        h = self.grid.h
        frac = np.where(h > 0, self.content / np.where(h > 0, h, 1.0), 0.0)
        frac = np.where(self.flooded, 1.0, np.clip(frac, 0.0, 1.0))
        nearest = ndimage.distance_transform_edt(self.grid.island, return_distances=False,
                                                 return_indices=True)
        frac = frac[tuple(nearest)]
        x, y = np.broadcast_arrays(np.asarray(x, float), np.abs(np.asarray(y, float)))
        d = self.grid.cell
        off = ((x < self.grid.x[0] - d / 2) | (x > self.grid.x[-1] + d / 2)
               | (y > self.grid.y[-1] + d / 2))
        return np.where(off, np.nan, _nearest_cell(self.grid, frac, x, y))

    def metrics(self, a: float) -> dict:
        """The flow-pattern metrics of the CFD cases (runs/metrics.py), in units of a."""
        return region_metrics(self.region(), self.grid, a, self.island_radius, self.fill) | {
            "cell_over_a": self.grid.cell / a, "steady": self.steady, "steps": self.steps,
            "time_s": self.time, "oil_mass_balance_error": self.mass_balance_error,
            "outflow_over_supply": self.flux_out / self.flux_in if self.flux_in > 0 else None}


def connected_region(flooded: np.ndarray, island: np.ndarray) -> np.ndarray:
    """The flooded cells connected (4-neighbours) to the island."""
    labels, _ = ndimage.label(flooded | island)
    keep = np.unique(labels[island])
    return np.isin(labels, keep[keep > 0]) & ~island


def region_metrics(region: np.ndarray, grid: Grid, a: float, island_radius: float,
                   fill: np.ndarray | None = None) -> dict:
    """The state, the inlet meniscus's distance from x = -a on y = 0, the region's length and
    (full) width, its rear meniscus on y = 0 [units of a], its oil [m3, whole contact] and
    whether it reaches the domain's edge. State II: the air behind the island on y = 0
    reaches the open air (the wake is open); state I: it is enclosed, or there is none.
    The menisci are read at the flooded cells' faces, or, given ``fill`` (how far into each
    open cell its meniscus reaches, 0-1), that far beyond them."""
    d, x = grid.cell, grid.x
    fill = np.zeros(region.shape) if fill is None else np.where(region, 0.0, fill)
    beyond = np.pad(fill, 1)                           # the open cell past each face
    if not region.any():
        return {"state": "II", "inlet_meniscus_distance_over_a": None,
                "flooded_length_over_a": None, "flooded_width_over_a": None,
                "rear_meniscus_x_over_a": None, "oil_volume_m3": 0.0,
                "touches_boundary": False}
    air, _ = ndimage.label(~region & ~grid.island)
    edge = np.unique(np.r_[air[:, 0], air[:, -1], air[-1]])
    wake = air[0, np.argmax(x > island_radius)]
    row = region[0]
    up = np.nonzero(row & (x < 0))[0]
    down = np.nonzero(row & (x > 0))[0]
    cols = np.nonzero(region.any(axis=0))[0]
    tops = region.shape[0] - 1 - np.argmax(region[::-1], axis=0)   # each column's top cell
    edge_y = (grid.y[tops] + d / 2 + d * beyond[tops + 2, np.arange(len(x)) + 1])[cols]
    return {
        "state": "II" if wake and wake in edge[edge > 0] else "I",
        "inlet_meniscus_distance_over_a":
        float((-a - (x[up[0]] - d / 2 - d * beyond[1, up[0]])) / a) if up.size else None,
        "flooded_length_over_a": float((x[cols[-1]] - x[cols[0]] + d
                                        + d * beyond[1:-1, cols[0]][region[:, cols[0]]].max()
                                        + d * beyond[1:-1, cols[-1] + 2][region[:, cols[-1]]]
                                        .max()) / a),
        "flooded_width_over_a": float(2 * edge_y.max() / a),
        "rear_meniscus_x_over_a": float((x[down[-1]] + d / 2 + d * beyond[1, down[-1] + 2]) / a)
        if down.size else None,
        "oil_volume_m3": float(2 * np.sum(np.where(region, grid.h, 0.0))) * d * d,
        "touches_boundary": bool(region[:, 0].any() or region[:, -1].any() or region[-1].any()),
    }


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
    ops = _Operators(prob, grid)
    if start is None:
        X, Y = np.meshgrid(grid.x, grid.y)
        c = np.where((np.hypot(X, Y) < prob.initial_radius) & ~grid.island, h, 0.0)
    else:
        c = _interpolate(start, grid) * h              # a full cell may hold more: it returns it
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


class _Operators:
    """The face coefficients of one grid and the two halves of a step."""

    def __init__(self, prob: ThinFilmProblem, grid: Grid):
        d, u = grid.cell, prob.speed
        k = 1.0 / (12.0 * prob.viscosity)
        self.u, self.d = u, d
        self.h = np.nan_to_num(grid.h)
        self.island = grid.island
        self.gx = np.nan_to_num(k * grid.hx**3)        # square faces: conductance [m3/(Pa s)]
        self.gy = np.nan_to_num(k * grid.hy**3)
        self.cx = np.nan_to_num(u * grid.hx * d)       # Couette flux of a full x face [m3/s]
        self.g_side = 0.0 * grid.h_side if prob.closed_side else 2.0 * k * grid.h_side**3
        self.g_out = 2.0 * self.gx[:, -1] if self.gx.shape[1] else np.zeros(0)
        self.cx_out = np.nan_to_num(u * grid.h[:, -1] * d)
        self.theta_s = np.radians(prob.contact_angle)
        cos_t = np.cos(self.theta_s)
        if prob.receding_meniscus == "bretherton":   # the pull where the walls leave at u
            ca = prob.viscosity * u / prob.surface_tension
            self.pull = (1.0 + 3.8 * ca ** (2.0 / 3.0)) / cos_t
        elif prob.receding_meniscus == "static":
            self.pull = 1.0
        else:
            self.pull = float(prob.receding_meniscus)
        self.normal_sigma = 1.5 if prob.normal_length is None else prob.normal_length / d
        self.film = prob.film
        self.cap = prob.film * self.h                  # what a meniscus cell passes on [m]
        on_track = np.clip((prob.track_half_width - (grid.y - d / 2)) / d, 0.0, 1.0)
        self.q_supply = u * prob.supply * on_track * d  # into column 0 [m3/s]
        self.young_laplace = 2.0 * prob.surface_tension * cos_t   # pcap = -it / h [N/m]
        self.theta_a = None if prob.advancing_angle is None else np.radians(prob.advancing_angle)
        self.dry = 1.0 - on_track[:, None]             # walls coming in dry: off the track
        self.sub_cell = prob.meniscus_position == "sub-cell"
        # the oil an open cell holds as the walls' layers, not as meniscus: the supply's
        # layers ahead of the contact, the films elsewhere [m]
        ahead = (grid.x < 0)[None, :] & np.ones_like(self.island)
        self.layers = np.where(ahead, np.maximum(prob.supply * on_track[:, None], self.cap),
                               self.cap)

    def pull_factor(self, flooded: np.ndarray) -> np.ndarray | float:
        """The dynamic menisci's pressure on every cell, a factor on the static one. The
        receding pull, 1 + (pull - 1) n^(2/3) where the walls leave the meniscus at u n (n:
        the x part of its outward normal, from the flooded cells smoothed over
        ``normal_length``; Ca n is the capillary number of the films it lays); the advancing
        angle, cos(theta) / cos(theta_s) with theta^3 = theta_s^3 + m (theta_a^3 - theta_s^3)
        where the walls come in dry (off the track) and run into the meniscus at u m. So a
        meniscus at an angle to u is not left to the staircase of the cells; 1 with static
        menisci."""
        if self.pull == 1.0 and self.theta_a is None:
            return 1.0
        phi = ndimage.gaussian_filter(flooded.astype(float), self.normal_sigma,
                                      mode="nearest")
        gy, gx = np.gradient(phi)
        nx = -gx / np.maximum(np.hypot(gx, gy), 1e-12)
        factor = 1.0 + (self.pull - 1.0) * np.clip(nx, 0.0, 1.0) ** (2.0 / 3.0)
        if self.theta_a is not None:
            m = np.clip(-nx, 0.0, 1.0)
            theta = np.cbrt(self.theta_s**3 + m * (self.theta_a**3 - self.theta_s**3))
            factor = factor + self.dry * (np.cos(theta) / np.cos(self.theta_s) - 1.0)
        return factor

    def fill(self, c: np.ndarray) -> np.ndarray:
        """How far into each cell a meniscus beside it reaches: the cell's bulk oil (beyond
        the walls' layers) over its room for it, 0-1."""
        room = self.h - self.layers
        return np.clip((c - self.layers) / np.where(room > 0, room, 1.0), 0.0, 1.0)

    def menisci(self, flooded: np.ndarray, c: np.ndarray) -> "_Faces":
        """Each face between a flooded cell and an open one: the flooded cell's conductance
        to the meniscus and the meniscus's pressure, for x faces and y faces. The meniscus
        sits theta cells from the flooded cell's centre, at the gap there (linear between
        the two centres), conductance g / theta: sub-cell, theta = 1/2 + the open cell's
        fill; cell, theta = 1 (the open cell's centre). Its pressure: Young-Laplace's,
        times the dynamic menisci's factor (``pull_factor``)."""
        factor = np.broadcast_to(self.pull_factor(flooded), flooded.shape)
        theta = 0.5 + self.fill(c) if self.sub_cell else np.ones_like(c)
        per_axis = {}
        for axis, g in ((1, self.gx), (0, self.gy)):
            lo = [slice(None), slice(None)]
            hi = [slice(None), slice(None)]
            lo[axis], hi[axis] = slice(None, -1), slice(1, None)
            lo, hi = tuple(lo), tuple(hi)
            hi_open = flooded[lo] & ~flooded[hi]        # else the lo side is the open one
            th = np.where(hi_open, theta[hi], theta[lo])
            h_f = np.where(hi_open, self.h[lo], self.h[hi])
            h_o = np.where(hi_open, self.h[hi], self.h[lo])
            h_m = h_f + th * (h_o - h_f)
            safe = np.where(h_m > 0, h_m, 1.0)          # faces on the island carry nothing
            suction = np.where(hi_open, factor[hi], factor[lo]) * self.young_laplace / safe
            per_axis[axis] = (g / th, np.where(h_m > 0, -suction, 0.0), h_m)
        (gx, px, hx), (gy, py, _) = per_axis[1], per_axis[0]
        return _Faces(gx=gx, gy=gy, px=px, py=py, hx=hx)

    def pressure(self, flooded: np.ndarray, c: np.ndarray, dt: float,
                 faces: "_Faces") -> np.ndarray:
        """p on the flooded cells, the menisci at ``faces``' pressures: each flooded cell's
        outflow is what it holds beyond its gap / dt."""
        ny, nx = flooded.shape
        n = int(flooded.sum())
        p = np.full((ny, nx), np.nan)
        if n == 0:
            return p
        idx = -np.ones((ny, nx), dtype=np.int64)
        idx[flooded] = np.arange(n)
        rows, cols, vals = [], [], []
        rhs = ((c - self.h) * self.d * self.d / dt)[flooded]
        carried = self.u * c * self.d                  # what an open cell's walls carry on
        zeros_y = np.zeros_like(self.gy)
        for lo, hi, g, gm, full, open_lo, pm in (
                (idx[:, :-1], idx[:, 1:], self.gx, faces.gx, self.cx, carried[:, :-1],
                 faces.px),
                (idx[:-1], idx[1:], self.gy, faces.gy, zeros_y, zeros_y, faces.py)):
            lo, hi, g, gm = lo.ravel(), hi.ravel(), g.ravel(), gm.ravel()
            full, open_lo, pm = full.ravel(), open_lo.ravel(), pm.ravel()
            both = (lo >= 0) & (hi >= 0) & (g > 0)
            a, b, gg = lo[both], hi[both], g[both]
            rows += [a, b, a, b]
            cols += [a, b, b, a]
            vals += [gg, gg, -gg, -gg]
            np.add.at(rhs, a, -full[both])
            np.add.at(rhs, b, full[both])
            sel = (lo >= 0) & (hi < 0) & (g > 0)       # flooded lo, meniscus in hi
            rows.append(lo[sel]), cols.append(lo[sel]), vals.append(gm[sel])
            np.add.at(rhs, lo[sel], -full[sel] + gm[sel] * pm[sel])
            sel = (lo < 0) & (hi >= 0) & (g > 0)       # meniscus in lo, flooded hi
            rows.append(hi[sel]), cols.append(hi[sel]), vals.append(gm[sel])
            np.add.at(rhs, hi[sel], open_lo[sel] + gm[sel] * pm[sel])
        first, side, last = idx[:, 0], idx[-1], idx[:, -1]
        np.add.at(rhs, first[first >= 0], self.q_supply[first >= 0])
        rows.append(side[side >= 0]), cols.append(side[side >= 0])
        vals.append(self.g_side[side >= 0])
        rows.append(last[last >= 0]), cols.append(last[last >= 0])
        vals.append(self.g_out[last >= 0])
        np.add.at(rhs, last[last >= 0], -self.cx_out[last >= 0])
        A = coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                       shape=(n, n)).tocsr()
        p[flooded] = spsolve(A, rhs, permc_spec="MMD_AT_PLUS_A")
        return p

    def step(self, flooded: np.ndarray, c: np.ndarray, dt: float):
        """One step: (p, change of the oil [m], flux leaving the domain [m3/s], the flooded
        cells opened). An open cell gives no more than it holds: the flooded cells drawing
        on it get less and run short of a full gap (air comes in: they open next step). A
        flooded cell that would run dry within the step opens now, and p is solved again."""
        opened = np.zeros_like(flooded)
        for _ in range(1000):
            faces = self.menisci(flooded, c)
            p = self.pressure(flooded, c, dt, faces)
            dc, q_out = self.move(flooded, p, c, dt, faces)
            dry = flooded & (c + dc < 0.0)
            if not dry.any():
                return p, dc, q_out, opened
            opened |= dry
            flooded = flooded & ~dry
        raise RuntimeError("the flooded set did not settle within a step")

    def move(self, flooded: np.ndarray, p: np.ndarray, c: np.ndarray, dt: float,
             faces: "_Faces"):
        """The change of the oil in every cell over dt [m] and the flux leaving the domain
        [m3/s], the menisci at ``faces``. An open cell gives no more than it holds: what
        the flooded region draws from it is cut back first (the flooded cell runs short of a
        full gap), the films and layers it passes on only when that is not enough."""
        u, d = self.u, self.d
        fl, fr = flooded[:, :-1], flooded[:, 1:]
        touch = _touches(flooded) & ~self.island
        # x faces lo -> hi: Poiseuille where a side is flooded, plus what the walls carry:
        # a full gap out of a flooded cell, the films a receding meniscus lays out of the
        # cell behind one, at most those films out of a cell beside one, else the layers
        lays = fl[:, :-1] & ~flooded[:, 1:-1] & ~flooded[:, 2:]
        carry = np.where(touch[:, :-1] & ~fr, np.minimum(c[:, :-1], self.cap[:, :-1]),
                         c[:, :-1])
        carry[:, 1:] = np.where(lays, self.film * faces.hx[:, :-1], carry[:, 1:])
        qx = _face_flux(fl, fr, p[:, :-1], p[:, 1:], self.gx, faces.gx, faces.px)
        qx += np.where(fl, self.cx, u * carry * d * (self.gx > 0))
        qy = _face_flux(flooded[:-1], flooded[1:], p[:-1], p[1:], self.gy, faces.gy, faces.py)
        q_side = np.where(flooded[-1], self.g_side * p[-1], 0.0)
        q_last = np.where(flooded[:, -1], self.cx_out + self.g_out * p[:, -1],
                          u * c[:, -1] * d)
        held = c * d * d / dt                          # [m3/s] over the step
        opn = ~flooded & ~self.island
        # faces on which an open cell gives to a flooded one (lo -> hi positive, hi -> lo
        # negative)
        draw_x = (~fl & fr & (qx > 0)) | (fl & ~fr & (qx < 0))
        draw_y = ((~flooded[:-1] & flooded[1:] & (qy > 0))
                  | (flooded[:-1] & ~flooded[1:] & (qy < 0)))
        layer = np.zeros_like(flooded)                 # the cells behind a receding meniscus
        layer[:, 1:-1] = lays
        for only_draws in (True, False):
            if not only_draws:                         # films are laid from the region's oil
                net = _net(qx, qy, q_last, q_side, self.q_supply)
                deficit = np.where(layer & opn, np.clip(-(held + net), 0.0, None), 0.0)
                qx += deficit[:, 1:]
            for _ in range(100):
                net = _net(qx, qy, q_last, q_side, self.q_supply)
                short = opn & (held + net < -1e-12 * self.h * d * d / dt)
                if not short.any():
                    break
                mx = draw_x if only_draws else np.ones_like(draw_x)
                my = draw_y if only_draws else np.ones_like(draw_y)
                give = _given(qx * mx, qy * my, 0 * q_last if only_draws else q_last,
                              0 * q_side if only_draws else q_side)
                short &= give > 0
                if not short.any():
                    break
                room = (held + net + give) / np.where(short, give, 1.0)
                scale = np.where(short, np.clip(room, 0.0, 1.0 - 1e-12), 1.0)
                sx = np.where(qx > 0, scale[:, :-1], scale[:, 1:])
                sy = np.where(qy > 0, scale[:-1], scale[1:])
                qx = np.where(mx, qx * sx, qx)
                qy = np.where(my, qy * sy, qy)
                if not only_draws:
                    q_last = q_last * scale[:, -1]
                    q_side = q_side * scale[-1]
        net = _net(qx, qy, q_last, q_side, self.q_supply)
        return net * dt / (d * d), float(q_last.sum() + q_side.sum())


class _Faces(NamedTuple):
    """Per face, lo -> hi: the conductance to a meniscus, its pressure [Pa] and (x faces) the
    gap there (used where one side is flooded and the other open), x faces (ny, nx - 1) and
    y faces (ny - 1, nx)."""

    gx: np.ndarray
    gy: np.ndarray
    px: np.ndarray
    py: np.ndarray
    hx: np.ndarray    # the gap at the meniscus on x faces [m]: a receding one lays f of it


def _face_flux(f_lo, f_hi, p_lo, p_hi, g, g_m, p_m):
    """Poiseuille flux lo -> hi [m3/s]: between two flooded cells, or from a flooded cell to
    the meniscus in its open neighbour (conductance g_m, pressure p_m); none between open
    cells."""
    return np.where(f_lo & f_hi, g * (p_lo - p_hi),
                    np.where(f_lo & ~f_hi, g_m * (p_lo - p_m),
                             np.where(~f_lo & f_hi, g_m * (p_m - p_hi), 0.0)))


def _net(qx, qy, q_last, q_side, q_supply):
    """Net inflow of every cell [m3/s] from the face fluxes (lo -> hi), the supply into the
    first column and the outflow through the last one and the side."""
    ny, nx = qy.shape[0] + 1, qx.shape[1] + 1
    net = np.zeros((ny, nx))
    net[:, :-1] -= qx
    net[:, 1:] += qx
    net[:-1] -= qy
    net[1:] += qy
    net[:, 0] += q_supply
    net[:, -1] -= q_last
    net[-1] -= q_side
    return net


def _given(qx, qy, q_last, q_side):
    """What every cell gives up [m3/s]: its outgoing face fluxes."""
    ny, nx = qy.shape[0] + 1, qx.shape[1] + 1
    out = np.zeros((ny, nx))
    out[:, :-1] += np.clip(qx, 0, None)
    out[:, 1:] += np.clip(-qx, 0, None)
    out[:-1] += np.clip(qy, 0, None)
    out[1:] += np.clip(-qy, 0, None)
    out[:, -1] += np.clip(q_last, 0, None)
    out[-1] += np.clip(q_side, 0, None)
    return out


def _touches(flooded: np.ndarray) -> np.ndarray:
    """Cells with a flooded 4-neighbour."""
    t = np.zeros_like(flooded)
    t[1:] |= flooded[:-1]
    t[:-1] |= flooded[1:]
    t[:, 1:] |= flooded[:, :-1]
    t[:, :-1] |= flooded[:, 1:]
    return t & ~flooded


def _nearest_cell(grid: Grid, values: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``values`` (ny, nx) of ``grid``'s cell nearest each point (x, y) [m] (the edge cells'
    beyond the grid)."""
    from scipy.interpolate import RegularGridInterpolator

    f = RegularGridInterpolator((grid.y, grid.x), values, method="nearest")
    pts = np.column_stack([np.clip(np.ravel(y), grid.y[0], grid.y[-1]),
                           np.clip(np.ravel(x), grid.x[0], grid.x[-1])])
    return f(pts).reshape(np.shape(x))


def _interpolate(sol: ThinFilmSolution, grid: Grid) -> np.ndarray:
    """The oil fraction c / h of ``sol`` at the cells of ``grid`` (nearest cell)."""
    frac = np.where(sol.grid.h > 0, sol.content / np.where(sol.grid.h > 0, sol.grid.h, 1), 0.0)
    X, Y = np.meshgrid(grid.x, grid.y)
    return np.where(grid.island, 0.0, _nearest_cell(sol.grid, np.nan_to_num(frac), X, Y))


def _gap(gap, X, Y, solid) -> np.ndarray:
    out = np.full(np.shape(X), np.nan)
    ok = ~np.asarray(solid)
    out[ok] = gap(np.asarray(X)[ok], np.asarray(Y)[ok])
    return out
