"""The plain tables of a case spec: ``[supply]``, ``[physics]``, ``[domain]`` and ``[run]``.

Each field states what it is, its unit and what it does (``description``,
``json_schema_extra["unit"]``: the spec reference in the docs and the error messages read
them). SI units, but lengths of the domain in units of the Hertzian radius a and angles in
degrees.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from ehlfoam.contact.spec import PrecalcSpec

#: Every table of a spec: unknown keys are refused, values frozen, NaN and inf refused, and
#: types strict (pydantic's strict mode): no true for a number, no "25" for a number, no 2.0
#: for an integer; an integer is a number (TOML writes 20 for 20.0). A list is a tuple only
#: through :func:`as_tuples` (TOML has no tuples).
STRICT = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False, strict=True)


#: The contact of a case spec without a [contact] table: the precalc's defaults at the
#: reference experiment's 8 mm/s
DEFAULT_CONTACT = PrecalcSpec(speed=0.008)


def deep_copy(data: Any) -> Any:
    """A copy of a spec's data whose tables (dicts, nested too) are new; values shared."""
    if isinstance(data, dict):
        return {k: deep_copy(v) for k, v in data.items()}
    return data


def merge_tables(into: dict[str, Any], table: dict[str, Any]) -> None:
    """Merge ``table`` into ``into`` key by key (tables within tables too; other values
    replace)."""
    for key, value in table.items():
        if isinstance(value, dict) and isinstance(into.get(key), dict):
            merge_tables(into[key], value)
        else:
            into[key] = deep_copy(value)


def as_tuples(value: Any) -> Any:
    """A before-validator of a tuple field of a strict model: TOML and JSON arrays (lists,
    nested too) become tuples, their items unchanged (and validated strictly)."""
    return tuple(as_tuples(v) for v in value) if isinstance(value, list) else value


class Supply(BaseModel):
    """Oil reaching the contact."""

    model_config = STRICT
    mode: Literal["flooded", "layers", "submerged", "rig"] = Field(
        "flooded",
        description='How oil reaches the contact. "flooded": the whole gap height on the track '
                    'is oil at the inlet, and the case starts from a puddle (ample oil); '
                    '"layers": an oil layer on each surface, on the track only, carried in by '
                    'the walls (a starved supply); "submerged": the contact runs in a bath, the '
                    'domain starts full of oil and oil flows in through every open boundary, '
                    'so that the only gas is what the scene makes; "rig": the oil on the rig '
                    '(disc_oil and ball_oil, or the mean layers disc_layer and ball_layer over '
                    'the track at the start) and nothing added: each pass takes in what the '
                    'passes before left on the tracks after its reflow over a revolution (the '
                    '[cycle] table; scene = "thin-film" only).')
    disc_layer: float = Field(
        2e-6, ge=0.0, le=1e-3,
        description='Thickness of the oil layer the disc carries into the inlet ("layers" '
                    'mode); in "rig" mode the mean layer on its track at the start.',
        json_schema_extra={"unit": "m"})
    ball_layer: float = Field(
        2e-6, ge=0.0, le=1e-3,
        description='Thickness of the oil layer the ball carries into the inlet ("layers" '
                    'mode); in "rig" mode the mean layer on its track at the start.',
        json_schema_extra={"unit": "m"})
    disc_oil: float | None = Field(
        None, gt=0.0, le=1e-5,
        description='The oil on the disc\'s track at the start ("rig" mode), spread evenly '
                    'over the track (|y| < track_half_width, the circle of track_radius); '
                    'none: disc_layer over the track.',
        json_schema_extra={"unit": "m3"})
    ball_oil: float | None = Field(
        None, gt=0.0, le=1e-5,
        description='The oil on the ball\'s track at the start ("rig" mode), spread evenly '
                    'over it (|y| < track_half_width, the great circle of contact.radius); '
                    'none: ball_layer over the track.',
        json_schema_extra={"unit": "m3"})
    track_radius: float = Field(
        0.039, gt=0.0, le=1.0,
        description='Radius of the disc\'s track ("rig" mode): a revolution takes '
                    '2 pi track_radius / u (the reference rig\'s, about 39 mm). Larger than '
                    'the domain\'s length (domain.upstream + domain.downstream).',
        json_schema_extra={"unit": "m"})
    track_half_width: float = Field(
        3e-4, gt=0.0, le=0.1,
        description="Half-width of the oil track at the inlet.",
        json_schema_extra={"unit": "m"})
    track_inner_half_width: float = Field(
        0.0, ge=0.0, le=0.1,
        description="Half-width of a dry band in the middle of the track (0: oil across the "
                    "whole track). With it the oil arrives as two side bands, the tracks a "
                    "contact in state II leaves behind.",
        json_schema_extra={"unit": "m"})
    initial_puddle: float = Field(
        4.0, ge=0.0, le=100.0,
        description="Radius of the oil puddle around the contact at t = 0 (0: none).",
        json_schema_extra={"unit": "a"})
    initial_bubble: float = Field(
        0.0, ge=0.0, le=20.0,
        description="Radius of a gas seed at t = 0, centred on the downstream point of the "
                    "island rim (0: none). No scene nucleates gas: with ample oil a bubble "
                    "forms only where one is seeded.",
        json_schema_extra={"unit": "a"})


