"""What a batch report's first screen says about its cases: the batch's own description and,
for each rung of the model ladder it holds, one line on how far its numbers can be trusted,
from the measurements in docs/validation.md (one place for those words)."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from ehlfoam._io import read_toml
from ehlfoam.batch.folder import SPEC_COPY
from ehlfoam.batch.regime import row_rung
from ehlfoam.errors import SpecError

__all__ = ["TRUST", "batch_description", "trust_lines"]

#: One line per rung family: what its numbers are worth, measured at the nominal point
#: (HVI60, 40 C, 20 N, 8 mm/s) against the converged 3D family (docs/validation.md).
TRUST = {
    "thin-film": (
        "thin-film (gap-averaged, seconds a case): inlet meniscus 4.9 a against the converged "
        "3D 5.6 a (12 % downstream), flooded width 15.4 a against 14.7 a (5 % wide); its "
        "bubble is the gas-release scene's with an instant release (within 7 % of the 3D bath "
        "at 99 kPa); at six reference points its medium level is within 8 % of the finest "
        "rung at rest; a state within a speed step of the transition can flip with the grid "
        "or the start (docs/ladder.md#speed-against-accuracy). On the coarse grid (0.4 a) "
        "bubbles read 8-12 % short and one under two cells (0.65 a at 2 mm/s) is missed; "
        "rests from a puddle take 8-60 transits, longest at low speed and thick layers "
        "(docs/models/stability.md)."),
    "coarse": (
        "3D coarse (minutes a case): a first look; the flooded width 17-21 % short of the "
        "converged one, the inlet some 16 % upstream; a few transits are not a rest: started "
        "from the thin-film state it was still shedding oil after 1-6 transits at 5 of 6 "
        "points of 4-21 mm/s (docs/models/stability.md, docs/ladder.md); its rear menisci lay "
        "films 1.5-2 times the thin-film model's, so it drains a state I region toward "
        "state II (docs/ladder.md#why-the-3d-levels-drain-at-state-i)."),
    "medium": (
        "3D medium: the default levels' width 17-21 % short of the converged one "
        "(docs/validation.md)."),
    "fine": (
        "3D fine: the default levels' width 17-21 % short of the converged one; converged "
        "values need the resolved family (docs/validation.md)."),
    "resolved": (
        "3D resolved (hours a transit): at the nominal point its width converges to 14.66 a "
        "(0.2 % between medium and fine) and its inlet meniscus to 5.6 a (GCI 3 %); at other "
        "points the same settings, not measured there (docs/ladder.md)."),
}


def batch_description(batch: Path) -> str:
    """The ``description`` of the batch spec kept in the batch folder (batch.toml), or ""."""
    try:
        value = read_toml(batch / SPEC_COPY).get("description", "")
    except SpecError:
        return ""
    return value if isinstance(value, str) else ""


def trust_lines(rows: Iterable[dict]) -> list[str]:
    """One line for each rung family among ``rows`` (results rows), thin-film first."""
    families = {next((f for f in ("thin-film", "resolved") if rung.startswith(f)), rung)
                for rung in map(row_rung, rows)}
    return [f"How far to trust it: {TRUST[f]}" for f in TRUST if f in families]
