"""Start a case from another state: a run case's final fields (:mod:`.previous`), a case
snapshot's (:mod:`.snapshot`) or a thin-film state's oil (:mod:`.thin_film`), told apart by
what ``source`` is."""

from __future__ import annotations

import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from ehlfoam.case.geometry import META, load_geometry
from ehlfoam.case.thin_film import is_thin_film_case
from ehlfoam.foam.fieldfile import field_file
from ehlfoam.run.fields import Structure
from ehlfoam.seed.previous import FIELDS, final_time, seed_from_previous
from ehlfoam.seed.snapshot import is_snapshot, load_snapshot, seed_from_snapshot
from ehlfoam.seed.thin_film import seed_from_thin_film
from ehlfoam.seed.thin_film_case import (check_thin_film_start, seed_thin_film_case,
                                         thin_film_state_of)
from ehlfoam.seed.write import RampError
from ehlfoam.thinfilm.state import load_state

__all__ = ["RampError", "check_start", "is_thin_film_state", "seed_case"]


def is_thin_film_state(source: str | Path) -> bool:
    """True when ``source`` names a thin-film state (a ``.npz`` that is no case snapshot)
    rather than a run case or a snapshot (:mod:`.snapshot`)."""
    return Path(source).suffix == ".npz" and not is_snapshot(source)


def _npz_members(path: Path) -> list[str]:
    """The arrays a ``.npz`` holds (from its zip directory, nothing decompressed)."""
    try:
        with zipfile.ZipFile(path) as z:
            return [n.removesuffix(".npy") for n in z.namelist()]
    except (OSError, zipfile.BadZipFile, ValueError) as err:
        raise RampError(f"{path} is not a thin-film state nor a case snapshot: not a "
                        f"readable .npz file ({err}); give a run case folder, a case snapshot "
                        "(`ehlfoam snapshot`) or a thin-film state (`ehlfoam thin-film`)"
                        ) from None


def _check_snapshot(path: Path) -> None:
    """Read the whole snapshot (every array decompressed, so that a flipped byte fails its
    checksum here) and check that its arrays agree."""
    try:
        mesh, gap, fields, record = load_snapshot(path)
        ok = ("alpha.oil" in fields and len(gap) == len(mesh.base_xy)
              and all(len(v) == len(mesh.base_cell) for v in fields.values())
              and isinstance(record, dict) and "time_s" in record)
    except Exception as err:  # noqa: BLE001 - any damage: zlib, zip CRC, JSON, shapes
        raise RampError(f"{path} is a case snapshot that cannot be read whole "
                        f"({type(err).__name__}: {' '.join(str(err).split())[:200]}): "
                        "damaged or truncated? Write it again with `ehlfoam snapshot`") from None
    if not ok:
        raise RampError(f"{path} is a case snapshot whose arrays do not agree (alpha.oil "
                        "missing or sizes that differ): damaged? Write it again with "
                        "`ehlfoam snapshot`")


def _check_state(path: Path) -> None:
    """Read the whole thin-film state and check its arrays' shapes."""
    try:
        sol = load_state(path)
        shape = (len(sol.grid.y), len(sol.grid.x))
        ok = (sol.grid.h.shape == shape and np.shape(sol.content) == shape
              and np.shape(sol.flooded) == shape)
    except Exception as err:  # noqa: BLE001 - any damage: missing arrays, zlib, zip CRC
        raise RampError(f"{path} is not a thin-film state written by `ehlfoam thin-film` "
                        f"({type(err).__name__}: {' '.join(str(err).split())[:200]})") from None
    if not ok:
        raise RampError(f"{path} is not a thin-film state written by `ehlfoam thin-film` "
                        "(its grid, gaps and oil have different shapes)")


