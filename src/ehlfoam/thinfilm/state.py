"""A thin-film state on disc: the grid, oil and pressure of a ``ThinFilmSolution``.

``ehlfoam thin-film`` (:mod:`ehlfoam.thinfilm.from_spec`) writes one per run (``.npz``); it
starts the next run of the thin-film model (``--start``), and a 3D case can start from it
(``ehlfoam case --start-from STATE.npz``, :mod:`ehlfoam.seed.thin_film`): the model reaches
the flooded region's balance in minutes where a 3D run from a puddle takes hours.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ehlfoam._io import atomic_write
from ehlfoam.thinfilm.problem import Grid
from ehlfoam.thinfilm.solution import ThinFilmSolution


def save_state(sol: ThinFilmSolution, path: str | Path) -> None:
    """Write the cell centres x, y [m], gaps h [m], ``flooded``, oil content c [m], pressure
    p [Pa], the menisci's fills, the time [s] and steps marched and, with the outlet model,
    the cavities' cells and the cavitation pressure [Pa, gauge] (with the gas balance the
    air its cavity cells hold [mol] and their gas pressure [Pa, gauge]) of ``sol`` to ``path``
    (.npz), atomically."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fill = np.zeros(sol.flooded.shape) if sol.fill is None else sol.fill
    extra = {} if sol.cavity is None else {"cavity": sol.cavity}
    if sol.cavitation_pressure is not None:
        extra["cavitation_pressure"] = np.float64(sol.cavitation_pressure)
    if sol.gas is not None:
        extra["gas_mol"] = sol.gas
    if sol.gas_pressure is not None:
        extra["gas_pressure"] = sol.gas_pressure
    atomic_write(path, lambda fh: np.savez_compressed(
        fh, x=sol.grid.x, y=sol.grid.y, h=sol.grid.h, flooded=sol.flooded,
        content=sol.content, p=sol.p, fill=fill, time_s=np.float64(sol.time),
        steps=np.int64(sol.steps), **extra))


def load_state(path: str | Path) -> ThinFilmSolution:
    """A state written by ``save_state``, enough of it to start a run from (its grid's cells,
    gaps and oil) and to read its flow: its pressure (NaN throughout in a state written before
    states kept it), its menisci's fills (None there), its cavities and time (none and 0
    in a state written before states kept them)."""
    with np.load(path) as d:
        grid = Grid(x=d["x"], y=d["y"], h=d["h"], hx=np.empty((0, 0)), hy=np.empty((0, 0)),
                    h_side=np.empty(0), island=np.isnan(d["h"]))
        return ThinFilmSolution(
            grid=grid, p=d["p"] if "p" in d else np.full(d["h"].shape, np.nan),
            content=d["content"], flooded=d["flooded"],
            time=float(d["time_s"]) if "time_s" in d else 0.0,
            steps=int(d["steps"]) if "steps" in d else 0,
            flux_in=0.0, flux_out=0.0, steady=False, island_radius=0.0,
            fill=d["fill"] if "fill" in d else None,
            cavity=d["cavity"] if "cavity" in d else None,
            cavitation_pressure=float(d["cavitation_pressure"])
            if "cavitation_pressure" in d else None,
            gas=d["gas_mol"] if "gas_mol" in d else None,
            gas_pressure=d["gas_pressure"] if "gas_pressure" in d else None)