class Physics(BaseModel):
    """Fluid properties, wetting and the interface numerics (the reference's assumed values by
    default)."""

    model_config = STRICT
    surface_tension: float = Field(
        0.030, gt=0.0, le=1.0,
        description="Oil-air surface tension.",
        json_schema_extra={"unit": "N/m"})
    contact_angle: float = Field(
        15.0, ge=0.0, le=180.0,
        description="Static contact angle of the oil on the disc, the ball and the island.",
        json_schema_extra={"unit": "deg"})
    advancing_angle: float | None = Field(
        None, ge=0.0, le=180.0,
        description="Apparent contact angle of a meniscus that the walls run into over dry "
                    "ground (Cox-Voinov's dependence on the speed across the line): in the "
                    "thin-film scene the menisci off the track that the walls run into; in "
                    "the 3D scenes, with receding_angle, a contact line the oil advances "
                    "over the wall "
                    "(docs/models/interface.md#a-wall-angle-that-follows-the-line). None: "
                    "contact_angle.",
        json_schema_extra={"unit": "deg"})
    receding_angle: float | None = Field(
        None, ge=0.0, le=180.0,
        description="3D scenes: the contact angle of a line that the oil recedes over the "
                    "wall. With advancing_angle or this set the walls' angle follows the "
                    "oil's speed across the line relative to the wall, from receding_angle "
                    "to advancing_angle (a tanh over a tenth of the rolling speed), and "
                    "oil at rest on the wall (a line at rest, the layers the walls carry) "
                    "takes their mean, not contact_angle. None: contact_angle.",
        json_schema_extra={"unit": "deg"})
    oil_density: float | None = Field(
        None, gt=0.0, le=1e4,
        description="Oil density; none takes the lubricant's rho0.",
        json_schema_extra={"unit": "kg/m3"})
    air_density: float = Field(
        1.2, gt=0.0, le=100.0,
        description="Air density.",
        json_schema_extra={"unit": "kg/m3"})
    air_viscosity: float = Field(
        1.8e-5, gt=0.0, le=1.0,
        description="Dynamic viscosity of the air; the solver's is this times "
                    "run.air_viscosity_factor.",
        json_schema_extra={"unit": "Pa s"})
    viscosity_factor: float = Field(
        1.0, gt=0.0, le=1e3,
        description="Multiplies the oil viscosity (and nothing else); 3 turns a "
                    "one-cell-thick gap into Reynolds flow (the single-phase check only).")
    interface_compression: float = Field(
        1.0, ge=0.0, le=4.0,
        description="interFoam's cAlpha: 1 keeps the meniscus sharp; 0 gives 3-15 times "
                    "smaller spurious currents in the oil but smears the interface over a few "
                    "transits.")
    isotropic_compression: float = Field(
        0.0, ge=0.0, le=1.0,
        description="interFoam's icAlpha: the share of the compression velocity taken from "
                    "the local speed |U| instead of the flux through each face (0: all from "
                    "the face flux, so that a meniscus lying along the flow is hardly "
                    "compressed). At 1 an advancing contact line stands at the same place on "
                    "any cells, at an apparent angle of 30-33 deg, but a resting meniscus "
                    "has stronger spurious currents. The resolved rungs set 1. The gas-release "
                    "scene refuses any but 0: the thin films' oil fraction climbs past 1 "
                    "with it and the run diverges.")
    interface_schemes: Literal["standard", "balanced"] = Field(
        "standard",
        description='"standard": the templates\' schemes; "balanced": uncorrected face '
                    'gradients for pressure and surface tension alike, the interface normal '
                    'from a point-cells least-squares gradient and the compression flux '
                    'limited to the interface. It calms a resting meniscus (currents below '
                    '1 % of u) but moves a rolling case\'s flooded region, hence not the '
                    'default.')
    interface_advection: Literal["compression", "isoadvector"] = Field(
        "compression",
        description='How the interface scene moves the interface: "compression", '
                    "interFoam's algebraic volume of fluid kept sharp by a compression flux "
                    '(interface_compression, isotropic_compression); "isoadvector", '
                    "interIsoFoam's geometric one (isoAdvector), sharp without a compression "
                    "term. At 40 C, 17 mm/s on 1 um layers the resolved coarse level smears "
                    "the region across the gap within a transit or diverges with the "
                    "compression and keeps it sharp with isoAdvector. The interface scene only "
                    "(interIsoFoam has no phase change).")
    wall_slip_length: float = Field(
        0.0, ge=0.0, le=1e-4,
        description="Navier slip length on the disc and the ball off the supply track, where "
                    "they come in dry (0: no slip); the pressure then drives (1 + 6 lambda / "
                    "h) times the no-slip flux. With isotropic_compression = 1, 1e-6 lets the "
                    "wall's angle reach an advancing contact line on in-plane cells of some "
                    "0.06 a and finer.",
        json_schema_extra={"unit": "m"})
    ambient_pressure: float = Field(
        1.013e5, gt=1e3, le=1e7,
        description="Absolute pressure at the open boundaries (cavitating scene; the "
                    "interface scene works in gauge pressure and adds it only to report one).",
        json_schema_extra={"unit": "Pa"})
    cavitation_pressure: float = Field(
        1e3, gt=0.0, le=1e5,
        description="Absolute pressure floor of the cavitating scene (compressibleInterFoam's "
                    "pMin), and the pressure below which the gas-release scene releases gas "
                    "from the oil. Positive: a perfect gas needs a positive floor.",
        json_schema_extra={"unit": "Pa"})
    oil_bulk_modulus: float | None = Field(
        None, gt=1e6, le=1e11,
        description="Bulk modulus of the oil in the cavitating scene; none keeps the oil "
                    "incompressible. A value (a mineral oil's is about 1.5e9 at ambient "
                    "pressure) makes it a perfect fluid, which compressibleInterFoam does not "
                    "transport conservatively.",
        json_schema_extra={"unit": "Pa"})
    gas_release_rate: float = Field(
        1e-3, gt=0.0, le=1e3,
        description="Gas-release scene: oil below the cavitation pressure releases "
                    "k (p_cav - p) volumes of gas per volume of oil per second (Kunz's "
                    "vaporisation term).",
        json_schema_extra={"unit": "1/(Pa s)"})
    gas_dissolution_rate: float = Field(
        0.0, ge=0.0, le=1e7,
        description='Gas-release scene with supply.mode = "submerged" only: gas in a cell '
                    'that also holds oil, above the cavitation pressure, dissolves back at '
                    'C alpha^2 (1 - alpha) volumes per cell volume per second (Kunz\'s '
                    'condensation term). 0: the gas never dissolves back.',
        json_schema_extra={"unit": "1/s"})
    air_solubility: float = Field(
        0.09, ge=0.0, le=1.0,
        description="Bunsen coefficient of air in the oil: volumes of air (at ambient "
                    "pressure) that a volume of saturated oil holds dissolved (about 0.09 for "
                    "mineral oils). The run reports its gas release against it; the "
                    "thin-film scene's gas balance (thin_film.bubble_gas = \"balance\") takes "
                    "it as Henry's law's Ostwald coefficient, C = s p / (R T).")

    @model_validator(mode="after")
    def _angles_in_order(self) -> "Physics":
        advancing, receding = self.wall_angles
        if receding > advancing:
            raise ValueError(f"receding_angle = {receding:g} deg must not exceed "
                             f"advancing_angle = {advancing:g} deg (either one unset is "
                             f"contact_angle = {self.contact_angle:g} deg)")
        return self

    @property
    def wall_angles(self) -> tuple[float, float]:
        """(advancing, receding) contact angles [deg], an unset one the static
        ``contact_angle``."""
        c = self.contact_angle
        return (c if self.advancing_angle is None else self.advancing_angle,
                c if self.receding_angle is None else self.receding_angle)


