"""The run's warnings: oil leaving off the outlet, a flooded region near an open boundary, a
rear meniscus in coarse cells, a front off the track in cells too wide for its contact line,
a thin-film bubble that closes within a cell, supply layers broken into drops. Each names
what to change; the run records them in metrics.json (``warnings``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ehlfoam.case.geometry import CaseGeometry
from ehlfoam.mesh import size_function
from ehlfoam.notices import Notice
from ehlfoam.run import fields as case_fields
from ehlfoam.spec.case import CaseSpec

__all__ = ["BARE_TRACK_WARNING", "CLEARANCE_WARNING", "FRONT_CELL_WARNING",
           "OFF_OUTLET_WARNING", "REAR_CELL_WARNING", "bare_track", "bare_track_warnings",
           "boundary_warnings", "enclosure_warnings", "front_cell_warnings",
           "front_contact_line_cells", "rear_cell_warnings", "rear_meniscus_cell"]

#: share of the outflow leaving off the outlet above which a run is flagged: the region (or a
#: wall film) reached the side or upstream boundary
#: (docs/models/interface.md#outflow-off-outlet)
OFF_OUTLET_WARNING = 0.05
#: flooded region nearer an open boundary than this (units a) is flagged: its meniscus feels
#: the boundary's fixed pressure, and at the outlet the oil leaves in bulk instead of as the
#: films the rear meniscus lays (docs/models/interface.md#region-near-boundary)
CLEARANCE_WARNING = 1.0
#: in-plane cells at the rear meniscus coarser than this (units a) are flagged: they lay wall
#: films thicker than Landau-Levich's (1.6-2.1 times at 0.55 a, 1.0 at 0.1 a on the 2D strip),
#: and the flooded width comes out short (the default levels' 0.4-0.8 a cells by 17-21 %
#: against the converged width; docs/models/interface.md#rear-meniscus-cells,
#: docs/validation.md#v-films)
REAR_CELL_WARNING = 0.15
#: The in-plane cells over the wall cell's height along the flooded region's front off the
#: track, where dry walls run into it, above which a run warns: in the contact-line strip the
#: meniscus holds no capillary suction beyond some 15
#: (docs/models/interface.md#front-contact-line-cells, docs/validation.md#v-contact-line).
FRONT_CELL_WARNING = 15.0
#: The share of the supply track's columns upstream of the flooded region left bare (under a
#: quarter of the supplied layers) above which a run warns: the layers broke into drops on
#: the way in. Whole layers leave none bare; a wall angle above the oil's static one, as the
#: resolved rungs' Cox-Voinov angle, breaks sub-micron layers: 33 % bare after 0.3 transit at
#: 40 C, 8 mm/s, 0.45 um (docs/models/interface.md#supply-layers-broken).
BARE_TRACK_WARNING = 0.1
#: how far upstream of the flooded region (units a) the bare track is read
_BARE_TRACK_MARGIN = 0.5



#: the spec key that moves each open boundary
_BOUNDARY_KEY = {"upstream": "domain.upstream", "outlet": "domain.downstream",
                 "side": "domain.side"}


def boundary_warnings(off_outlet: float | None, pattern: dict | None = None) -> list[Notice]:
    """Warnings when more than :data:`OFF_OUTLET_WARNING` of the oil leaving the domain
    (``off_outlet``, the share at the last write) did not leave through the outlet, and when
    the flooded region of the last write (``pattern``: its ``flooded_clearance_over_a`` and
    ``flooded_nearest_boundary``) is within :data:`CLEARANCE_WARNING` of an open boundary."""
    out = []
    if off_outlet is not None and off_outlet > OFF_OUTLET_WARNING:
        out.append(Notice(
            "outflow-off-outlet",
            f"{off_outlet:.0%} of the outflow left through the side or upstream boundary (above "
            f"{OFF_OUTLET_WARNING:.0%}): the region is cut short, widen the domain (domain.side, "
            f"domain.upstream)", "docs/models/interface.md#outflow-off-outlet"))
    clearance = (pattern or {}).get("flooded_clearance_over_a")
    if clearance is not None and clearance < CLEARANCE_WARNING:
        where = pattern["flooded_nearest_boundary"]
        out.append(Notice(
            "region-near-boundary",
            f"the flooded region is {clearance:.2f} a from the {where} boundary (below "
            f"{CLEARANCE_WARNING:g} a): the boundary may hold or cut it, move it out "
            f"({_BOUNDARY_KEY[where]})", "docs/models/interface.md#region-near-boundary"))
    return out


def enclosure_warnings(pattern: dict | None, cavity: np.ndarray | None) -> list[Notice]:
    """A warning when the metrics read an enclosed bubble in a thin-film state (its oil
    fraction's 0.5 contour closed around gas behind the contact: ``pattern``'s
    ``enclosed_bubbles``) where the model holds no cavity (``cavity``: its enclosed open
    cells, None without an outlet model): its gas reaches the outer air through part-filled
    cells, so the region closes within a cell and its state I is not settled on that grid
    (25 C, 20 mm/s: closed on 0.4 and 0.2 a cells, open on 0.1 a)."""
    if cavity is None or not (pattern or {}).get("enclosed_bubbles") or np.any(cavity):
        return []
    return [Notice(
        "closed-within-a-cell",
        "the metrics read a bubble enclosed (state I) where the model's gas reaches the air "
        "through part-filled cells: refine thin_film.cell to settle the state",
        "docs/models/thin-film.md#closed-within-a-cell")]


def rear_meniscus_cell(spec: CaseSpec, pattern: dict | None) -> float | None:
    """In-plane cell size (units a) where the closed flooded region's rear meniscus crosses
    y = 0 (at ``flooded_x_max_over_a``): the cells that lay the wall films leaving the region,
    which decide how much oil it holds and how wide it grows. None for an open wake (state II)
    or no region."""
    x_rear = (pattern or {}).get("flooded_x_max_over_a")
    if x_rear is None or pattern.get("state") != "I":
        return None
    return float(size_function(spec)(x_rear * spec.a, 0.0) / spec.a)


def rear_cell_warnings(rear_cell: float | None, follows: bool = False) -> list[Notice]:
    """A warning when the rear meniscus sits in cells (``rear_cell``, units a) coarser than
    :data:`REAR_CELL_WARNING`, naming what refines them: in a mesh that ``follows`` its start
    state's meniscus (``mesh.follow``), a wider band, which the region has grown out of."""
    if rear_cell is None or rear_cell <= REAR_CELL_WARNING:
        return []
    effect = (f"the rear meniscus sits in {rear_cell:.2f} a cells (above "
              f"{REAR_CELL_WARNING:g} a): its films, ")
    fix = ("oil and width are off: widen the followed band (mesh.follow.half_width)"
           if follows else "the oil held and the width are off, refine there (mesh.refine "
           "as in nominal_films.toml)")
    return [Notice("rear-meniscus-cells", effect + fix,
                   "docs/models/interface.md#rear-meniscus-cells")]


