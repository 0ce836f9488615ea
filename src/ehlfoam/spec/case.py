"""The case spec: one validated description of an OpenFOAM case around the contact.

A TOML file with the tables below; every key is optional and defaults to the reference
conditions of ``ball_on_disc.md`` (HVI60, 40 C, 20 N, 8 mm/s, ample oil). SI units
throughout (m, s, N, Pa, kg/m3), except the contact angle in degrees and the domain in
units of the Hertzian radius a::

    [contact]            # the EHL precalc spec (ehlfoam.contact.spec.PrecalcSpec), e.g.
    load = 20.0          # N
    speed = 0.008        # m/s, pure rolling
    temperature = 40.0   # C
    lubricant = "HVI60"

    [supply]
    mode = "layers"      # "flooded" (ample oil), "layers" or "submerged"
    disc_layer = 2e-6    # m, oil layer carried into the inlet on the disc
    ball_layer = 2e-6    # m, ... on the ball
    track_half_width = 3e-4   # m

    [physics]            # assumed values of the reference
    surface_tension = 0.030
    contact_angle = 15.0 # degrees, disc, ball and island
    ...

    [domain]             # units of a
    upstream = 12.0
    ...

    [mesh]
    resolution = "medium"   # coarse | medium | fine

    [run]
    ...

Validation happens once, in :func:`make_case_spec`; errors name the parameter, its value and
its valid range, before anything is written.
"""

from __future__ import annotations

import math
from functools import cached_property
from pathlib import Path
from typing import Annotated, Any, Literal, Union

import numpy as np
from pydantic import (BaseModel, ConfigDict, Discriminator, Field, Tag, ValidationError,
                      field_validator, model_validator)
from scipy.spatial import cKDTree

from ehlfoam.errors import SpecError, format_validation_error

from ehlfoam._io import read_toml

from ehlfoam.contact.spec import PrecalcSpec

_STRICT = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

#: In-plane cell size at the island rim and far away (units a), cells across the gap and their
#: grading toward the walls. The wall cell is 2.4 / 1.7 / 1.2 % of the local gap: the oil films
#: left behind the flooded region are a few per cent of the gap, and with wall cells of 8 % (the
#: levels before, 6 layers graded 3) they were not resolved, too little oil left the flooded
#: region and no run became steady (docs/cases.md, "Mesh levels").
RESOLUTIONS: dict[str, dict[str, float]] = {
    "coarse": {"size_rim": 0.12, "size_far": 0.8, "n_layers": 10, "wall_grading": 8.0},
    "medium": {"size_rim": 0.08, "size_far": 0.55, "n_layers": 12, "wall_grading": 10.0},
    "fine": {"size_rim": 0.055, "size_far": 0.38, "n_layers": 14, "wall_grading": 12.0},
}

#: The levels whose mesh follows the start state's meniscus (``mesh.follow``): a band of
#: in-plane cells of ``band`` (a) along the meniscus, twice as fine on the region's sides
#: (``mesh.follow.sides``), and one wall cell of ``wall_cell`` [m] everywhere, on the base
#: cells and layers of :data:`FOLLOW_BASE`. The wall cell halves with the side cells, as the
#: contact-line model needs (``physics.wall_slip_length``: the slip resolved along the wall
#: as well as across it); under that model, with the side band carried round the region's
#: front (runs/nominal_resolved.toml), the flooded width and the inlet meniscus both
#: converge over the three levels (docs/cases.md, "The front in the side cells on all three
#: levels"). Without slip the cells' numerical slip is the contact lines' only slip and the
#: width follows the side cells ("The menisci's angles are the cells'"); the levels of
#: :data:`RESOLUTIONS` leave the meniscus in their base cells.
FOLLOW_LEVELS: dict[str, dict[str, float]] = {
    "coarse": {"band": 0.24, "wall_cell": 1.6e-6},
    "medium": {"band": 0.12, "wall_cell": 0.8e-6},
    "fine": {"band": 0.06, "wall_cell": 0.4e-6},
}

#: Base cells of the following levels: the coarse level's in-plane sizes (the bands carry the
#: resolution where the meniscus is) and 20 layers across the gap.
FOLLOW_BASE: dict[str, float] = {"size_rim": RESOLUTIONS["coarse"]["size_rim"],
                                 "size_far": RESOLUTIONS["coarse"]["size_far"],
                                 "n_layers": 20}

#: mesh.polar_radius = "auto" with mesh.follow: the polar ring ends at this radius (a), twice
#: the default island's, so that the bands (which refine free quads only) reach the meniscus.
FOLLOW_POLAR_RADIUS = 3.0

#: mesh.polar_radius = "auto": the polar ring's outer radius over the nearest boundary's
#: distance (6.8 a in the default 8 a wide half domain, the radius measured on every level).
POLAR_RING_SHARE = 0.85