@dataclass(frozen=True)
class DomainBox:
    """The meshed domain around the contact in metres: the one record of its rectangle, which
    the mesh (:class:`ehlfoam.mesh.MeshParams`), the flow-pattern metrics
    (:class:`ehlfoam.metrics.raster.Geometry`) and a written case
    (:attr:`ehlfoam.case.geometry.CaseGeometry.box`) extend or give.

    ``x_min <= x <= x_max`` (x the rolling direction, the inlet at x_min) and ``0 <= y <=
    y_max`` (``symmetric``: a half domain with a symmetry plane at y = 0) or ``|y| <= y_max``,
    minus the island, the hole of radius ``island_radius`` [m] at the origin, which must lie
    strictly inside. :meth:`Domain.box` makes it from the spec's domain (units of a)."""

    x_min: float
    x_max: float
    y_max: float
    island_radius: float
    symmetric: bool = True

    def __post_init__(self) -> None:
        for name in ("x_min", "x_max", "y_max", "island_radius"):
            value = getattr(self, name)
            if (isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating))
                    or not math.isfinite(value)):
                raise ValueError(f"{name} must be a finite number in metres, got {value!r}")
        r = float(self.island_radius)
        if r <= 0:
            raise ValueError(f"island_radius must be > 0 m, got {self.island_radius!r}")
        for name, ok in (("x_min", self.x_min < -r), ("x_max", self.x_max > r),
                         ("y_max", self.y_max > r)):
            if not ok:
                bound = "< -island_radius" if name == "x_min" else "> island_radius"
                raise ValueError(f"{name} must be {bound} = {r:.6g} m (the island must lie "
                                 f"inside the rectangle), got {name} = {getattr(self, name)!r}")
        if not isinstance(self.symmetric, (bool, np.bool_)):
            raise ValueError(f"symmetric must be True or False, got {self.symmetric!r}")

    @property
    def y_min(self) -> float:
        """Lower y bound of the domain [m]: 0 (half domain) or -y_max."""
        return 0.0 if self.symmetric else -float(self.y_max)

    @property
    def area(self) -> float:
        """Area of the domain [m^2]: the rectangle minus the (half) island."""
        hole = math.pi * self.island_radius**2 * (0.5 if self.symmetric else 1.0)
        return (self.x_max - self.x_min) * (self.y_max - self.y_min) - hole

    def fields(self) -> dict[str, float | bool]:
        """Its fields by name, to build a record that extends it."""
        return {"x_min": self.x_min, "x_max": self.x_max, "y_max": self.y_max,
                "island_radius": self.island_radius, "symmetric": self.symmetric}


