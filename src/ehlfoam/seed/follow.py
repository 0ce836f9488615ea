"""Cases whose mesh follows the meniscus of the state they start from (``mesh.follow``).

The levels of :data:`~ehlfoam.spec.levels.RESOLUTIONS` leave the meniscus in their base cells,
and the flooded width does not converge over them; with bands of cells along the whole
meniscus, twice as fine on the region's sides, and one thin wall cell everywhere
(:data:`~ehlfoam.spec.levels.FOLLOW_LEVELS`), the meniscus is resolved on every level
(docs/models/interface.md#the-mesh). A case of such a level is written in three steps:

1. a probe case on the level's base mesh, without bands, started from the source
   (``--start-from``: a run case, a case snapshot or a thin-film state);
2. the probe's initial mid-gap meniscus read off (:func:`ehlfoam.seed.band.meniscus_lines`)
   and turned into bands of the level's cells, and side bands where ``mesh.follow.sides``
   says;
3. the case itself on the mesh with those bands, started from the same source.

The written spec (``ehlfoam/spec.json``) has no ``follow``: its bands are in ``mesh.refine``
and the level's sizes spelled out, so it rebuilds the same mesh by itself.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path
from typing import Any

from ehlfoam.spec.case import CaseSpec, make_case_spec
from ehlfoam.case.geometry import CaseGeometry
from ehlfoam.case.ownership import check_replaceable
from ehlfoam.case.writer import write_case

from ehlfoam.seed.band import meniscus_bands, meniscus_lines, side_bands
from ehlfoam.seed.ladder import keep_start, thin_film_start
from ehlfoam.seed.start import seed_case


def explicit_level(spec: CaseSpec, refine: tuple = ()) -> CaseSpec:
    """``spec`` without ``mesh.follow``: the level's sizes, wall cell and polar ring spelled
    out, and ``refine`` added to its own refinements."""
    level = spec.mesh.level()
    mesh = spec.mesh.model_dump()
    mesh.update(follow=None, size_rim=level["size_rim"], size_far=level["size_far"],
                n_layers=level["n_layers"], wall_cell=level["wall_cell"],
                wall_grading=level["wall_grading"] if level["wall_cell"] is None else None,
                polar_radius=spec.polar_radius,
                refine=[r.model_dump() for r in spec.mesh.refine] + [r.model_dump()
                                                                      for r in refine])
    return make_case_spec({**spec.model_dump(), "mesh": mesh})


def following_spec(spec: CaseSpec, source: str | Path | None,
                   scratch: str | Path | None = None) -> CaseSpec:
    """The explicit spec of ``spec``'s following level (``mesh.follow`` set): its bands along
    the mid-gap meniscus of ``source`` as a probe case on the base mesh starts from it.
    ``spec`` itself without ``mesh.follow``. Raises ValueError without a source, or when the
    source has no meniscus line as long as the band's half-width."""
    follow = spec.mesh.follow
    if follow is None:
        return spec
    if source is None:
        raise ValueError("mesh.follow needs the state the case starts from (--start-from "
                         "a run case, a case snapshot or a thin-film state)")
    base = explicit_level(spec)
    work = Path(tempfile.mkdtemp(prefix="follow-probe-", dir=scratch))
    try:
        probe = work / "probe"
        write_case(base, probe)
        seed_case(probe, source)
        _, lines = meniscus_lines(probe, "start")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    bands = meniscus_bands(lines, spec.mesh.follow_band, follow.half_width)
    if not bands:
        raise ValueError(f"{source} has no meniscus line of {follow.half_width:g} a or longer "
                         "for mesh.follow's bands")
    if follow.sides is not None:
        bands += side_bands(bands, follow.sides)
    return explicit_level(spec, tuple(bands))


def write_started_case(spec: CaseSpec, out: str | Path, source: str | Path | None,
                       overwrite: bool = False) -> tuple[CaseGeometry, dict[str, Any] | None]:
    """Write ``spec``'s case in ``out`` and start it from ``source`` (None: the spec's own
    start: its supply and puddle, or with ``run.start = "thin-film"`` the thin-film balance
    of its point, run first in a sibling scratch folder and kept in the case,
    :mod:`ehlfoam.seed.ladder`); with ``mesh.follow`` its mesh follows the source's meniscus
    (:func:`following_spec`). Returns the case geometry and the seed's record (None without a
    source). Raises ValueError for ``mesh.follow`` without a source (the case writer's), and
    :class:`~ehlfoam.case.ownership.CaseExists` for an ``out`` that may not be written (before
    any work). The start is written into the case before it is renamed into place: a start
    that fails leaves no case behind (and an earlier case it was to replace as it was)."""
    out = Path(out).absolute()
    check_replaceable(out, overwrite)
    if source is None and spec.run.start == "thin-film" and spec.scene != "thin-film":
        out.parent.mkdir(parents=True, exist_ok=True)
        work = Path(tempfile.mkdtemp(prefix=f".{out.name}.thin-film-start-", dir=out.parent))
        try:
            return _write_started(spec, out, thin_film_start(spec, work / "case"), overwrite,
                                  kept=True)
        finally:
            shutil.rmtree(work, ignore_errors=True)
    return _write_started(spec, out, source, overwrite)


def _write_started(spec: CaseSpec, out: Path, source: str | Path | None, overwrite: bool,
                   kept: bool = False) -> tuple[CaseGeometry, dict[str, Any] | None]:
    if spec.mesh.follow is not None and source is not None:
        out.parent.mkdir(parents=True, exist_ok=True)
        spec = following_spec(spec, source, scratch=out.parent)
    seeded: list[dict[str, Any]] = []

    def prepare(tmp: Path) -> None:
        seeded.append(seed_case(tmp, source))
        if kept:
            keep_start(Path(source), tmp)

    geom = write_case(spec, out, overwrite=overwrite,
                      prepare=None if source is None else prepare)
    return geom, (seeded[0] if seeded else None)