class Supply(BaseModel):
    """Oil reaching the contact.

    Attributes:
        mode: "flooded": the whole gap height on the track is oil at the inlet and the case
            starts from a puddle (ample oil); "layers": an oil layer on each surface, on the
            track only, is carried in by the walls (a starved supply); "submerged": the
            contact runs in a bath, the domain starts full of oil and what flows in
            through every open boundary is oil, so the only gas is what the scene makes
            (gas-release scene; with it the gas may dissolve back,
            physics.gas_dissolution_rate).
        disc_layer, ball_layer: oil layer thickness on the disc and on the ball at the
            inlet [m] ("layers" mode).
        track_half_width: half-width of the oil track at the inlet [m].
        track_inner_half_width: half-width of a dry band in the middle of the track [m]
            (0: oil across the whole track). With it the oil arrives as two side bands,
            |y| in [track_inner_half_width, track_half_width]: the two oil tracks a contact in
            state II leaves behind, which come back to the inlet after a revolution when no
            oil is added (ball_on_disc.md).
        initial_puddle: radius of the oil puddle around the contact at t = 0, units of a
            (0: none).
        initial_bubble: radius of a gas seed at t = 0, units of a, centred on the
            downstream point of the island rim (0: none). Neither scene nucleates gas: with
            ample oil the cavitating scene has a bubble only if one is seeded (or air is
            carried in between thin layers); docs/cavitation.md.
    """

    model_config = _STRICT
    mode: Literal["flooded", "layers", "submerged"] = "flooded"
    disc_layer: float = Field(2e-6, ge=0.0, le=1e-3)
    ball_layer: float = Field(2e-6, ge=0.0, le=1e-3)
    track_half_width: float = Field(3e-4, gt=0.0, le=0.1)
    track_inner_half_width: float = Field(0.0, ge=0.0, le=0.1)
    initial_puddle: float = Field(4.0, ge=0.0, le=100.0)
    initial_bubble: float = Field(0.0, ge=0.0, le=20.0)