class Domain(BaseModel):
    """Extents of the meshed domain around the contact centre."""

    model_config = STRICT
    upstream: float = Field(
        12.0, gt=1.0, le=200.0,
        description="Distance from the contact centre to the inlet boundary (x = -upstream); "
                    "far enough that the inlet meniscus of ample oil, 6-6.6 a ahead of the "
                    "contact, stays clear of it.",
        json_schema_extra={"unit": "a"})
    downstream: float = Field(
        14.0, gt=1.0, le=200.0,
        description="Distance from the contact centre to the outlet boundary "
                    "(x = downstream).",
        json_schema_extra={"unit": "a"})
    side: float = Field(
        8.0, gt=1.0, le=200.0,
        description="Distance from the contact centre to the side boundary (|y| = side).",
        json_schema_extra={"unit": "a"})
    island_radius: float = Field(
        1.5, gt=1.0, le=10.0,
        description="Radius of the island wall that replaces the Hertzian contact (not "
                    "meshed); above 1 so that its gap is sub-micron but not nanometric.",
        json_schema_extra={"unit": "a"})
    symmetry: Literal["half", "full"] = Field(
        "half",
        description='"half": y >= 0, with a symmetry plane at y = 0; "full": the whole '
                    'domain.')

    @model_validator(mode="after")
    def _island_inside(self) -> "Domain":
        limit = min(self.upstream, self.downstream, self.side)
        if self.island_radius >= 0.8 * limit:
            raise ValueError(f"island_radius = {self.island_radius:g} a must stay below 0.8 x "
                             f"the nearest boundary ({0.8 * limit:g} a)")
        return self

    def box(self, a: float) -> DomainBox:
        """This domain in metres, for the Hertzian radius ``a`` [m]."""
        return DomainBox(x_min=-self.upstream * a, x_max=self.downstream * a,
                         y_max=self.side * a, island_radius=self.island_radius * a,
                         symmetric=self.symmetry == "half")


