"""A thin-film case (``scene = "thin-film"``): a case folder that the gap-averaged model runs,
without OpenFOAM.

    spec -> gap (ehlfoam.gap, cached) -> the model's grid (ehlfoam.thinfilm) -> case folder

The folder holds what a 3D case's holds for the run, the metrics and the reports, and no
OpenFOAM files: ``ehlfoam/spec.json``, ``ehlfoam/geometry.json`` (a :class:`CaseGeometry`
whose solver is "thin-film", its cells the grid's), ``ehlfoam/thin_film.json`` (the grid and
the model's options: the marker of a thin-film case), ``precalc/`` (the EHL precalc the gap
comes from) and, when it starts from a state, ``ehlfoam/start.npz``. ``ehlfoam run DIR``
marches it (:mod:`ehlfoam.run.thin_film`) and writes ``metrics.json``, ``history.csv``,
``state.npz`` and ``log.thin-film``. Like a 3D case it is built in a temporary folder, marked
the tool's own (``ehlfoam/case.json``) and put in place by
:func:`ehlfoam.case.writer.write_case`.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from ehlfoam._io import atomic_write_json, atomic_write_text, link_tree
from ehlfoam.case.geometry import META, CaseGeometry
from ehlfoam.gap.source import load_gap
from ehlfoam.spec.case import CaseSpec
from ehlfoam.spec.thin_film import thin_film_cells
from ehlfoam.thinfilm.from_spec import problem_from_spec, scene_options
from ehlfoam.thinfilm.problem import Grid

__all__ = ["MARKER", "START", "is_thin_film_case", "read_marker", "thin_film_case"]

#: in ``ehlfoam/``: the grid and the options of a thin-film case (its marker), and the state
#: it starts from
MARKER, START = "thin_film.json", "start.npz"


def is_thin_film_case(case: str | os.PathLike) -> bool:
    """True for a case folder written for ``scene = "thin-film"``."""
    return (Path(case) / META / MARKER).is_file()


def read_marker(case: str | os.PathLike) -> dict[str, Any]:
    """The ``ehlfoam/thin_film.json`` of a thin-film case: its grid (cell [a] and [m], nx,
    ny, the cells outside the island), domain [a], options and step [s]."""
    return json.loads((Path(case) / META / MARKER).read_text())


def thin_film_case(spec: CaseSpec) -> tuple[CaseGeometry, Callable[[Path], None]]:
    """The thin-film case of ``spec``: its :class:`CaseGeometry` and the function that writes
    its files into a (temporary, empty) case folder. The EHL precalc is solved or reused
    here; :func:`ehlfoam.case.writer.write_case` builds the folder, marks it the tool's own
    and puts it in place."""
    gap, precalc = load_gap(spec.contact)
    options = scene_options(spec)
    prob = problem_from_spec(spec, gap, options)
    x, y, island = Grid.layout(prob)      # the run builds the gaps
    cells = int((~island).sum())
    a, d = spec.a, float(x[1] - x[0])     # as Grid.cell
    dt = spec.thin_film.courant * d / spec.speed
    summary = json.loads((precalc / "summary.json").read_text())
    hc = float(summary["hc_m"])
    box = spec.domain.box(a)
    geom = CaseGeometry(
        a=a, radius=spec.contact.radius, speed=spec.speed, x_min=box.x_min, x_max=box.x_max,
        y_max=box.y_max, island_radius=box.island_radius, symmetric=True, n_layers=1,
        cells=cells, transit_time=spec.transit_time, end_time=spec.end_time,
        write_interval=spec.transit_time / spec.run.writes_per_transit, max_delta_t=dt,
        capillary_limit="none", min_cell_size=d,
        island_gap=float(gap(np.array([box.island_radius]), np.array([0.0]))[0]),
        hc=hc, contact_flow=spec.speed * hc * 2.0 * a, gap_mismatch=0.0,
        oil_viscosity=spec.oil_viscosity, oil_density=spec.oil_density, solver=spec.solver,
        ambient_pressure=spec.physics.ambient_pressure)
    marker = {"cell_over_a": options.cell, "cell_m": d, "nx": len(x), "ny": len(y),
              "grid_cells": thin_film_cells(spec), "cells": cells,
              "domain_over_a": list(options.domain), "options": asdict(options),
              "cavitation_pressure_gauge_Pa": prob.cavitation_pressure, "time_step_s": dt}

    def fill(folder: Path) -> None:
        meta = folder / META
        meta.mkdir()
        atomic_write_text(meta / "spec.json", spec.model_dump_json(indent=2) + "\n")
        atomic_write_json(meta / "geometry.json", asdict(geom))
        atomic_write_json(meta / MARKER, marker)
        link_tree(precalc, folder / "precalc")

    return geom, fill