def _check_run_case(path: Path) -> None:
    """A run case: its geometry, mesh structure and the fields of its last write, read."""
    if not path.is_dir():
        raise RampError(f"{path} is neither a run case folder nor a .npz (a case snapshot or "
                        "a thin-film state)")
    try:
        geom = load_geometry(path)
        cells = len(Structure.load(path).base_cell)
    except Exception as err:  # noqa: BLE001 - missing or damaged ehlfoam/ files
        raise RampError(f"{path} is not a case written by `ehlfoam case` with a readable "
                        f"{META}/geometry.json and {META}/mesh.npz ({type(err).__name__}: "
                        f"{' '.join(str(err).split())[:200]})") from None
    t, folder = final_time(path)
    names = [n for n in FIELDS if (folder / n).is_file()]
    if "alpha.oil" not in names:
        raise RampError(f"{path}: its last write {folder.name} has no alpha.oil to start "
                        "from (an unfinished write, or not a time folder the solver wrote)")
    for name in names:
        try:
            value = np.asarray(field_file(folder / name).internal_field, dtype=float)
        except Exception as err:  # noqa: BLE001 - foamlib's parse errors
            raise RampError(f"{path}: {folder.name}/{name} cannot be read as an OpenFOAM "
                            f"field ({type(err).__name__}: "
                            f"{' '.join(str(err).split())[:200]})") from None
        if value.ndim and value.shape[0] not in (cells, 3):
            raise RampError(f"{path}: {folder.name}/{name} holds {value.shape[0]} values, "
                            f"the case has {cells} cells (t = {t:g} s)")
    if geom.cells != cells:
        raise RampError(f"{path}: its geometry.json says {geom.cells} cells, its mesh.npz "
                        f"{cells}")


def check_start(source: str | Path, scene: str | None = None) -> None:
    """Raise :class:`RampError` unless ``source`` can start a case: a run case whose last
    write is read whole, a case snapshot read whole, or a thin-film state read whole (or a
    thin-film case that has run: its state). A case of ``scene = "thin-film"`` starts only
    from the last two (:func:`~ehlfoam.seed.thin_film_case.check_thin_film_start`). Call it
    before writing anything: a fake time folder, a snapshot with a flipped byte or a file that
    is no state is refused here, not after a case was built."""
    path = Path(source)
    if not path.exists():
        raise RampError(f"{source}: no such case folder or file")
    if scene == "thin-film" or _thin_film_case(source):
        state = check_thin_film_start(source)
        if "kind" in _npz_members(state):
            raise RampError(f"{source} is a case snapshot: a thin-film case starts from a "
                            "thin-film state (state.npz of a thin-film run, or ehlfoam "
                            "thin-film) or a thin-film case folder that has run")
        _check_state(state)
        return
    if path.suffix == ".npz" and path.is_file():
        if "kind" in _npz_members(path):
            _check_snapshot(path)
        else:
            _check_state(path)
        return
    _check_run_case(path)


def seed_case(case: str | Path, source: str | Path) -> dict[str, Any]:
    """Start ``case`` from ``source``: a run case's final fields
    (:func:`ehlfoam.seed.previous.seed_from_previous`), a case snapshot's
    (:func:`ehlfoam.seed.snapshot.seed_from_snapshot`) or a thin-film state's oil
    (:func:`ehlfoam.seed.thin_film.seed_from_thin_film`; a thin-film case folder's state);
    a thin-film ``case`` from a thin-film state
    (:func:`ehlfoam.seed.thin_film_case.seed_thin_film_case`)."""
    if is_thin_film_case(case):
        return seed_thin_film_case(case, source)
    if _thin_film_case(source):
        source = thin_film_state_of(source)
    if is_snapshot(source):
        return seed_from_snapshot(case, source)
    if is_thin_film_state(source):
        return seed_from_thin_film(case, source)
    return seed_from_previous(case, source)


def _thin_film_case(source: str | Path) -> bool:
    """``source`` is a thin-film case folder (its state.npz starts a case)."""
    return Path(source).is_dir() and is_thin_film_case(source)
