"""Start a case from another state: a run case's final fields (:mod:`.previous`), a case
snapshot's (:mod:`.snapshot`) or a thin-film state's oil (:mod:`.thin_film`), told apart by
what ``source`` is."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ehlfoam.case.thin_film import is_thin_film_case
from ehlfoam.seed.previous import final_time, seed_from_previous
from ehlfoam.seed.snapshot import is_snapshot, seed_from_snapshot
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


def check_start(source: str | Path, scene: str | None = None) -> None:
    """Raise :class:`RampError` (or OSError) unless ``source`` can start a case: a run case
    with a written time, a case snapshot, or a readable thin-film state (or a thin-film case
    that has run); a case of ``scene = "thin-film"`` only the last two
    (:func:`~ehlfoam.seed.thin_film_case.check_thin_film_start`). Call it before writing
    anything."""
    if scene == "thin-film" or _thin_film_case(source):
        check_thin_film_start(source)
        return
    if is_snapshot(source):
        return
    if not is_thin_film_state(source):
        final_time(source)
        return
    try:
        load_state(source)
    except (OSError, KeyError, ValueError) as err:
        raise RampError(f"{source} is not a thin-film state written by "
                        f"`ehlfoam thin-film` ({err})") from None


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