class Physics(BaseModel):
    """Fluid properties and wetting (the reference's assumed values by default).

    Attributes:
        surface_tension: oil-air surface tension [N/m].
        contact_angle: static contact angle of oil on steel and glass [deg].
        oil_density: [kg/m3]; None takes the lubricant's rho0.
        air_density [kg/m3], air_viscosity [Pa s].
        viscosity_factor: multiplies the oil viscosity (and divides nothing else); 3 turns
            a one-cell-thick gap into Reynolds flow (used by the single-phase check only).
        interface_compression: interFoam's cAlpha (1, the default, keeps the meniscus sharp;
            0 gives 3-15x smaller spurious currents in the oil but smears the
            interface over a few transits: docs/cases.md).
        isotropic_compression: interFoam's icAlpha: the share of the compression velocity
            taken from the local speed |U| instead of the flux through each face (0, the
            default: all from the face flux, so a meniscus lying along the flow is hardly
            compressed; 1: every face of it as hard). At 1 the wall cells move with their
            wall up to an advancing contact line, which then stands at the same place on any
            cells (on the contact-line strip 6.32-6.29 a over 0.12-0.03 a cells, where icAlpha
            0 moves it 0.3 a per halving of the cells), at an apparent angle of 30-33
            deg that the wall's angle hardly moves; at rest it feeds the spurious currents
            (45 % of u on the coarse static meniscus): docs/cases.md, "The advancing contact
            line and the interface compression".
        interface_schemes: "standard" (the default: the templates' schemes) or "balanced":
            uncorrected face gradients for pressure and surface tension alike (on the thin-gap
            mesh's up to ~23 degree non-orthogonal faces the corrected ones do not balance a
            resting meniscus exactly), the interface normal from a point-cells least-squares
            gradient, and the compression flux limited to the interface
            (``Gauss interfaceCompression``). At a static meniscus with the default
            compression it cuts the currents 7-20x on the polar ring (to 0.6-1 % of u); in a
            rolling case it moves the flooded region (inlet meniscus 12 % upstream, 16-37 %
            more oil) where fully corrected gradients keep the standard answer, hence not
            the default (docs/cases.md, "Balanced interface schemes"). With
            run.alpha_subcycles = 3 and run.capillary_safety = 0.5 a resting meniscus
            stays below 1 % of u on all three levels, at 7 times the wall time of a rolling
            transit (docs/cases.md, "Sub-cycles and the capillary limit"). At the default
            step it keeps a resting meniscus at 5-7 a, where the nominal rolling one sits,
            below 0.5 % of u on all three levels (the standard schemes: 1.1-16 %, growing
            with refinement); the nominal case then settles on the medium level in 825 s,
            coarse first ("The static meniscus where the rolling one sits"). On the
            leaning columns the uncorrected gradients change nothing, at rest or rolling;
            the normal and the limited flux do both, and the rolling region then grows
            narrower and longer, holds more oil and so balances later (still 0.95 of the
            inflow out after 26 transits on coarse), with 44-48 %
            of its oil in partly filled cells ("What calms the resting meniscus").
        wall_slip_length: [m] Navier slip on the disc and the ball off the supply track,
            where they come in dry (0, the default: no slip), as v1912's directionMixed
            condition (generator/wall_slip.py): the wall's fluid moves with it but for this
            length times the shear, and the pressure drives (1 + 6 lambda / h) times the
            no-slip flux. With isotropic_compression = 1, 1 um lets the wall's angle reach an
            advancing contact line on in-plane cells of some 0.06 a and finer; on coarser
            ones the line falls back towards the compression's 30 deg (docs/cases.md,
            "Navier slip at the walls").
        ambient_pressure: [Pa, absolute] at the open boundaries (cavitating scene; the
            interface scene works in gauge pressure and adds it only to report one).
        cavitation_pressure: [Pa, absolute] the pressure floor of the cavitating scene
            (compressibleInterFoam's pMin) and the pressure below which the gas-release
            scene releases gas from the oil. The reference assumes 0; a perfect gas needs a
            positive floor, so the default is 1 kPa (sensitivity in docs/cavitation.md).
        gas_release_rate: [1/(Pa s)] of the gas-release scene: oil below the cavitation
            pressure releases gas at k (p_cav - p) volumes of gas per volume of oil per
            second (Kunz's vaporisation term).
        gas_dissolution_rate: [1/s] of the gas-release scene: gas in a cell that also holds
            oil, where the pressure is above the cavitation pressure, goes back into the oil
            at C alpha^2 (1 - alpha) volumes per cell volume per second (alpha the oil
            fraction; Kunz's condensation term, Cc with tInf = 1 s). 0, the default: the
            gas never dissolves back. Only with supply.mode = "submerged": the scene has one
            gas, and where outer air meets the oil it would dissolve the air too.
        air_solubility: Bunsen coefficient of air in the oil: volumes of air (at ambient
            pressure) a volume of oil saturated at ambient pressure holds dissolved; ~0.09
            for mineral oils. The gas-release scene has no budget of dissolved air; the run
            reports its release against what all the oil could give up
            (``gas_release_over_dissolved_air`` in metrics.json).
        oil_bulk_modulus: [Pa] of the oil in the cavitating scene; None (the default) keeps
            the oil incompressible. A value (a mineral oil's isothermal one at ambient
            pressure is ~1.5 GPa) makes it a perfect fluid, which compressibleInterFoam does
            not transport conservatively: 10 % of the oil carried in lost over 4 transits
            against 0.4 % incompressible (docs/cavitation.md), for a density change of
            4e-5 over the meshed region's 60 kPa.
    """

    model_config = _STRICT
    surface_tension: float = Field(0.030, gt=0.0, le=1.0)
    contact_angle: float = Field(15.0, ge=0.0, le=180.0)
    oil_density: float | None = Field(None, gt=0.0, le=1e4)
    air_density: float = Field(1.2, gt=0.0, le=100.0)
    air_viscosity: float = Field(1.8e-5, gt=0.0, le=1.0)
    viscosity_factor: float = Field(1.0, gt=0.0, le=1e3)
    interface_compression: float = Field(1.0, ge=0.0, le=4.0)
    isotropic_compression: float = Field(0.0, ge=0.0, le=1.0)
    interface_schemes: Literal["standard", "balanced"] = "standard"
    wall_slip_length: float = Field(0.0, ge=0.0, le=1e-4)
    ambient_pressure: float = Field(1.013e5, gt=1e3, le=1e7)
    cavitation_pressure: float = Field(1e3, gt=0.0, le=1e5)
    oil_bulk_modulus: float | None = Field(None, gt=1e6, le=1e11)
    gas_release_rate: float = Field(1e-3, gt=0.0, le=1e3)
    gas_dissolution_rate: float = Field(0.0, ge=0.0, le=1e7)
    air_solubility: float = Field(0.09, ge=0.0, le=1.0)


class Domain(BaseModel):
    """Extents around the contact centre, units of the Hertzian radius a.

    Attributes:
        upstream: distance to the inlet boundary (x = -upstream a). 12 a: with ample oil
            (8 um layers at 8 mm/s) the inlet meniscus sits 6-6.6 a upstream of x = -a, and
            at 8 a it touched the boundary (docs/cases.md, "The upstream boundary leaked oil").
        downstream: distance to the outlet boundary.
        side: distance to the side boundary (|y| = side a).
        island_radius: radius of the island wall that replaces the Hertzian contact
            (not meshed); > 1 so that its gap is sub-micron but not nanometric.
        symmetry: "half" (y >= 0 with a symmetry plane) or "full".
    """

    model_config = _STRICT
    upstream: float = Field(12.0, gt=1.0, le=200.0)
    downstream: float = Field(14.0, gt=1.0, le=200.0)
    side: float = Field(8.0, gt=1.0, le=200.0)
    island_radius: float = Field(1.5, gt=1.0, le=10.0)
    symmetry: Literal["half", "full"] = "half"

    @model_validator(mode="after")
    def _island_inside(self) -> "Domain":
        limit = min(self.upstream, self.downstream, self.side)
        if self.island_radius >= 0.8 * limit:
            raise ValueError(f"island_radius = {self.island_radius:g} a must stay below 0.8 x "
                             f"the nearest boundary ({0.8 * limit:g} a)")
        return self


