"""A 3D case started from the thin-film balance of its own operating point
(``run.start = "thin-film"``; the resolved rungs of the ladder, docs/ladder.md).

The thin-film counterpart of the spec (:func:`ehlfoam.spec.case.thin_film_counterpart`: the
same contact, supply, oil and domain on the model's medium level) is written as a thin-film
case and run to its balance (seconds to a minute on one core); its state starts the 3D case
(:func:`ehlfoam.seed.start.seed_case`) and, with ``mesh.follow``, places the bands of its
mesh. The start's record (its ``metrics.json``, ``state.npz`` and log) is kept in the 3D
case's ``ehlfoam/thin-film-start/``.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from ehlfoam.case.geometry import META
from ehlfoam.case.writer import write_case
from ehlfoam.metrics.record import MetricsRecord, read_metrics
from ehlfoam.run.thin_film import STATE_FILE, run_thin_film_case
from ehlfoam.spec.case import CaseSpec, thin_film_counterpart

__all__ = ["START_FOLDER", "keep_start", "thin_film_start"]

#: where a case started from its thin-film balance keeps that start's record (in META)
START_FOLDER = "thin-film-start"
#: what of the start's case folder is kept
_KEPT = ("metrics.json", STATE_FILE, "history.csv", "log.thin-film")


def thin_film_start(spec: CaseSpec, folder: str | Path) -> Path:
    """The thin-film case of ``spec``'s operating point in ``folder``, run to its balance;
    one that ran to its end already (the same spec) is reused. Returns ``folder`` (a source
    for ``seed_case``). Raises RuntimeError when the model fails (its log says why)."""
    folder = Path(folder).absolute()
    tf = thin_film_counterpart(spec)
    record = _finished(folder, tf)
    if record is None:
        write_case(tf, folder, overwrite=True)
        record = run_thin_film_case(folder)
    if record.status == "failed" or not (folder / STATE_FILE).is_file():
        raise RuntimeError(f"the thin-film start in {folder} failed ({record.end_reason}): "
                           f"see its log.thin-film")
    return folder


def keep_start(start: Path, case: Path) -> None:
    """Copy the start's record into ``case``'s ``ehlfoam/thin-film-start/``."""
    dest = Path(case) / META / START_FOLDER
    dest.mkdir(parents=True, exist_ok=True)
    for name in _KEPT:
        if (Path(start) / name).is_file():
            shutil.copy2(Path(start) / name, dest / name)


def _finished(folder: Path, tf: CaseSpec) -> MetricsRecord | None:
    """The record of a start in ``folder`` that ran to its end with the spec ``tf``."""
    spec_file = folder / META / "spec.json"
    if not spec_file.is_file():
        return None
    try:
        same = CaseSpec.model_validate_json(spec_file.read_text()) == tf
        record = read_metrics(folder)
    except (OSError, ValueError):
        return None
    if not same or record is None or record.status != "finished":
        return None
    return record