class Run(BaseModel):
    """Time stepping, steady-state detection and limits."""

    model_config = STRICT
    end_time: float | None = Field(
        None, gt=0.0, le=1e3,
        description="Simulated time limit; none: transits_max transit times.",
        json_schema_extra={"unit": "s"})
    transit_length: float = Field(
        10.0, gt=0.0, le=1e3,
        description="The length whose transit time L / u is the steady-state window (about "
                    "the flooded region's size).",
        json_schema_extra={"unit": "a"})
    transits_max: float = Field(
        4.0, gt=0.0, le=1e3,
        description="Time limit in transit times when end_time is not set.")
    steady_tolerance: float = Field(
        0.01, gt=0.0, lt=1.0,
        description="Relative change of the oil volume and of the meniscus positions (in a) "
                    "over one transit below which the run counts as steady.")
    writes_per_transit: int = Field(
        10, ge=2, le=1000,
        description="Field writes per transit time (what the monitor sees); unset, 2 in "
                    "the thin-film scene.")
    wall_limit: float = Field(
        3600.0, gt=0.0, le=1e6,
        description="Wall-clock limit of the run.",
        json_schema_extra={"unit": "s"})
    max_courant: float = Field(
        1.0, gt=0.0, le=10.0,
        description="OpenFOAM's maxCo: the largest Courant number of a time step.")
    max_alpha_courant: float = Field(
        1.0, gt=0.0, le=10.0,
        description="OpenFOAM's maxAlphaCo: the largest Courant number at the interface.")
    capillary_limit: Literal["galusinski-vigneaux", "brackbill", "none"] = Field(
        "galusinski-vigneaux",
        description='The surface-tension time-step limit: "galusinski-vigneaux" (viscous, the '
                    'one that matters at Re << 1), "brackbill" (inertial, strict) or "none".')
    capillary_safety: float = Field(
        2.0, gt=0.0, le=100.0,
        description="Factor on the capillary time-step limit. 2 keeps a resting meniscus's "
                    "currents at some 8 % of u; 0.5 keeps the lateral currents at the films a "
                    "rear meniscus lays below 1 % of u.")
    air_viscosity_factor: float = Field(
        100.0, ge=1.0, le=1000.0,
        description="The solver's air viscosity is this times physics.air_viscosity (not in "
                    "the gas-release scene). The spurious capillary currents in the air, which "
                    "scale as sigma / mu_air, set the time step: 100 (still 12 times less "
                    "viscous than the oil) halves the steps at a cost of a few per cent in the "
                    "flow pattern; 1 is the physical air.")
    pressure_correctors: int = Field(
        3, ge=1, le=10,
        description="PIMPLE's nCorrectors: pressure solutions per time step.")
    alpha_subcycles: int | None = Field(
        None, ge=1, le=20,
        description="MULES sub-cycles of the oil fraction per time step (nAlphaSubCycles); "
                    "none keeps the template's (1 in the interface scenes, 3 in the cavitating "
                    "one). 3 calms a resting meniscus.")
    n_procs: int = Field(
        1, ge=1, le=1024,
        description="MPI ranks (1: serial).")
    start: Literal["spec", "thin-film"] = Field(
        "spec",
        description='What a 3D case starts from: "spec", the supply\'s layers and the '
                    'initial puddle; "thin-film", the thin-film model\'s balance of the same '
                    'point (its medium level, run first: seconds to a minute), which brings the '
                    'case to rest in fewer transits (a thin-film case is that balance: it '
                    'marches from its puddle either way). --start-from overrides it.')
    max_steps: int = Field(
        10_000_000, ge=1, le=10**12,
        description="The most time steps a case may take to its end time: a case whose end "
                    "time over its largest time step (the capillary limit on the smallest "
                    "cell, or the write interval) exceeds it is refused before it is built, "
                    "with the estimate. A bound on the work, not on the result.")