#: how fast, in a of cell size per a of distance, the cells grow back from a refinement box
#: (mesh.refine) to the level's size: 0.1 a cells reach 0.55 a within 1.8 a
REFINE_GROWTH = 0.25


class RefineBox(BaseModel):
    """A box of finer in-plane cells (``mesh.refine``), units of a: x in [x_min, x_max],
    |y| in [y_min, y_max], cells of ``size`` there, growing back to the level's size at
    :data:`REFINE_GROWTH` outside. It refines the free quads only: the polar ring keeps its
    cells. For the films the rear meniscus lays (docs/cases.md, "The films decide the width")."""

    model_config = _STRICT
    x_min: float = Field(ge=-200.0, le=200.0)
    x_max: float = Field(ge=-200.0, le=200.0)
    y_min: float = Field(0.0, ge=0.0, le=200.0)
    y_max: float = Field(gt=0.0, le=200.0)
    size: float = Field(gt=0.0, le=10.0)

    @model_validator(mode="after")
    def _ordered(self) -> "RefineBox":
        if not self.x_min < self.x_max:
            raise ValueError(f"x_min = {self.x_min:g} a must be below x_max = {self.x_max:g} a")
        if not self.y_min < self.y_max:
            raise ValueError(f"y_min = {self.y_min:g} a must be below y_max = {self.y_max:g} a")
        return self

    def size_at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Cell size (a) this box asks for at (x, y) (a): its size inside, growing with the
        distance outside."""
        dx = np.maximum(np.maximum(self.x_min - x, x - self.x_max), 0.0)
        ay = np.abs(y)
        dy = np.maximum(np.maximum(self.y_min - ay, ay - self.y_max), 0.0)
        return self.size + REFINE_GROWTH * np.hypot(dx, dy)


class RefineBand(BaseModel):
    """A band of finer in-plane cells along a line (``mesh.refine``), units of a: within
    ``half_width`` of the polyline through ``points`` ((x, |y|) pairs, so a half domain's
    line serves the full domain too), cells of ``size``, growing back to the level's size at
    :data:`REFINE_GROWTH` further out. Like a box it refines the free quads only.
    ``ehlfoam band CASE`` writes the bands that follow a run's mid-gap meniscus, so that a
    continued run has its whole meniscus in cells of a chosen size (docs/cases.md, "A band
    along the meniscus")."""

    model_config = _STRICT
    points: tuple[tuple[float, float], ...] = Field(min_length=2, max_length=10_000)
    half_width: float = Field(gt=0.0, le=20.0)
    size: float = Field(gt=0.0, le=10.0)

    @field_validator("points")
    @classmethod
    def _points_in_range(cls, points: tuple[tuple[float, float], ...]):
        for x, y in points:
            if not (-200.0 <= x <= 200.0 and 0.0 <= y <= 200.0):
                raise ValueError(f"point ({x:g}, {y:g}) a lies outside -200 <= x <= 200, "
                                 "0 <= y <= 200 (units of a, y = |y|)")
        return points

    @cached_property
    def _tree(self) -> cKDTree:
        """The line sampled every quarter of the smaller of size and half-width: the distance
        to the samples is the distance to the line within an eighth of that."""
        p = np.asarray(self.points, float)
        step = 0.25 * min(self.size, self.half_width)
        seg = np.diff(p, axis=0)
        n = np.maximum(np.ceil(np.hypot(seg[:, 0], seg[:, 1]) / step).astype(int), 1)
        samples = [p[i] + np.outer(np.arange(k) / k, seg[i]) for i, k in enumerate(n)]
        return cKDTree(np.vstack(samples + [p[-1:]]))

    def size_at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Cell size (a) this band asks for at (x, y) (a): its size within half_width of
        its line, growing with the distance further out."""
        x, y = np.broadcast_arrays(np.asarray(x, float), np.abs(np.asarray(y, float)))
        dist, _ = self._tree.query(np.stack([x.ravel(), y.ravel()], axis=1))
        beyond = np.maximum(dist.reshape(x.shape) - self.half_width, 0.0)
        return self.size + REFINE_GROWTH * beyond


def _refine_kind(value: Any) -> str:
    """Which kind of refinement a ``mesh.refine`` entry is: a band has points."""
    if isinstance(value, dict):
        return "band" if "points" in value else "box"
    return "band" if isinstance(value, RefineBand) else "box"


#: the kinds of ``mesh.refine`` entries, by the tag pydantic puts in an error's location
REFINE_KINDS: dict[str, type[BaseModel]] = {"box": RefineBox, "band": RefineBand}

#: an entry of ``mesh.refine``: a box, or a band along a line
Refinement = Annotated[Union[tuple(Annotated[m, Tag(t)] for t, m in REFINE_KINDS.items())],
                       Discriminator(_refine_kind)]


class SideBox(BaseModel):
    """Where the followed meniscus is the region's side (``mesh.follow.sides``), units of a:
    the band's points with x_min <= x <= x_max and |y| >= y_min get a second band of half the
    level's cells and half its half-width. The width is set there: the meniscus meeting both
    walls spans 0.13-0.2 a in plane where the gap is 60-95 um (docs/cases.md, "Three steps
    of one series").

    ``size`` and ``half_width`` (a) override the second band's cells and half-width, which
    separates the sides' resolution from the rest of the meniscus's (docs/cases.md, "The
    side band alone"); None (the default): half the level's."""

    model_config = _STRICT
    x_min: float = Field(ge=-200.0, le=200.0)
    x_max: float = Field(ge=-200.0, le=200.0)
    y_min: float = Field(0.0, ge=0.0, le=200.0)
    size: float | None = Field(None, gt=0.0, le=10.0)
    half_width: float | None = Field(None, gt=0.0, le=20.0)

    @model_validator(mode="after")
    def _ordered(self) -> "SideBox":
        if not self.x_min < self.x_max:
            raise ValueError(f"x_min = {self.x_min:g} a must be below x_max = {self.x_max:g} a")
        return self

    def holds(self, points: np.ndarray) -> np.ndarray:
        """Which of the (k, 2) points (x, |y|), units of a, lie in the box (bool, k)."""
        x, y = points[:, 0], np.abs(points[:, 1])
        return (x >= self.x_min) & (x <= self.x_max) & (y >= self.y_min)


class Follow(BaseModel):
    """A mesh that follows the meniscus of the state the case starts from (``mesh.follow``,
    with ``ehlfoam case --start-from``): bands of the level's cells
    (:data:`FOLLOW_LEVELS`) within ``half_width`` (a) of the start state's mid-gap meniscus,
    and optionally a finer band on the region's sides (:class:`SideBox`). The written case
    has the bands in ``mesh.refine`` and the level's sizes spelled out."""

    model_config = _STRICT
    half_width: float = Field(1.0, gt=0.0, le=20.0)
    sides: SideBox | None = None


class Mesh(BaseModel):
    """Resolution level (see :data:`RESOLUTIONS`) and optional overrides.

    Attributes:
        resolution: "coarse", "medium" or "fine".
        n_layers: cells across the gap (None: the level's value).
        size_rim, size_far: in-plane cell size at the island rim / far away, units of a.
            The nominal menisci sit in cells of about size_far, and the flooded width
            depends on it (docs/cases.md, "The far field decides the width").
        wall_grading: mid-gap cell height over wall cell height (1: uniform layers); finer
            cells at the walls carry the supply layers and the films left behind.
        wall_cell: instead of wall_grading, one wall cell height [m] everywhere: each column
            of cells graded just enough for it (uniform where the gap is too thin, graded
            at most 100). A share of the gap that falls as the gap grows: thin where the
            rear meniscus lays its films in a wide gap, thick near the contact, where the
            region's front runs onto dry walls and in-plane cells within some 15 wall cells
            hold it (docs/cases.md, "One wall cell everywhere"). None by default.
        polar_radius: outer radius, units of a, of a structured polar ring of cells around
            the island (log-polar, near-square cells, the size growing with the radius as
            everywhere); "auto" (the default): :data:`POLAR_RING_SHARE` x the nearest
            boundary (6.8 a in the default domain); None: free quads everywhere. Below
            0.95 x the nearest boundary. A circular meniscus meets every ring cell the same
            way, which converges the flooded width where free quads do not (docs/cases.md,
            "A polar ring around the contact", "The polar ring becomes the default").
            With ``follow``, "auto" is :data:`FOLLOW_POLAR_RADIUS`.
        columns: how the columns of nodes cross the gap: "normal" (the default) leans each
            column so that it meets every layer at right angles (an in-plane shift of a
            few um at most), "vertical" keeps them upright, which makes every face where
            the ball slopes non-orthogonal (docs/cases.md, "Columns across the gap").
        refine: boxes (:class:`RefineBox`) and bands along a line (:class:`RefineBand`) of
            finer in-plane cells, e.g. ``[{x_min = 5, x_max = 14, y_max = 8, size = 0.1}]``
            where the rear meniscus and the region's shoulders sit: the films they lay
            converge only in cells of 0.05-0.1 a (docs/cases.md, "The films decide the
            width"), and an advancing meniscus on dry walls holds its suction only in cells
            within some 15 wall cells ("The region's sides are moving contact lines").
            ``ehlfoam band CASE`` writes bands along a run's meniscus. Empty by default.
        follow: the following levels (:class:`Follow`, :data:`FOLLOW_LEVELS`): the mesh
            follows the meniscus of the state the case starts from (``--start-from``); the
            level then sets the band's cells and the wall cell, on :data:`FOLLOW_BASE`.
            None (the default): the levels of :data:`RESOLUTIONS`.
    """

    model_config = _STRICT
    resolution: Literal["coarse", "medium", "fine"] = "medium"
    n_layers: int | None = Field(None, ge=1, le=64)
    size_rim: float | None = Field(None, gt=0.0, le=10.0)
    size_far: float | None = Field(None, gt=0.0, le=50.0)
    wall_grading: float | None = Field(None, ge=1.0, le=100.0)
    wall_cell: float | None = Field(None, ge=1e-8, le=1e-4)
    polar_radius: float | Literal["auto"] | None = "auto"
    columns: Literal["normal", "vertical"] = "normal"
    refine: tuple[Refinement, ...] = ()
    follow: Follow | None = None

    @field_validator("polar_radius", mode="before")
    @classmethod
    def _polar_radius_valid(cls, value: Any) -> Any:
        if value is None or value == "auto":
            return value
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not 1.0 < value <= 200.0:
            raise ValueError('must be a radius in units of a (1 < radius <= 200), "auto" '
                             f'({POLAR_RING_SHARE:g} x the nearest boundary) or none (free '
                             'quads)')
        return float(value)

    @model_validator(mode="after")
    def _one_wall_rule(self) -> "Mesh":
        if self.wall_cell is not None and self.wall_grading is not None:
            raise ValueError(f"set one of wall_grading ({self.wall_grading:g}) and wall_cell "
                             f"({self.wall_cell:g} m): the wall cell fixes each column's "
                             f"grading")
        return self

    def level(self) -> dict[str, float | None]:
        """The level's sizes with the overrides applied: ``n_layers``, ``size_rim`` and
        ``size_far`` (a), ``wall_grading`` (-) and ``wall_cell`` [m]. One of the last two
        is None: with ``wall_cell`` set the columns are graded for it and the level's
        grading does not apply."""
        if self.follow is None:
            out = dict(RESOLUTIONS[self.resolution])
            wall_cell = self.wall_cell
        else:
            out = {**FOLLOW_BASE, "wall_grading": None}
            wall_cell = self.wall_cell
            if wall_cell is None and self.wall_grading is None:   # the level's wall cell
                wall_cell = FOLLOW_LEVELS[self.resolution]["wall_cell"]
        for key in ("n_layers", "size_rim", "size_far", "wall_grading"):
            if getattr(self, key) is not None:
                out[key] = getattr(self, key)
        out["n_layers"] = int(out["n_layers"])
        out["wall_cell"] = wall_cell
        if wall_cell is not None:
            out["wall_grading"] = None
        return out

    @property
    def follow_band(self) -> float | None:
        """In-plane cell size (a) of the band along the followed meniscus (None without
        ``follow``)."""
        return None if self.follow is None else FOLLOW_LEVELS[self.resolution]["band"]


class Run(BaseModel):
    """Time stepping, steady-state detection and limits.

    Attributes:
        end_time: simulated time limit [s]; None: ``transits_max`` transit times.
        transit_length: the length, units of a, whose transit time L/u is the steady-state
            window (about the flooded region's size).
        transits_max: time limit in transit times when end_time is None.
        steady_tolerance: relative change of the oil volume and of the meniscus positions
            (units a) over one transit below which the run counts as steady.
        writes_per_transit: field writes per transit time (what the monitor sees).
        wall_limit: wall-clock limit [s].
        max_courant, max_alpha_courant: OpenFOAM's maxCo and maxAlphaCo (1: measured
            stable and within the run-to-run scatter of 0.5 on the nominal case,
            docs/cases.md).
        capillary_limit: time-step limit for surface tension: "galusinski-vigneaux"
            (viscous, the one that matters at Re << 1), "brackbill" (inertial, strict) or
            "none".
        capillary_safety: factor on that limit. 2 (the default since 2026-11-24): a
            meniscus at rest keeps its currents at 7.5-8.5 % of u where 3 let them burst to
            42 %, and the rolling case's oil and length move halfway to the values of 1, at
            1.5 times the steps a transit of 3 (1: 3.4 times). docs/cases.md, "The capillary
            safety". For the films a rear meniscus lays, use 0.5: at 2 a slab's straight rear
            meniscus grows lateral currents of 0.3-0.9 u, at 0.5 (on 0.045-0.06 a cells)
            0.002-0.008 u ("Lateral currents").
        air_viscosity_factor: the air's viscosity in the solver is this times
            physics.air_viscosity (not in the gas-release scene: :attr:`CaseSpec.air_viscosity`).
            Spurious capillary currents in the air scale as
            sigma / mu_air and set the Courant-limited time step; 100 (the default, still
            12 times less viscous than the oil) halves the steps of the medium level
            against 20 at a measured cost of a few per cent in the flow pattern
            (docs/cases.md: the air's pressure drops are some 6 % of the capillary
            pressure). 1 is the physical air.
        pressure_correctors: PIMPLE's nCorrectors (pressure solutions per time step).
        alpha_subcycles: MULES sub-cycles of the oil fraction per time step
            (nAlphaSubCycles); None keeps the template's (1 in the interface scenes, 3 in
            the cavitating one). 3 calms a resting meniscus (docs/cases.md, "Sub-cycles
            and the capillary limit").
        n_procs: MPI ranks (1: serial).
    """

    model_config = _STRICT
    end_time: float | None = Field(None, gt=0.0, le=1e3)
    transit_length: float = Field(10.0, gt=0.0, le=1e3)
    transits_max: float = Field(4.0, gt=0.0, le=1e3)
    steady_tolerance: float = Field(0.01, gt=0.0, lt=1.0)
    writes_per_transit: int = Field(10, ge=2, le=1000)
    wall_limit: float = Field(3600.0, gt=0.0, le=1e6)
    max_courant: float = Field(1.0, gt=0.0, le=10.0)
    max_alpha_courant: float = Field(1.0, gt=0.0, le=10.0)
    capillary_limit: Literal["galusinski-vigneaux", "brackbill", "none"] = "galusinski-vigneaux"
    capillary_safety: float = Field(2.0, gt=0.0, le=100.0)
    air_viscosity_factor: float = Field(100.0, ge=1.0, le=1000.0)
    pressure_correctors: int = Field(3, ge=1, le=10)
    alpha_subcycles: int | None = Field(None, ge=1, le=20)
    n_procs: int = Field(1, ge=1, le=1024)


#: The OpenFOAM application of each scene.
SOLVERS = {"interface": "interFoam", "single-phase": "interFoam",
           "cavitating": "compressibleInterFoam", "gas-release": "interPhaseChangeFoam"}


class CaseSpec(BaseModel):
    """One OpenFOAM case around the EHL contact.

    Attributes:
        name: label used in reports.
        scene: "interface": two-phase oil/air, surface tension, no cavitation (interFoam);
            "single-phase": oil everywhere (the check against the Reynolds solution);
            "cavitating": two-phase oil/air where the air is a perfect gas that expands
            below ambient pressure, down to the cavitation pressure (compressibleInterFoam).
            "gas-release": incompressible oil and air, and oil below the cavitation pressure
            turns into gas at physics.gas_release_rate (interPhaseChangeFoam, Kunz's
            vaporisation term only): the gas that makes a bubble where no air reaches.
            Its air has the oil's kinematic viscosity (:attr:`air_viscosity`).
        contact: the EHL conditions (:class:`ehlfoam.contact.spec.PrecalcSpec`).
        walls_moving: False holds both walls still (the static-meniscus test).
    """

    model_config = _STRICT
    name: str = "case"
    scene: Literal["interface", "single-phase", "cavitating", "gas-release"] = "interface"
    contact: PrecalcSpec = PrecalcSpec(speed=0.008)
    supply: Supply = Supply()
    physics: Physics = Physics()
    domain: Domain = Domain()
    mesh: Mesh = Mesh()
    run: Run = Run()
    walls_moving: bool = True

    @model_validator(mode="after")
    def _polar_ring_inside(self) -> "CaseSpec":
        rp, d = self.polar_radius, self.domain   # "auto" resolved: always inside
        if rp is not None:
            top = 0.95 * min(d.upstream, d.downstream, d.side)
            if not d.island_radius < rp <= top:
                raise ValueError(f"mesh.polar_radius = {rp:g} a must lie in "
                                 f"({d.island_radius:g}, {top:g}] a: beyond the island "
                                 f"(domain.island_radius) and within 0.95 x the nearest "
                                 f"boundary")
        return self

    # ---- derived quantities: the one place they are computed ---------------------------
    @property
    def a(self) -> float:
        """Hertzian radius [m]."""
        return self.contact.contact().a

    @property
    def polar_radius(self) -> float | None:
        """Outer radius of the polar ring, units of a (``mesh.polar_radius`` with "auto"
        resolved against the domain), or None for free quads."""
        rp, d = self.mesh.polar_radius, self.domain
        if rp == "auto" and self.mesh.follow is not None:
            return FOLLOW_POLAR_RADIUS
        if rp == "auto":
            return POLAR_RING_SHARE * min(d.upstream, d.downstream, d.side)
        return rp

    @property
    def speed(self) -> float:
        """Rolling speed u [m/s] (both surfaces)."""
        return self.contact.speed

    @property
    def wall_speed(self) -> float:
        """Speed of the disc and the ball surface [m/s]: u, or 0 with walls_moving false."""
        return self.speed if self.walls_moving else 0.0

    @property
    def oil_viscosity(self) -> float:
        """Oil dynamic viscosity at ambient pressure [Pa s], times viscosity_factor."""
        return self.contact.oil().eta0 * self.physics.viscosity_factor

    @property
    def air_viscosity(self) -> float:
        """The air's dynamic viscosity in the solver [Pa s]: physics.air_viscosity times
        run.air_viscosity_factor; in the gas-release scene the air has the oil's kinematic
        viscosity instead, mu_air = rho_air eta_oil / rho_oil (1.7 times the real air's at 40 C).

        interPhaseChangeFoam v1912 computes the mixture's kinematic viscosity once, from the
        initial oil fraction, and never again (the correct() of its phase-change models is
        empty, so incompressibleTwoPhaseMixture::calcNu is not called): oil that reaches a cell
        that started as air keeps the air's kinematic viscosity. With equal kinematic
        viscosities the frozen field is right everywhere (docs/cavitation.md)."""
        if self.scene == "gas-release":
            return self.physics.air_density * self.oil_viscosity / self.oil_density
        return self.physics.air_viscosity * self.run.air_viscosity_factor

    @property
    def oil_density(self) -> float:
        """[kg/m3]."""
        return self.physics.oil_density or self.contact.oil().rho0

    @property
    def fills_domain(self) -> bool:
        """Oil fills the domain at t = 0 and is what flows in through the open boundaries
        (the single-phase scene, and a submerged supply)."""
        return self.scene == "single-phase" or self.supply.mode == "submerged"

    @property
    def solver(self) -> str:
        """The OpenFOAM application of the scene."""
        return SOLVERS[self.scene]

    @property
    def temperature_k(self) -> float:
        """Oil (and air) temperature [K]."""
        return self.contact.temperature + 273.15

    @property
    def transit_time(self) -> float:
        """transit_length a / u [s]."""
        return self.run.transit_length * self.a / self.speed

    @property
    def end_time(self) -> float:
        """Simulated time limit [s]."""
        return self.run.end_time or self.run.transits_max * self.transit_time

    def to_toml_dict(self) -> dict[str, Any]:
        """The spec as plain TOML-able data (None values dropped)."""
        return _drop_none(self.model_dump())


def _drop_none(value):
    if isinstance(value, dict):
        return {k: _drop_none(v) for k, v in value.items() if v is not None}
    return value


def make_case_spec(data: dict[str, Any] | None = None, **overrides: Any) -> CaseSpec:
    """Validate a case spec from nested data; ``overrides`` are dotted keys
    (``{"contact.speed": 0.017}``) applied on top; None clears an optional key
    (``{"mesh.polar_radius": None}``: free quads). Raises :class:`SpecError`."""
    data = _deep_copy(data or {})
    for dotted, value in overrides.items():
        node = data
        *parents, leaf = dotted.split(".")
        for p in parents:
            node = node.setdefault(p, {})
        node[leaf] = value
    try:
        spec = CaseSpec(**data)
    except ValidationError as err:
        raise SpecError(f"invalid case spec: {format_validation_error(err, CaseSpec)}") from None
    except SpecError as err:  # raised by PrecalcSpec's own validators
        raise SpecError(f"invalid case spec: contact: {err}") from None
    _check_supply_fits(spec)
    _check_scene_options(spec)
    return spec


def _check_scene_options(spec: CaseSpec) -> None:
    default = Run.model_fields["air_viscosity_factor"].default
    if spec.scene == "gas-release" and spec.run.air_viscosity_factor != default:
        raise SpecError(
            f"invalid case spec: run.air_viscosity_factor = {spec.run.air_viscosity_factor:g} "
            f"does not apply to scene = \"gas-release\", whose air has the oil's kinematic "
            f"viscosity (leave it at {default:g})")
    rate = spec.physics.gas_dissolution_rate
    if rate > 0 and (spec.scene != "gas-release" or spec.supply.mode != "submerged"):
        raise SpecError(
            f"invalid case spec: physics.gas_dissolution_rate = {rate:g} 1/s needs scene = "
            f"\"gas-release\" and supply.mode = \"submerged\" (here {spec.scene!r}, "
            f"{spec.supply.mode!r}): the scene has one gas, and where outer air meets the oil "
            f"it would dissolve the air too (valid range otherwise: 0)")


def _check_supply_fits(spec: CaseSpec) -> None:
    side = spec.domain.side * spec.a
    if spec.supply.track_half_width >= side:
        raise SpecError(
            f"invalid case spec: supply.track_half_width = {spec.supply.track_half_width:g} m "
            f"must be smaller than the domain side {spec.domain.side:g} a = {side:g} m")
    inner = spec.supply.track_inner_half_width
    if inner >= spec.supply.track_half_width:
        raise SpecError(
            f"invalid case spec: supply.track_inner_half_width = {inner:g} m must be in "
            f"[0, {spec.supply.track_half_width:g}) m (below supply.track_half_width)")
    if not math.isfinite(spec.a):
        raise SpecError("invalid case spec: contact gives a non-finite Hertz radius")


def _deep_copy(data):
    if isinstance(data, dict):
        return {k: _deep_copy(v) for k, v in data.items()}
    return data


def load_case_spec(path: str | Path, **overrides: Any) -> CaseSpec:
    """Read and validate a TOML case spec; ``overrides`` as in :func:`make_case_spec`."""
    return make_case_spec(read_toml(path), **overrides)