def front_contact_line_cells(spec: CaseSpec, geom: CaseGeometry,
                             structure: case_fields.Structure, case: Path,
                             pattern: dict | None) -> float | None:
    """The median, along the closed flooded region's edge where dry walls run into it off
    the track, of the in-plane cell size over the wall cell's height
    (:func:`case_fields.advancing_front_cells`, at the last write). None for an open wake, no
    region or no such edge."""
    folders = case_fields.time_folders(case)
    if (pattern or {}).get("state") != "I" or not folders:
        return None
    try:
        ratios = case_fields.advancing_front_cells(folders[-1][1], structure, geom,
                                                   spec.supply.track_half_width)
    except (OSError, ValueError, KeyError):     # a last write cut short: no figure
        return None
    return float(np.median(ratios)) if len(ratios) else None


def front_cell_warnings(front_cells: float | None,
                        isotropic_compression: float = 0.0) -> list[Notice]:
    """A warning when the region's front off the track, where dry walls run into it, sits in
    cells wider than :data:`FRONT_CELL_WARNING` wall cells; none with the compression taken
    from the local speed (``physics.isotropic_compression = 1``), with which the advancing
    line holds on any cells (docs/models/interface.md#numerics)."""
    if front_cells is None or front_cells <= FRONT_CELL_WARNING or isotropic_compression == 1.0:
        return []
    return [Notice("front-contact-line-cells",
                   f"the front where dry walls run into it sits in cells {front_cells:.0f} wall "
                   f"cells wide (above {FRONT_CELL_WARNING:g}): width and inlet meniscus "
                   f"unconverged, physics.isotropic_compression = 1",
                   "docs/models/interface.md#front-contact-line-cells")]


def bare_track(spec: CaseSpec, geom: CaseGeometry, structure: case_fields.Structure,
               case: Path, pattern: dict | None) -> float | None:
    """The share of the supply track's columns upstream of the flooded region (half an a
    clear of it, or of the island without one) left bare at the last write
    (:func:`case_fields.bare_track_share`). None unless the supply is layers, or without a
    whole last write."""
    supply = spec.supply
    layers = supply.disc_layer + supply.ball_layer
    if supply.mode != "layers" or layers <= 0.0:
        return None
    folders = case_fields.time_folders(case)
    if not folders:
        return None
    front = (pattern or {}).get("flooded_x_min_over_a")
    upstream_of = (front * geom.a if front is not None else -geom.island_radius) \
        - _BARE_TRACK_MARGIN * geom.a
    try:
        return case_fields.bare_track_share(folders[-1][1], structure, geom,
                                            supply.track_half_width, layers, upstream_of)
    except (OSError, ValueError, KeyError):     # a last write cut short: no figure
        return None


def bare_track_warnings(share: float | None) -> list[Notice]:
    """A warning when more than :data:`BARE_TRACK_WARNING` of the supply track upstream of
    the flooded region is bare: the supply layers broke into drops on their way in."""
    if share is None or share <= BARE_TRACK_WARNING:
        return []
    return [Notice("supply-layers-broken",
                   f"{share:.0%} of the supply track upstream of the region is bare: the layers "
                   f"broke into drops on the way in, the inlet meniscus and the oil are off",
                   "docs/models/interface.md#supply-layers-broken")]
