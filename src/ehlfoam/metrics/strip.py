"""What a strip case's writes say (:mod:`ehlfoam.case.strip`): its rear meniscus, the films
behind it, and what the wall cells do at a contact line.

The strip is one column of cells per x: its oil fraction, summed over a column, gives the oil
thickness there (both walls together). The rear meniscus is where the column's oil over its
gap crosses 0.5; the films are the oil behind it, and the deposited fraction is that over
the gap at the meniscus, the quantity Landau-Levich predicts. The theory these are compared
with is :mod:`ehlfoam.thinfilm.bridge`.

SI units: lengths in m, speeds in m/s, pressures in Pa; positions also over a where named
``_over_a``.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import numpy as np

from ehlfoam.foam.fieldfile import field_file
from ehlfoam.mesh import PolyMesh

__all__ = ["columns", "film_history", "rear_films", "wall_rows"]


def columns(mesh: PolyMesh, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per column of the strip, in x order: x [m], gap [m] and oil thickness [m, both walls
    together] for the cells' oil fraction ``alpha``."""
    disc = mesh.patch_slice("disc")
    base = mesh.base_cell[mesh.owner[disc]]
    n = int(mesh.base_cell.max()) + 1
    area, x_base = np.zeros(n), np.zeros(n)
    area[base] = np.linalg.norm(mesh.face_areas[disc], axis=1)
    x_base[base] = mesh.face_centres[disc, 0]
    volume = np.bincount(mesh.base_cell, mesh.cell_volumes, minlength=n)
    oil = np.bincount(mesh.base_cell, mesh.cell_volumes * np.clip(alpha, 0.0, 1.0), minlength=n)
    order = np.argsort(x_base)
    return x_base[order], volume[order] / area[order], oil[order] / area[order]


def rear_films(mesh: PolyMesh, alpha: np.ndarray, a: float, x_out: float) -> dict | None:
    """The rear meniscus of one write of the strip (``alpha``: the cells' oil fraction):
    ``x_rear_over_a`` and the gap there ``gap_rear_m`` (linear between the columns whose oil
    over the gap crosses 0.5), the films behind it ``film_m`` (the median oil thickness from
    x_rear + a to x_out - a / 2, both walls; NaN without columns there), their
    ``deposited_fraction`` of the gap at the meniscus, and the oil held per metre of width
    ``oil_per_width_m2``. None where no column upstream of a dry one holds oil."""
    x, h, oil = columns(mesh, alpha)
    frac = oil / h
    dry = np.flatnonzero(frac < 0.5)
    if not len(dry) or dry[0] == 0:
        return None
    k = dry[0]
    w = (frac[k - 1] - 0.5) / (frac[k - 1] - frac[k])
    x_r = x[k - 1] + w * (x[k] - x[k - 1])
    h_r = h[k - 1] + w * (h[k] - h[k - 1])
    behind = (x > x_r + a) & (x < x_out - 0.5 * a)
    film = float(np.median(oil[behind])) if behind.any() else float("nan")
    return {"x_rear_over_a": float(x_r / a), "gap_rear_m": float(h_r), "film_m": film,
            "deposited_fraction": film / h_r,
            "oil_per_width_m2": float(np.sum(np.clip(alpha, 0.0, 1.0) * mesh.cell_volumes)
                                      / np.ptp(mesh.points[:, 1]))}


def film_history(writes: Iterable[tuple[float, Path]], mesh: PolyMesh, a: float,
                 x_out: float) -> list[dict]:
    """:func:`rear_films` of each write (time [s], its folder; e.g.
    ``ehlfoam.run.fields.time_folders(case)``) that has a rear meniscus, with its time
    ``t_s``."""
    rows = []
    for t, folder in writes:
        alpha = np.asarray(field_file(Path(folder) / "alpha.oil").internal_field, float)
        row = rear_films(mesh, alpha, a, x_out)
        if row is not None:
            rows.append({"t_s": t, **row})
    return rows


def wall_rows(folder: Path, mesh: PolyMesh, u: float, x_m: float, reach: float) -> dict:
    """What the wall cells (the layers on the disc and on the ball) do at one write of the
    strip (``folder``), beside its mid-gap layer, around the meniscus at x_m [m]:

    - ``stalled_length_m``: the length of strip within ``reach`` [m] of the meniscus over which
      the wall cells, on both walls on average, move at less than half their wall's speed u
      [m/s] along x. Next to a moving contact line a wall's own cells move with it but for
      a slip length; a length of several cells is the numerical contact line's drag;
    - ``wall_air_fraction``: the mean air fraction of the wall cells in the flooded columns
      (above 99 % oil beyond their wall cells): air the walls carried in under the oil;
    - ``wall_pressure_excess_pa``: the median of the wall cells' p_rgh over their mid-gap
      cell's in those columns [Pa]: the contact angle's curvature on that air.
    """
    alpha = np.asarray(field_file(folder / "alpha.oil").internal_field, float)
    ux = np.asarray(field_file(folder / "U").internal_field, float)[:, 0]
    p = np.asarray(field_file(folder / "p_rgh").internal_field, float)
    n = int(mesh.layer.max()) + 1
    cols = np.zeros((int(mesh.base_cell.max()) + 1, n), int)
    cols[mesh.base_cell, mesh.layer] = np.arange(mesh.n_cells)
    cols = cols[np.argsort(mesh.cell_centres[cols[:, 0], 0])]
    x = mesh.cell_centres[cols[:, 0], 0]
    walls = cols[:, [0, n - 1]]
    moving = np.abs(ux[walls]).mean(axis=1) / u
    near = np.abs(x - x_m) <= reach
    stalled = float(np.sum(np.gradient(x)[near & (moving < 0.5)]))
    flooded = alpha[cols[:, 1:n - 1]].mean(axis=1) > 0.99
    if not flooded.any():
        return {"stalled_length_m": stalled, "wall_air_fraction": float("nan"),
                "wall_pressure_excess_pa": float("nan")}
    air = 1.0 - np.clip(alpha[walls[flooded]], 0.0, 1.0)
    excess = p[walls[flooded]] - p[cols[flooded, n // 2]][:, None]
    return {"stalled_length_m": stalled, "wall_air_fraction": float(air.mean()),
            "wall_pressure_excess_pa": float(np.median(excess))}
