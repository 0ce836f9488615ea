"""The newest written fields of a case, read with pyvista's OpenFOAM reader.

The reader needs a ``*.foam`` file in the case folder and would scan every time folder; the
case itself is never written to: a temporary folder holds ``case.foam`` and links to
``constant/``, ``system/`` and the newest complete time folder only, so a report costs the
same after 4 writes as after 400.

The mid-gap oil fraction and its raster come from :mod:`ehlfoam.run.fields` and
:mod:`ehlfoam.metrics.pattern`, the very functions the metrics use, so the pictures and the numbers
agree. Pressure ``p`` is gauge (0 = ambient at the open boundaries) in the interface scene;
an absolute pressure (cavitating scene) is turned into gauge here.
"""

from __future__ import annotations

import functools
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ehlfoam.case.geometry import CaseGeometry
from ehlfoam.foam.fieldfile import is_complete
from ehlfoam.metrics import pattern as flow
from ehlfoam.run.fields import Structure, column_raster, time_folders

#: Cell fields read from the newest time (those present).
FIELD_NAMES = ("alpha.oil", "U", "p", "p_rgh")
#: How many of the newest time folders are tried before giving up (a running case may be
#: writing the newest one).
TRIES = 3


def newest_complete_time(case: Path) -> tuple[float, Path] | None:
    """(time [s], folder) of the newest time folder (after 0) whose alpha.oil is complete."""
    folders = time_folders(case)
    for t, folder in reversed(folders[-TRIES:]):
        if is_complete(folder / "alpha.oil"):
            return t, folder
    return None


def read_internal_mesh(case: Path, folder: Path):
    """The internal mesh with the cell fields of time folder ``folder`` (pyvista
    UnstructuredGrid, SI). Only that folder is visible to the reader."""
    import pyvista as pv

    with tempfile.TemporaryDirectory(prefix="ehlfoam-report-") as tmp:
        tmp = Path(tmp)
        for name in ("constant", "system"):
            os.symlink((case / name).absolute(), tmp / name)
        os.symlink(folder.absolute(), tmp / folder.name)
        (tmp / "case.foam").write_text("")
        reader = pv.OpenFOAMReader(str(tmp / "case.foam"))
        reader.disable_all_patch_arrays()
        reader.enable_patch_array("internalMesh")
        reader.cell_to_point_creation = False
        reader.disable_all_cell_arrays()
        for name in FIELD_NAMES:
            if name in reader.cell_array_names:
                reader.enable_cell_array(name)
        reader.set_active_time_value(reader.time_values[-1])
        data = reader.read()
    mesh = data["internalMesh"] if "internalMesh" in data.keys() else data[0]
    return mesh


@dataclass(eq=False)
class Fields:
    """The fields of one written time; ``mesh`` is pyvista's internal mesh (cells in
    OpenFOAM's order), ``structure`` the generator's base-cell/layer map of it."""

    time: float
    folder: Path
    mesh: object
    structure: Structure
    geom: CaseGeometry
    gauge_offset: float = 0.0     # Pa subtracted from p to make it gauge

    def cell(self, name: str) -> np.ndarray | None:
        """A cell field (SI) or None if it was not written."""
        if name not in self.mesh.cell_data:
            return None
        return np.asarray(self.mesh.cell_data[name])

    @functools.cached_property
    def pressure(self) -> np.ndarray | None:
        """Gauge pressure per cell [Pa] (p, or p_rgh without gravity)."""
        p = self.cell("p")
        if p is None:
            p = self.cell("p_rgh")
        return None if p is None else p - self.gauge_offset

    def mid_gap(self, values: np.ndarray) -> np.ndarray:
        """Per base cell, the mid-gap value of a cell field."""
        return self.structure.mid_gap(values, self.geom.n_layers)

    @functools.cached_property
    def mid_alpha(self) -> np.ndarray:
        """Oil fraction at mid-gap per base cell (what the metrics read)."""
        return self.mid_gap(self.cell("alpha.oil"))

    @functools.cached_property
    def raster(self) -> flow.Raster:
        """The mid-gap oil fraction on the metrics' raster (a/20, full mirrored domain)."""
        return column_raster(self.mid_alpha, self.structure, self.geom)

    @functools.cached_property
    def pattern(self) -> dict:
        """Flow-pattern metrics of this time (same function as metrics.json's)."""
        return flow.flow_pattern_from_raster(self.raster)


def load_fields(case: str | os.PathLike, geom: CaseGeometry, scene: str = "interface",
                ambient_pressure: float = 1.013e5) -> Fields | None:
    """The newest complete fields of ``case``, or None when no time after 0 was written.
    Raises (OSError, ValueError, KeyError) when the files are there but unreadable."""
    case = Path(case)
    newest = newest_complete_time(case)
    if newest is None:
        return None
    t, folder = newest
    mesh = read_internal_mesh(case, folder)
    structure = Structure.load(case)
    if mesh.n_cells != len(structure.cell_volumes):
        raise ValueError(f"{folder}: {mesh.n_cells} cells read, the mesh has "
                         f"{len(structure.cell_volumes)}")
    if "alpha.oil" not in mesh.cell_data:
        raise KeyError(f"{folder}: no alpha.oil")
    offset = ambient_pressure if scene == "cavitating" else 0.0
    return Fields(time=t, folder=folder, mesh=mesh, structure=structure, geom=geom,
                  gauge_offset=offset)
