"""Start a ramp step from the previous step's final fields.

A speed ramp runs its steps one after the other; each new case starts from the oil, velocity
and pressure its predecessor ended with, so that a flow pattern can persist past the speed at
which it would not form from the standard start (hysteresis).

Consecutive speeds at one load share the base mesh: the Hertzian radius a, hence the domain and
the in-plane cells, depend on the load only, and the gap heights differ by nanometres. Then the
final internal fields are copied cell by cell (exact, the equivalent of mapFields on an
identical mesh). If the meshes differ (other cell count or in-plane positions), they are
interpolated layer by layer across the gap (:mod:`.field_mapping`; OpenFOAM's mapFields crashes
on these meshes), the oil put back to the previous case's volume. Either way only the internal
fields are taken over: the boundary conditions stay those of the new case (walls at the new
speed).

The seeded fields are written into the new case's ``0.orig/`` (its initial condition, copied
to ``0/`` by the run, and by the case's own Allrun), and ``ehlfoam/ramp.json`` records where
they came from.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import Any

import numpy as np
from foamlib import FoamFieldFile

from ehlfoam._io import atomic_write_json
from ehlfoam.case.writer import META, load_geometry

from ehlfoam.run.fields import Structure, time_folders
from ehlfoam.seed.mapping import LayeredMesh, carry_oil, interpolate

#: The fields a ramp step takes over (internal values only) when its 0.orig/ has them:
#: alpha.oil, U, p_rgh (interFoam), also p and T (compressibleInterFoam).
FIELDS = ("alpha.oil", "U", "p_rgh", "p", "T")
#: In-plane cell centres closer than this fraction of a count as the same mesh. A cell's
#: centroid moves sideways by ~1e-4 a when the gap above it changes by nanometres (measured
#: 6e-5 a between 10 and 20 mm/s); the smallest cells are 0.055 a (fine level).
SAME_MESH_TOL = 1e-3


#: The largest median difference between a start's gaps (a thin-film state's, a snapshot's)
#: and a case's, relative to the case's: a start of the same contact differs by its
#: sampling only (under 1 %), one of another load or radius by tens of per cent.
GAP_TOLERANCE = 0.05


class RampError(RuntimeError):
    """The previous ramp step has nothing to start from."""


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
    return FoamFieldFile(path).internal_field


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
    """Internal fields interpolated onto the new mesh layer by layer (:mod:`.field_mapping`),
    the oil at the previous case's volume (:func:`.field_mapping.carry_oil`, whose record
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


def _write_internal(path: Path, value: Any) -> None:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 1 and len(arr) in (3, 6, 9):
        # foamlib writes such scalar lists as a vector/tensor (see ehlfoam.case.writer)
        raise RampError(f"{path}: a {len(arr)}-cell field cannot be written safely")
    with FoamFieldFile(path) as f:
        f.internal_field = value


def seed_from_previous(case: str | Path, previous: str | Path) -> dict[str, Any]:
    """Write ``previous``'s final internal fields (alpha.oil, U, p_rgh; p and T too in a
    compressible scene) as the initial fields of ``case`` (its ``0.orig/``), by copy on the
    same mesh, else interpolated layer by layer (:mod:`.field_mapping`).

    Returns (and writes to ``case/ehlfoam/ramp.json``) {"previous" (relative to the case),
    "previous_time_s", "method", "fields", "oil" (how the oil was carried over, see
    :func:`.field_mapping.carry_oil`; None for a copy), "cells"}.
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


def write_seed(case: Path, fields: dict[str, Any], info: dict[str, Any]) -> dict[str, Any]:
    """Write ``fields`` (name -> internal values) as ``case``'s initial fields (``0.orig/``),
    drop a stale ``0/`` that would shadow them, and record ``info`` and the case's cell count
    in ``ehlfoam/ramp.json``; returns that record."""
    for name, value in fields.items():
        _write_internal(case / "0.orig" / name, value)
    if (case / "0").exists():      # a stale start folder would shadow 0.orig
        shutil.rmtree(case / "0")
    info = {**info, "cells": load_geometry(case).cells}
    atomic_write_json(case / META / "ramp.json", info)
    return info


def check_same_gap(their_gap: np.ndarray, s: Structure, source: str | Path) -> None:
    """Raise :class:`RampError` when ``their_gap`` [m] (a start's gaps at the case's
    columns, NaN where it has none) differs from the case's own columns' gaps (their volume
    over their footprint) by more than :data:`GAP_TOLERANCE` (median relative difference
    over the columns it covers): a start of another contact."""
    gap = s.column_gaps()
    on = np.isfinite(their_gap)
    diff = float(np.median(np.abs(their_gap[on] / gap[on] - 1.0))) if on.any() else np.inf
    if not diff <= GAP_TOLERANCE:
        raise RampError(f"{source}: its gaps differ from the case's by {diff:.1%} (median over "
                        f"the columns it covers; at most {GAP_TOLERANCE:.0%}): a start of "
                        "another contact (load, radius or oil)?")


def is_thin_film_state(source: str | Path) -> bool:
    """True when ``source`` names a thin-film state (a ``.npz`` that is no case snapshot)
    rather than a run case or a snapshot (:mod:`.case_snapshot`)."""
    from ehlfoam.seed.snapshot import is_snapshot

    return Path(source).suffix == ".npz" and not is_snapshot(source)


def check_start(source: str | Path) -> None:
    """Raise :class:`RampError` (or OSError) unless ``source`` can start a case: a run case
    with a written time, a case snapshot, or a readable thin-film state. Call it before
    writing anything."""
    from ehlfoam.seed.snapshot import is_snapshot

    if is_snapshot(source):
        return
    if not is_thin_film_state(source):
        final_time(source)
        return
    from ehlfoam.thinfilm.state import load_state

    try:
        load_state(source)
    except (OSError, KeyError, ValueError) as err:
        raise RampError(f"{source} is not a thin-film state written by "
                        f"`ehlfoam thin-film` ({err})") from None


def seed_case(case: str | Path, source: str | Path) -> dict[str, Any]:
    """Start ``case`` from ``source``: a run case's final fields (:func:`seed_from_previous`),
    a case snapshot's (:func:`ehlfoam.seed.snapshot.seed_from_snapshot`) or a thin-film state's
    oil (:func:`ehlfoam.seed.thin_film.seed_from_thin_film`)."""
    from ehlfoam.seed.snapshot import is_snapshot, seed_from_snapshot

    if is_snapshot(source):
        return seed_from_snapshot(case, source)
    if is_thin_film_state(source):
        from ehlfoam.seed.thin_film import seed_from_thin_film

        return seed_from_thin_film(case, source)
    return seed_from_previous(case, source)
