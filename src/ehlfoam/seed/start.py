"""Start a case from another state: a run case's final fields (:mod:`.previous`), a case
snapshot's (:mod:`.snapshot`) or a thin-film state's oil (:mod:`.thin_film`), told apart by
what ``source`` is."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ehlfoam.seed.previous import final_time, seed_from_previous
from ehlfoam.seed.snapshot import is_snapshot, seed_from_snapshot
from ehlfoam.seed.thin_film import seed_from_thin_film
from ehlfoam.seed.write import RampError
from ehlfoam.thinfilm.state import load_state

__all__ = ["RampError", "check_start", "is_thin_film_state", "seed_case"]


def is_thin_film_state(source: str | Path) -> bool:
    """True when ``source`` names a thin-film state (a ``.npz`` that is no case snapshot)
    rather than a run case or a snapshot (:mod:`.snapshot`)."""
    return Path(source).suffix == ".npz" and not is_snapshot(source)


def check_start(source: str | Path) -> None:
    """Raise :class:`RampError` (or OSError) unless ``source`` can start a case: a run case
    with a written time, a case snapshot, or a readable thin-film state. Call it before
    writing anything."""
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
    (:func:`ehlfoam.seed.thin_film.seed_from_thin_film`)."""
    if is_snapshot(source):
        return seed_from_snapshot(case, source)
    if is_thin_film_state(source):
        return seed_from_thin_film(case, source)
    return seed_from_previous(case, source)
