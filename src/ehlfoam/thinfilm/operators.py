"""The discrete thin-film model on one grid: the faces' conductances and Couette fluxes, the
menisci's positions and pressures, the pressure solve on the flooded cells and the oil each
step moves (:class:`Operators`; the model: :mod:`ehlfoam.thinfilm.march`; its outlet, the
cavities at the cavitation pressure: :mod:`ehlfoam.thinfilm.cavity`)."""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from scipy import ndimage
from scipy.sparse import csr_matrix
from scipy.sparse.linalg import spsolve

from ehlfoam.thinfilm.cavity import cavities_and_outer_air
from ehlfoam.thinfilm.kernels import fill, pressure_on_grid
from ehlfoam.thinfilm.pass_kernels import (DONE, NEEDS_LU, PassConstants, after_pressure,
                                           flooded_pressure, menisci, one_pass,
                                           passes)
from ehlfoam.thinfilm.problem import Grid, ThinFilmProblem


class Operators:
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
        if prob.supply_layers is None:
            on_track = np.clip((prob.track_half_width - (grid.y - d / 2)) / d, 0.0, 1.0)
            self.q_supply = u * prob.supply * on_track * d  # into column 0 [m3/s]
            incoming = prob.supply * on_track           # the layers coming in, each row [m]
        else:                                           # lateral profiles (a cycle's)
            incoming, on_track = prob.supply_rows(grid.y)
            self.q_supply = u * incoming * d
        self.young_laplace = 2.0 * prob.surface_tension * cos_t   # pcap = -it / h [N/m]
        self.theta_a = None if prob.advancing_angle is None else np.radians(prob.advancing_angle)
        self.dry = 1.0 - on_track[:, None]             # walls coming in dry: off the track
        self.sub_cell = prob.meniscus_position == "sub-cell"
        self.p_cav = prob.cavitation_pressure          # gauge [Pa] or None
        self.closed_side = prob.closed_side
        # the oil an open cell holds as the walls' layers, not as meniscus: the supply's
        # layers ahead of the contact, the films elsewhere [m]
        ahead = (grid.x < 0)[None, :] & np.ones_like(self.island)
        self.layers = np.where(ahead, np.maximum(incoming[:, None], self.cap), self.cap)
        self._ones = np.ones_like(self.h)              # the static menisci's factor
        self._none = np.zeros_like(self.island)        # no cells
        self.k = PassConstants(
            h=self.h, layers=self.layers, island=self.island, gx=self.gx, gy=self.gy,
            cx=self.cx, cap=self.cap, film=float(self.film), u=float(u), d=float(d),
            g_side=np.ascontiguousarray(self.g_side, dtype=float), g_out=self.g_out,
            cx_out=self.cx_out, q_supply=np.ascontiguousarray(self.q_supply, dtype=float),
            short=-1e-12 * self.h * d * d,             # a cell short of oil: below it / dt
            young_laplace=float(self.young_laplace),
            p_cav=0.0 if self.p_cav is None else float(self.p_cav),
            has_cav=self.p_cav is not None, closed_side=bool(self.closed_side),
            sub_cell=bool(self.sub_cell))

    def pull_factor(self, flooded: np.ndarray) -> np.ndarray | float:
        """The dynamic menisci's pressure on every cell, a factor on the static one. The
        receding pull, 1 + (pull - 1) n^(2/3) where the walls leave the meniscus at u n (n:
        the x part of its outward normal, from the flooded cells smoothed over
        ``normal_length``; Ca n is the capillary number of the films it lays); the advancing
        angle, cos(theta) / cos(theta_s) with theta^3 = theta_s^3 + m (theta_a^3 - theta_s^3)
        where the walls come in dry (off the track) and run into the meniscus at u m. So a
        meniscus at an angle to u is not left to the staircase of the cells; 1 with static
        menisci."""
        if self.static_menisci:
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

    def fill(self, c: np.ndarray, cavity: np.ndarray | None = None) -> np.ndarray:
        """How far into each cell a meniscus beside it reaches: the cell's bulk oil (beyond
        the walls' layers) over its room for it, 0-1; in a cavity, its film content over
        its gap (the oil the walls carry through it: Elrod-Adams's fraction)."""
        if cavity is None:
            cavity = np.zeros(c.shape, dtype=bool)
        return fill(c, self.h, self.layers, cavity)

    def cavities(self, flooded: np.ndarray, before: np.ndarray | None = None) -> np.ndarray:
        """The open cells whose gas the flooded region encloses, at the cavitation pressure
        (:func:`ehlfoam.thinfilm.cavity.cavities`; ``before``: the outer air of a flooded
        set that held this one); none without one."""
        return self.open_cells(flooded, before)[0]

    def open_cells(self, flooded: np.ndarray,
                   before: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray | None]:
        """:meth:`cavities` and the outer air they were told from (None without a
        cavitation pressure): the open cells, not island, are the two together."""
        if self.p_cav is None:
            return np.zeros_like(flooded), None
        return cavities_and_outer_air(flooded, self.island, self.closed_side, before)

    def menisci(self, flooded: np.ndarray, c: np.ndarray,
                cavity: np.ndarray | None = None,
                gas: np.ndarray | None = None) -> "_Faces":
        """Each face between a flooded cell and an open one: the flooded cell's conductance
        to the meniscus and the meniscus's pressure, for x faces and y faces. The meniscus
        sits theta cells from the flooded cell's centre, at the gap there (linear between
        the two centres), conductance g / theta: sub-cell, theta = 1/2 + the open cell's
        fill; cell, theta = 1 (the open cell's centre). Its pressure: Young-Laplace's,
        times the dynamic menisci's factor (``pull_factor``), but no lower than the
        cavitation pressure; a cavity's boundary (``cavity``: the open cells the region
        encloses) is at the cavitation pressure, or, with ``gas`` (every cavity cell's gas
        pressure, gauge [Pa]: the gas balance, :mod:`ehlfoam.thinfilm.gas`), a meniscus
        like the outer air's, Young-Laplace's below that gas pressure, floored alike."""
        if cavity is None:
            cavity = np.zeros_like(flooded)
        return _Faces(*menisci(flooded, c, cavity, self._factor(flooded),
                               *self._gas(gas), self.k))

    def pressure(self, flooded: np.ndarray, c: np.ndarray, dt: float,
                 faces: "_Faces") -> np.ndarray:
        """p on the flooded cells, the menisci at ``faces``' pressures: each flooded cell's
        outflow is what it holds beyond its gap / dt."""
        p, ok, *system = flooded_pressure(flooded, c, dt, faces.gx, faces.gy, faces.px,
                                          faces.py, self.k, MAX_BAND)
        return p if ok else _by_lu(*system)

    def step(self, flooded: np.ndarray, c: np.ndarray, dt: float,
             gas: Callable[[np.ndarray], np.ndarray] | None = None) -> "Step":
        """One step (:class:`Step`). An open cell gives no more than it holds: the flooded
        cells drawing on it get less and run short of a full gap (air comes in: they open
        next step). A flooded cell that would run dry within the step opens now, and one
        whose pressure falls below the cavitation pressure opens to gas now (its oil stays:
        Elrod-Adams's complementarity, :mod:`ehlfoam.thinfilm.cavity`); p is solved again
        until neither happens. ``gas``: the cavities' gas pressures (gauge [Pa] on their
        cells) for a set of cavity cells, where a gas balance sets them
        (:mod:`ehlfoam.thinfilm.gas`); None: at the cavitation pressure.

        Each pass is one kernel (:func:`~ehlfoam.thinfilm.pass_kernels.one_pass`), and
        without a gas balance, with static menisci, the passes are one call
        (:func:`~ehlfoam.thinfilm.pass_kernels.passes`) but where sparse LU must solve
        the pressure; the oil's moves in a pass: the change of every cell's oil and the
        fluxes through the outlet and the side. An open cell gives no more than it holds:
        what the flooded region draws from it is cut back first (the flooded cell runs
        short of a full gap), the films and layers it passes on only when that is not
        enough; a cavity's cells pass on all the oil they hold, as no air meniscus holds
        it back."""
        opened = np.zeros_like(flooded)
        cavitated = np.zeros_like(flooded)
        outer = None        # the outer air of the last pass: each pass only opens cells
        for _ in range(1000):
            if gas is None and self.static_menisci:     # passes until done, in one call
                status, flooded, cavity, found, p, dc, q_last, q_side, faces, system = \
                    passes(flooded, c, dt, self._none if outer is None else outer,
                           outer is not None, self._ones, opened, cavitated, self.k,
                           MAX_BAND)
            else:
                status, flooded, cavity, found, p, dc, q_last, q_side, faces, system = \
                    self._pass(flooded, c, dt, gas, outer, opened, cavitated)
            if self.p_cav is not None:
                outer = found
            if status == NEEDS_LU:
                p = _by_lu(*system)
                status, flooded, dc, q_last, q_side = after_pressure(
                    flooded, p, c, dt, cavity, *faces, opened, cavitated, self.k)
            if status == DONE:
                return Step(p, dc, float(q_last.sum()), float(q_side.sum()), opened,
                            cavitated, cavity, q_last)
        raise RuntimeError("the flooded set did not settle within a step")

    def _pass(self, flooded: np.ndarray, c: np.ndarray, dt: float,
              gas: Callable[[np.ndarray], np.ndarray] | None, outer: np.ndarray | None,
              opened: np.ndarray, cavitated: np.ndarray) -> tuple:
        """One pass of :meth:`step` (:func:`one_pass`), its menisci's factor and, with a gas
        balance, the gas pressures of the cavities it finds, from Python."""
        if gas is None:
            cavity, pressures = self._none, None
        else:           # the gas balance's pressures are those of the cavities found
            cavity, outer = self.open_cells(flooded, outer)
            pressures = gas(cavity) if cavity.any() else None
        return one_pass(flooded, c, dt, cavity, self._none if outer is None else outer,
                        gas is None, outer is not None, self._factor(flooded),
                        *self._gas(pressures), opened, cavitated, self.k, MAX_BAND)

    @property
    def static_menisci(self) -> bool:
        """Whether the menisci's factor is 1 everywhere (:meth:`pull_factor`): static
        menisci, no advancing angle."""
        return self.pull == 1.0 and self.theta_a is None

    def _factor(self, flooded: np.ndarray) -> np.ndarray:
        """The dynamic menisci's factor on every cell (:meth:`pull_factor`), as an array."""
        factor = self.pull_factor(flooded)
        return self._ones if np.isscalar(factor) else np.ascontiguousarray(factor, dtype=float)

    def _gas(self, gas: np.ndarray | None) -> tuple[np.ndarray, bool]:
        """The cavities' gas pressures as the menisci read them, and whether there are any
        (there are not without a cavitation pressure)."""
        if gas is None or self.p_cav is None:
            return self.h, False
        return np.ascontiguousarray(gas, dtype=float), True


