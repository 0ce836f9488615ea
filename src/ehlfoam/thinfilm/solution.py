"""A marched thin-film state (:class:`ThinFilmSolution`) and what is read off it: the flooded
region and its flow-pattern metrics, the oil fraction at any point."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from ehlfoam.thinfilm.problem import Grid


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
    cell its meniscus reaches (0-1; in a cavity its film content over its gap); with the
    outlet model, ``cavity``: the open cells whose gas the region encloses, at the gauge
    ``cavitation_pressure`` [Pa] (:mod:`ehlfoam.thinfilm.cavity`); with the gas balance
    (:mod:`ehlfoam.thinfilm.gas`), ``gas``: the air each cavity cell holds [mol, half
    domain] and ``gas_pressure``: its cavity's gas pressure [Pa, gauge; NaN elsewhere]."""

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
    cavity: np.ndarray | None = None
    cavitation_pressure: float | None = None
    gas: np.ndarray | None = None
    gas_pressure: np.ndarray | None = None

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

    def mid_gap_alpha(self) -> np.ndarray:
        """What a 3D case's mid-gap oil fraction would read in each cell (ny, nx; NaN in the
        island), for the flow-pattern metrics of the 3D cases (:mod:`ehlfoam.metrics.pattern`,
        which read the alpha = 0.5 crossing between cell centres linearly): 1 in the flooded
        cells; in an open cell beside them, f / (1/2 + f) for the meniscus's fill f (0-1), so
        that the crossing falls where the model puts the meniscus, 1/2 + f cells from the
        flooded cell's centre; 0 where the walls carry only films or layers (gas at
        mid-gap). In a cavity f is the film content over the gap."""
        f = np.zeros(self.flooded.shape) if self.fill is None else np.clip(self.fill, 0, 1)
        alpha = np.where(self.flooded, 1.0, f / (0.5 + f))
        return np.where(self.grid.island, np.nan, alpha)

    def gauge_pressure(self) -> np.ndarray:
        """The pressure of every cell [Pa, gauge; NaN in the island]: the solved one in the
        flooded cells, the cavitation pressure in the cavities (their gas's, with the gas
        balance), 0 (ambient) in the outer air."""
        gas = np.zeros(self.flooded.shape)
        if self.cavity is not None and self.cavitation_pressure is not None:
            at = self.cavitation_pressure if self.gas_pressure is None else \
                np.nan_to_num(self.gas_pressure, nan=self.cavitation_pressure)
            gas = np.where(self.cavity, at, 0.0)
        p = np.where(self.flooded, np.nan_to_num(self.p), gas)
        return np.where(self.grid.island, np.nan, p)

    def metrics(self, a: float) -> dict:
        """The flow-pattern metrics of the CFD cases (ehlfoam.metrics.pattern), in units of a."""
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


def _nearest_cell(grid: Grid, values: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``values`` (ny, nx) of ``grid``'s cell nearest each point (x, y) [m] (the edge cells'
    beyond the grid)."""
    from scipy.interpolate import RegularGridInterpolator

    f = RegularGridInterpolator((grid.y, grid.x), values, method="nearest")
    pts = np.column_stack([np.clip(np.ravel(y), grid.y[0], grid.y[-1]),
                           np.clip(np.ravel(x), grid.x[0], grid.x[-1])])
    return f(pts).reshape(np.shape(x))


def oil_fraction_on(sol: ThinFilmSolution, grid: Grid) -> np.ndarray:
    """The oil fraction c / h of ``sol`` at the cells of ``grid`` (nearest cell; 0 in the
    island)."""
    frac = np.where(sol.grid.h > 0, sol.content / np.where(sol.grid.h > 0, sol.grid.h, 1), 0.0)
    X, Y = np.meshgrid(grid.x, grid.y)
    return np.where(grid.island, 0.0, _nearest_cell(sol.grid, np.nan_to_num(frac), X, Y))


def gas_on(sol: ThinFilmSolution, grid: Grid, cavity: np.ndarray) -> np.ndarray:
    """The air [mol] that the cavities of ``sol`` hold, on the cells ``cavity`` of ``grid``:
    the same cells' amounts on the same grid; on another grid, the amount per area of the
    nearest cell, scaled so that the total is the state's (a bubble refined or coarsened keeps
    its air, so its pressure starts where it was; a cell the start's cavity did not cover
    starts empty, its cavity's pressure set by the whole cavity's air). None held, or no
    cavity to hold it: zeros."""
    n = np.nan_to_num(np.asarray(sol.gas, float))
    if np.array_equal(sol.grid.x, grid.x) and np.array_equal(sol.grid.y, grid.y):
        return np.where(cavity, n, 0.0)
    X, Y = np.meshgrid(grid.x, grid.y)
    per_area = _nearest_cell(sol.grid, n / sol.grid.cell ** 2, X, Y)
    out = np.where(cavity, per_area * grid.cell ** 2, 0.0)
    total, got = float(n.sum()), float(out.sum())
    return out * (total / got) if got > 0 else out
