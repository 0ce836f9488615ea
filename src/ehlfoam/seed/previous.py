"""Start a ramp step from the previous step's final fields.

A speed ramp runs its steps one after the other; each new case starts from the oil, velocity
and pressure its predecessor ended with, so that a flow pattern can persist past the speed at
which it would not form from the standard start (hysteresis).

Consecutive speeds at one load share the base mesh: the Hertzian radius a, hence the domain and
the in-plane cells, depend on the load only, and the gap heights differ by nanometres. Then the
final internal fields are copied cell by cell (exact, the equivalent of mapFields on an
identical mesh). If the meshes differ (other cell count or in-plane positions), they are
interpolated layer by layer across the gap (:mod:`.mapping`; OpenFOAM's mapFields crashes
on these meshes), the oil put back to the previous case's volume. Either way only the internal
fields are taken over: the boundary conditions stay those of the new case (walls at the new
speed).

The seeded fields are written into the new case's ``0.orig/`` (its initial condition, copied
to ``0/`` by the run, and by the case's own Allrun), and ``ehlfoam/ramp.json`` records where
they came from.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from ehlfoam.case.geometry import META, load_geometry
from ehlfoam.foam.fieldfile import field_file
from ehlfoam.run.fields import Structure, time_folders
from ehlfoam.seed.mapping import LayeredMesh, carry_oil, interpolate
from ehlfoam.seed.write import RampError, write_seed

#: The fields a ramp step takes over (internal values only) when its 0.orig/ has them:
#: alpha.oil, U, p_rgh (interFoam), also p and T (compressibleInterFoam).
FIELDS = ("alpha.oil", "U", "p_rgh", "p", "T")
#: In-plane cell centres closer than this fraction of a count as the same mesh. A cell's
#: centroid moves sideways by ~1e-4 a when the gap above it changes by nanometres (measured
#: 6e-5 a between 10 and 20 mm/s); the smallest cells are 0.055 a (fine level).
SAME_MESH_TOL = 1e-3


def final_time(case: str | Path) -> tuple[float, Path]:
    """The last written time [s] of a finished case and its folder."""
    folders = time_folders(case)
    if not folders:
        raise RampError(f"case {case} has no written time to start a ramp step from")
    return folders[-1]


def same_mesh(case: str | Path, previous: str | Path) -> bool:
    """True when both cases have the same cells in the same in-plane places (so that the
    internal fields can be copied cell by cell)."""
    g_new, g_old = load_geometry(case), load_geometry(previous)
    if g_new.cells != g_old.cells:
        return False
    new, old = np.load(Path(case) / META / "mesh.npz"), np.load(Path(previous) / META / "mesh.npz")
    for key in ("base_cell", "layer"):
        if not np.array_equal(new[key], old[key]):
            return False
    return bool(np.allclose(new["cell_centres"][:, :2], old["cell_centres"][:, :2], rtol=0.0,
                            atol=SAME_MESH_TOL * g_new.a))


def _read_internal(path: Path) -> Any:
    return field_file(path).internal_field


def fields_to_carry(case: Path, folder: Path) -> list[str]:
    """The fields of :data:`FIELDS` that the new case starts from (its 0.orig/) and the
    previous case wrote (its final time folder)."""
    names = [n for n in FIELDS if (case / "0.orig" / n).is_file() and (folder / n).is_file()]
    if "alpha.oil" not in names:
        raise RampError(f"no alpha.oil to carry from {folder} into {case}")
    return names


def _copied_fields(folder: Path, names: list[str]) -> dict[str, Any]:
    return {name: _read_internal(folder / name) for name in names}


def _mapped_fields(case: Path, previous: Path, folder: Path, names: list[str]
                   ) -> tuple[dict[str, Any], dict[str, Any] | None]:
    """Internal fields interpolated onto the new mesh layer by layer (:mod:`.mapping`),
    the oil at the previous case's volume (:func:`.mapping.carry_oil`, whose record
    comes second); a uniform field is taken over as it is."""
    theirs, own = Structure.load(previous), Structure.load(case)
    source, target = LayeredMesh.of(theirs), LayeredMesh.of(own)
    out: dict[str, Any] = {}
    oil = None
    for name in names:
        value = _read_internal(folder / name)
        arr = np.asarray(value, dtype=float)
        uniform = arr.ndim == 0 or (arr.ndim == 1 and len(arr) != len(source.base_cell))
        out[name] = value if uniform else interpolate(arr, source, target)
        if name == "alpha.oil" and not uniform:
            v = theirs.cell_volumes
            out[name], oil = carry_oil(out[name], own.cell_volumes,
                                       float(v @ np.clip(arr, 0.0, 1.0)), float(v.sum()))
    return out, oil


def seed_from_previous(case: str | Path, previous: str | Path) -> dict[str, Any]:
    """Write ``previous``'s final internal fields (alpha.oil, U, p_rgh; p and T too in a
    compressible scene) as the initial fields of ``case`` (its ``0.orig/``), by copy on the
    same mesh, else interpolated layer by layer (:mod:`.mapping`).

    Returns (and writes to ``case/ehlfoam/ramp.json``) {"previous" (relative to the case),
    "previous_time_s", "method", "fields", "oil" (how the oil was carried over, see
    :func:`.mapping.carry_oil`; None for a copy), "cells"}.
    """
    case, previous = Path(case).absolute(), Path(previous).absolute()
    t, folder = final_time(previous)
    names = fields_to_carry(case, folder)
    if same_mesh(case, previous):
        fields, method, oil = _copied_fields(folder, names), "copy", None
    else:
        (fields, oil), method = _mapped_fields(case, previous, folder, names), "interpolated"
    return write_seed(case, fields, {"previous": os.path.relpath(previous, case),
                                     "previous_time_s": t, "method": method, "fields": names,
                                     "oil": oil})