class Step(NamedTuple):
    """What one step did: p [Pa, gauge] on the flooded cells (NaN elsewhere), the change of
    every cell's oil [m], the fluxes leaving through the outlet and the side [m3/s], the
    flooded cells it opened as they ran dry, those it opened to gas (below the cavitation
    pressure), the cavities' cells (the open cells the region enclosed, at the
    cavitation pressure) and the outlet's flux on each row [m3/s] (what the walls carry out
    of the last column: the lateral profile of the oil the contact leaves behind)."""

    p: np.ndarray
    dc: np.ndarray
    q_outlet: float
    q_side: float
    opened: np.ndarray
    cavitated: np.ndarray
    cavity: np.ndarray
    outlet_rows: np.ndarray | None = None


class _Faces(NamedTuple):
    """Per face, lo -> hi: the conductance to a meniscus, its pressure [Pa] and (x faces) the
    gap there (used where one side is flooded and the other open), x faces (ny, nx - 1) and
    y faces (ny - 1, nx)."""

    gx: np.ndarray
    gy: np.ndarray
    px: np.ndarray
    py: np.ndarray
    hx: np.ndarray    # the gap at the meniscus on x faces [m]: a receding one lays f of it


#: the widest band (cells) solved as a band; sparse LU beyond, where the band's n b^2 loses
#: (measured on full rectangles: 0.14 against 1.9 ms at a band of 15, even at 50, LU 1.5
#: times faster at 64)
MAX_BAND = 48


def _by_lu(data: np.ndarray, indices: np.ndarray, indptr: np.ndarray, rhs: np.ndarray,
           idx: np.ndarray) -> np.ndarray:
    """p on the grid (NaN off the flooded cells) from the flooded cells' system (CSR, the
    right-hand side and the cells' numbers) by sparse LU: where the banded Cholesky solve
    refuses it, as its band (the region's narrower side, in cells) is wider than
    ``MAX_BAND`` or a pivot is not positive."""
    n = rhs.size
    x = spsolve(csr_matrix((data, indices, indptr), shape=(n, n)), rhs,
                permc_spec="MMD_AT_PLUS_A")
    return pressure_on_grid(idx, np.atleast_1d(x))


def touches(flooded: np.ndarray) -> np.ndarray:
    """Cells with a flooded 4-neighbour."""
    t = np.zeros_like(flooded)
    t[1:] |= flooded[:-1]
    t[:-1] |= flooded[1:]
    t[:, 1:] |= flooded[:, :-1]
    t[:, :-1] |= flooded[:, 1:]
    return t & ~flooded
