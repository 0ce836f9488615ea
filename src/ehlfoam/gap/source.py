"""The deformed gap a case is built on: an EHL precalc solution (:mod:`ehlfoam.contact`),
solved once per contact.

Solutions are cached per machine under ``$EHLFOAM_CACHE/precalc/<hash of the contact spec>``
(the same cache folder as the OpenFOAM runtime), so a batch of cases that share a contact
solves it once. A cache entry is written atomically (solved in a temporary sibling, renamed).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import tempfile
from pathlib import Path

from ehlfoam.gap.field import GapField
from ehlfoam.paths import cache_dir
from ehlfoam.contact.outputs import write_all
from ehlfoam.contact.solver import FINE_GRID_M, default_grid, solve
from ehlfoam.contact.spec import PrecalcSpec


class PrecalcFailed(RuntimeError):
    """The EHL precalc of a case did not converge."""


def spec_key(spec: PrecalcSpec) -> str:
    """A stable hash of everything that changes the solution (the starved-inlet keys only
    when set and the two-phase coupling only with the two-phase option, so a flooded
    complementarity spec keeps the key it had before they existed; the default grid by its
    size where it is 2049, above FINE_GRID_M, so that a cache of the 1025 it was before
    is not taken for it)."""
    unset = {k for k in ("inlet_layer", "inlet_meniscus") if getattr(spec, k) is None}
    if spec.cavitation != "twophase":
        unset.add("twophase_coupling")
    text = spec.model_dump_json(exclude=unset)
    if spec.grid is None:
        M = spec.contact().M
        if M >= FINE_GRID_M:
            text += f"|default grid {default_grid(M)}"
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def precalc_dir(spec: PrecalcSpec, cache: Path | None = None, require_converged: bool = True) -> Path:
    """The folder holding the precalc outputs of ``spec``, solving it if not cached.

    Raises :class:`PrecalcFailed` if the solution did not converge and ``require_converged``.
    """
    root = (cache or cache_dir()) / "precalc"
    final = root / spec_key(spec)
    if not (final / "summary.json").is_file():
        root.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(dir=root, prefix=f".{final.name}."))
        try:
            (tmp / "spec.json").write_text(spec.model_dump_json(indent=2))
            write_all(solve(spec), tmp)
            try:
                os.replace(tmp, final)
            except OSError:  # another process got there first: keep theirs
                shutil.rmtree(tmp, ignore_errors=True)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
    if require_converged:
        import json

        summary = json.loads((final / "summary.json").read_text())
        if not summary.get("converged"):
            raise PrecalcFailed(f"the EHL precalc did not converge ({final}/summary.json); "
                                "the gap cannot be trusted")
    return final


def load_gap(spec: PrecalcSpec, cache: Path | None = None) -> tuple[GapField, Path]:
    """The gap field h(x, y) [m] of ``spec`` and the precalc folder it came from."""
    folder = precalc_dir(spec, cache)
    return GapField.load(folder), folder
