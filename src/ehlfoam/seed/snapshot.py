"""A run case's state in one small file, to start other cases from (``ehlfoam snapshot``).

A run folder holds its mesh and every written time, tens to hundreds of MB, and run folders
are not part of the repository: a study that runs for hours over several sessions or machines
loses its states with the folder. What another case needs to go on from a write is the oil
(alpha.oil) and the velocity (U) there, and enough of the mesh to interpolate them layer by
layer (:class:`~ehlfoam.seed.mapping.LayeredMesh`: each column's centre and its layers' relative
heights). A snapshot stores those per column and layer in a compressed ``.npz``: the oil
fraction and the heights to 1.5e-5 (16-bit), the velocity in half precision (1e-3 relative),
each column's gap [m], which tells a snapshot of another contact, and a record of where it
came from (the case, the time, its spec and its history.csv, so that a study can go on
reading the run's history). The pressure is not kept: interFoam solves it afresh at every
step, and in this Stokes flow the velocity follows within a few steps.

    ehlfoam snapshot CASE OUT.npz [--time last|TRANSITS] [--fields alpha.oil U]
    ehlfoam case SPEC --out NEW --start-from OUT.npz

A snapshot of a 66,060-cell case (20 layers) takes 0.51 MB, 0.14 MB with alpha.oil alone, and
2 s to write.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Iterable

import numpy as np

from ehlfoam._io import atomic_write
from ehlfoam.case.geometry import META, load_geometry
from ehlfoam.foam.fieldfile import field_file
from ehlfoam.run.fields import Structure, time_folders, write_near
from ehlfoam.seed.mapping import LayeredMesh, carry_oil, interpolate
from ehlfoam.seed.write import check_same_gap, write_seed

#: The ``kind`` entry that tells a snapshot from a thin-film state (both are .npz).
KIND = "ehlfoam-case-snapshot"
#: The fields a snapshot may keep; alpha.oil always.
FIELDS = ("alpha.oil", "U")
_SCALE = 65535.0   # 16-bit fractions in [0, 1]


class SnapshotError(ValueError):
    """A snapshot cannot be written or read; the message names what is wrong."""


def is_snapshot(path: str | Path) -> bool:
    """True when ``path`` is a readable ``.npz`` written by :func:`save_snapshot`."""
    try:
        with np.load(path, allow_pickle=False) as d:
            return "kind" in d.files and str(d["kind"]) == KIND
    except (OSError, ValueError, EOFError):
        return False


def _columns(s: Structure) -> tuple[int, int]:
    """(columns, layers) of a case whose every column has the same layers, else raise."""
    n_base, n_layers = len(s.base_x), int(s.layer.max()) + 1
    if len(s.base_cell) != n_base * n_layers:
        raise SnapshotError(f"the mesh has {len(s.base_cell)} cells, not {n_base} columns of "
                            f"{n_layers} layers: not a layered gap mesh")
    return n_base, n_layers


def save_snapshot(case: str | Path, path: str | Path, at: str = "last",
                  fields: tuple[str, ...] = FIELDS) -> dict[str, Any]:
    """Write the fields of ``case``'s write nearest ``at`` transits ("last": its last write)
    to ``path`` (a compressed .npz, written atomically). Returns the snapshot's record:
    {"source", "time_s", "transits", "cells", "columns", "layers", "mesh_oil_m3",
    "mesh_volume_m3" (the oil and the volume in its mesh, a half domain's half), "fields",
    "spec", "history"}."""
    case, path = Path(case), Path(path)
    if path.suffix != ".npz":
        raise SnapshotError(f"snapshot file = {str(path)!r} must end in .npz")
    unknown = [f for f in fields if f not in FIELDS]
    if unknown or "alpha.oil" not in fields:
        raise SnapshotError(f"fields = {list(fields)}: a snapshot keeps alpha.oil and "
                            f"optionally U (valid: {', '.join(FIELDS)})")
    geom = load_geometry(case)
    s = Structure.load(case)
    n_base, n_layers = _columns(s)
    t, folder, values = _read_write(case, at, geom.transit_time, fields, len(s.base_cell))
    mesh = LayeredMesh.load(case)
    arrays: dict[str, np.ndarray] = {
        "kind": np.array(KIND),
        "base_xy": mesh.base_xy.astype(np.float32),
        "zeta": _fraction16(mesh.zeta_columns()),
        "gap": s.column_gaps().astype(np.float32),
    }
    for name, value in values.items():
        columns = mesh.columns(value)
        arrays[name] = (_fraction16(np.clip(columns, 0.0, 1.0)) if name == "alpha.oil"
                        else columns.astype(np.float16))
    spec = case / META / "spec.json"
    history = case / "history.csv"
    record = {"source": str(case), "time_s": t, "transits": t / geom.transit_time,
              "cells": len(s.base_cell), "columns": n_base, "layers": n_layers,
              "mesh_oil_m3": float(s.cell_volumes @ np.clip(values["alpha.oil"], 0.0, 1.0)),
              "mesh_volume_m3": float(s.cell_volumes.sum()),
              "fields": list(fields),
              "spec": json.loads(spec.read_text()) if spec.is_file() else None,
              "history": history.read_text() if history.is_file() else None}
    arrays["record"] = np.array(json.dumps(record))
    atomic_write(path, lambda fh: np.savez_compressed(fh, **arrays))
    return record


def _read_write(case: Path, at: str, transit_time: float, fields: tuple[str, ...],
                n: int) -> tuple[float, Path, dict[str, np.ndarray]]:
    """(time [s], folder, fields per cell) of the write nearest ``at`` transits; for "last"
    the one before it when the last cannot be read whole (a running case may be writing it)."""
    tries = [write_near(case, at, transit_time)]
    if at == "last":
        tries += [tf for tf in time_folders(case) if tf[0] < tries[0][0]][-1:]
    for t, folder in tries:
        try:
            return t, folder, {name: np.broadcast_to(   # a uniform value or a list
                np.asarray(field_file(folder / name).internal_field, dtype=float),
                (n, 3) if name == "U" else (n,)) for name in fields}
        except (OSError, ValueError) as err:
            error = f"{folder}: cannot read {', '.join(fields)} ({err})"
    raise SnapshotError(error)


def _fraction16(values: np.ndarray) -> np.ndarray:
    return np.rint(np.asarray(values) * _SCALE).astype(np.uint16)


def _require_snapshot(path: str | Path) -> None:
    if not is_snapshot(path):
        raise SnapshotError(f"{path} is not a case snapshot written by `ehlfoam snapshot`")


def load_snapshot(path: str | Path) -> tuple[LayeredMesh, np.ndarray, dict[str, np.ndarray],
                                             dict[str, Any]]:
    """(mesh, column gaps [m], fields per cell, record) of a snapshot file; raises
    :class:`SnapshotError` for a file that is none."""
    _require_snapshot(path)
    with np.load(path, allow_pickle=False) as d:
        base_xy = d["base_xy"].astype(float)
        zeta = d["zeta"].astype(float) / _SCALE
        n_base, n_layers = zeta.shape
        base_cell = np.repeat(np.arange(n_base), n_layers)
        layer = np.tile(np.arange(n_layers), n_base)
        mesh = LayeredMesh(base_cell, layer, zeta.ravel(), base_xy)
        fields = {}
        for name in FIELDS:
            if name in d.files:
                v = d[name].astype(float)
                fields[name] = (v / _SCALE).ravel() if name == "alpha.oil" else v.reshape(-1, 3)
        return mesh, d["gap"].astype(float), fields, json.loads(str(d["record"]))


def map_snapshot(case: Path, s: Structure, snapshot: Path, names: Iterable[str]
                 ) -> tuple[dict[str, np.ndarray], dict[str, Any] | None, dict[str, Any]]:
    """The snapshot's fields among ``names`` interpolated onto ``case``'s mesh (its loaded
    :class:`Structure` ``s``), the oil at its source's volume: (fields, how the oil was
    carried over (:func:`.mapping.carry_oil`; None without alpha.oil), the snapshot's
    record). Raises :class:`.write.RampError` for a snapshot of another contact (its gaps
    differ from the case's)."""
    source, their_gap, fields, record = load_snapshot(snapshot)
    target = LayeredMesh.of(s)
    gap_at = interpolate(their_gap[source.base_cell], source, target)
    check_same_gap(s.gap_mean(gap_at), s, snapshot)
    out, oil = {}, None
    wanted = set(names)
    for name, value in fields.items():
        if name not in wanted:
            continue
        out[name] = interpolate(value, source, target)
        if name == "alpha.oil":
            out[name], oil = carry_oil(out[name], s.cell_volumes, *source_oil(record, case, s))
    return out, oil, record


def seed_from_snapshot(case: str | Path, snapshot: str | Path) -> dict[str, Any]:
    """Write a snapshot's fields as ``case``'s initial fields (its ``0.orig/``), interpolated
    layer by layer onto its mesh (:func:`map_snapshot`; the same mesh gets its own values
    back, to the snapshot's precision). Returns (and writes to ``case/ehlfoam/ramp.json``)
    {"previous", "previous_time_s", "method": "snapshot", "fields", "cells", "source", "oil"
    (how the oil was carried over, :func:`.mapping.carry_oil`)}."""
    case, snapshot = Path(case).absolute(), Path(snapshot).absolute()
    own = [name for name in FIELDS if (case / "0.orig" / name).is_file()]
    out, oil, record = map_snapshot(case, Structure.load(case), snapshot, own)
    return write_seed(case, out, {
        "previous": os.path.relpath(snapshot, case), "previous_time_s": record["time_s"],
        "method": "snapshot", "fields": sorted(out), "source": record["source"], "oil": oil})


def source_oil(record: dict[str, Any], case: Path, s: Structure
                ) -> tuple[float | None, float | None]:
    """(oil, domain volume) [m^3] in the mesh of a snapshot's source, (None, None) when
    unknown. Snapshots written before 2026-11-29 keep neither: when the source's spec names
    the case's domain, its run's history gives the oil at the snapshot's time (over the
    case's mirror, as the history counts the whole contact) and the case's own volume stands
    for the domain's."""
    if "mesh_oil_m3" in record:
        return record["mesh_oil_m3"], record["mesh_volume_m3"]
    own = json.loads((case / META / "spec.json").read_text()).get("domain")
    if (record.get("spec") or {}).get("domain") != own:
        return None, None
    try:
        history, _ = snapshot_history_of(record)
    except SnapshotError:
        return None, None
    oil = float(history["oil_volume_m3"][-1]) / load_geometry(case).mirror
    return oil, float(s.cell_volumes.sum())


def snapshot_history(snapshot: str | Path) -> tuple[dict[str, np.ndarray], float]:
    """(history columns, transit time [s]) of the run a snapshot was taken from, its
    history.csv up to the snapshot's write as :func:`ehlfoam.run.history.read_history`
    reads it; raises :class:`SnapshotError` when it kept none."""
    _require_snapshot(snapshot)
    with np.load(snapshot, allow_pickle=False) as d:   # the record only, not the fields
        record = json.loads(str(d["record"]))
    try:
        return snapshot_history_of(record)
    except SnapshotError as err:
        raise SnapshotError(f"{snapshot}: {err}") from None


def snapshot_history_of(record: dict[str, Any]) -> tuple[dict[str, np.ndarray], float]:
    """:func:`snapshot_history` of a snapshot's record."""
    import csv
    import io

    from ehlfoam.run.history import history_columns

    columns = (history_columns(list(csv.DictReader(io.StringIO(record["history"]))))
               if record.get("history") else None)
    if columns is None or record["transits"] <= 0.0:
        raise SnapshotError("its run kept no history.csv")
    keep = columns["time_s"] <= record["time_s"] * (1.0 + 1e-9)
    return {k: v[keep] for k, v in columns.items()}, record["time_s"] / record["transits"]

