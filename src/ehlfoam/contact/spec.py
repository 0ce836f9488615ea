"""The validated input of a precalc run (one source of truth, SI units inside).

A spec comes from the command line or a TOML file (``[precalc]`` table or top level) with
the same keys. Every bad value is refused before any work, with one message naming the
parameter, its value and the valid range (:class:`SpecError`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from ehlfoam._io import read_toml
from ehlfoam.errors import SpecError, format_validation_error, range_text, unit_of
from ehlfoam.contact.formulas import Contact
from ehlfoam.contact.lubricant import OIL_TABLES, Lubricant, PressureLaws, lubricant_from_table, table_range

#: Ambient pressure [Pa] (reference, assumed).
P_AMBIENT_PA = 1.013e5
GRID_MIN, GRID_MAX = 65, 8193


class PrecalcSpec(BaseModel):
    """Operating conditions and numerical settings of one EHL precalc (SI units; each field
    states its unit in ``json_schema_extra["unit"]``)."""

    #: unknown keys refused, frozen, NaN and inf refused, strict types (no true or "25" for
    #: a number, no 2.0 for an integer; an integer is a number)
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False, strict=True)

    load: float = Field(20.0, gt=0.0, le=1e5,
                        description="Normal load F pressing the ball on the disc.",
                        json_schema_extra={"unit": "N"})
    speed: float = Field(0.01, gt=0.0, le=100.0,
                         description="Mean rolling speed u; pure rolling: the ball and the disc "
                                     "surfaces both move at u.",
                         json_schema_extra={"unit": "m/s"})
    temperature: float = Field(40.0, ge=-40.0, le=300.0,
                               description="Oil temperature; selects eta0 and alpha of a "
                                           "tabulated oil.",
                               json_schema_extra={"unit": "C"})
    lubricant: str = Field("HVI60",
                           description='A tabulated oil ("HVI60") or "custom", which takes '
                                       'eta0, alpha and rho0.')
    eta0: float | None = Field(None, gt=0.0, le=1e4,
                               description='Ambient viscosity of a custom oil (lubricant = '
                                           '"custom" only).',
                               json_schema_extra={"unit": "Pa s"})
    alpha: float | None = Field(None, ge=0.0, le=1e-7,
                                description='Pressure-viscosity coefficient of a custom oil '
                                            '(lubricant = "custom" only).',
                                json_schema_extra={"unit": "1/Pa"})
    rho0: float | None = Field(None, gt=0.0, le=1e4,
                               description='Density of a custom oil at ambient pressure '
                                           '(lubricant = "custom" only).',
                               json_schema_extra={"unit": "kg/m3"})
    radius: float = Field(9.525e-3, gt=0.0, le=10.0,
                          description="Ball radius R (the disc is flat).",
                          json_schema_extra={"unit": "m"})
    modulus: float = Field(1.11e11, gt=0.0, le=1e13,
                           description="Reduced elastic modulus E' of the ball and the disc.",
                           json_schema_extra={"unit": "Pa"})
    viscosity: Literal["roelands", "barus"] = Field(
        "roelands", description='The pressure-viscosity law: "roelands" or "barus".')
    density: Literal["dowson-higginson", "incompressible"] = Field(
        "dowson-higginson",
        description='The pressure-density law: "dowson-higginson" or "incompressible".')
    cavitation: Literal["complementarity", "twophase"] = Field(
        "complementarity",
        description='"complementarity": the pressure stays >= 0; "twophase": the density '
                    'drops below ambient pressure, with a zero-gradient outlet, on the domain '
                    'x in [-2a, 6a], y in [-2a, 2a].')
    twophase_p_scale: float = Field(
        P_AMBIENT_PA, gt=0.0, le=1e7,
        description="Pressure scale p_s of the two-phase density, rho / rho0 = max(0, 1 + "
                    "p / p_s) for gauge p < 0; the default, the ambient pressure, makes the "
                    "density proportional to the absolute pressure.",
        json_schema_extra={"unit": "Pa"})
    twophase_coupling: Literal["coupled", "one-way"] = Field(
        "coupled",
        description='The two-phase option\'s coupling of the sub-ambient pressures to the '
                    'contact: "coupled": their elastic deformation in the film and their load '
                    'in the load balance, solved together with the contact by an outer '
                    'iteration; "one-way": solved with the contact\'s film held (they are '
                    'left out of both; faster). Used only with cavitation = "twophase".')
    inlet_layer: float | None = Field(
        None, gt=0.0, le=1e-3,
        description="Starved inlet: the oil carried into the contact, both surfaces together, "
                    "as a layer thickness (mass-conserving film content upstream of the "
                    "contact centre); none: fully flooded.",
        json_schema_extra={"unit": "m"})
    inlet_meniscus: float | None = Field(
        None, gt=0.0, le=50.0,
        description="Starved inlet: the inlet meniscus, its distance upstream of the contact's "
                    "leading edge x = -a in units of a (the pressure is zero upstream of it); "
                    "none: fully flooded.",
        json_schema_extra={"unit": "a"})
    grid: int | None = Field(None, description="Grid points along y, 2^k + 1 or 3 * 2^k + 1 "
                                               "(65 to 8193; e.g. 769: the heavily loaded film "
                                               "within 2 % in two thirds of the time of "
                                               "1025); none: chosen from the Moes load "
                                               "parameter.")
    max_cycles: int = Field(100, ge=1, le=1000, description="Most multigrid cycles.")
    tol_residual: float = Field(3e-5, gt=0.0, lt=1.0,
                                description="Convergence tolerance of the Reynolds residual "
                                            "(relative).")
    tol_load: float = Field(3e-5, gt=0.0, lt=1.0,
                            description="Convergence tolerance of the load balance (relative).")

    @field_validator("grid")
    @classmethod
    def _grid_halves(cls, v: int | None) -> int | None:
        """The multigrid halves the grid down to its coarsest level: n - 1 a power of two,
        or three times one."""
        if v is None:
            return v
        m = max(v - 1, 0)
        while m and m % 2 == 0:
            m //= 2
        if not (GRID_MIN <= v <= GRID_MAX) or m not in (1, 3):
            raise ValueError(f"must be 2**k + 1 or 3*2**k + 1 with {GRID_MIN} <= grid <= "
                             f"{GRID_MAX} (e.g. 257, 513, 769, 1025)")
        return v

    @model_validator(mode="before")
    @classmethod
    def _temperature_in_table(cls, data):
        """A tabulated oil's own temperature range, checked before the field's generic one
        (so that --temperature 500 names HVI60's 25 to 60 C)."""
        if not isinstance(data, dict):
            return data
        oil, temp = data.get("lubricant", "HVI60"), data.get("temperature")
        if oil in OIL_TABLES and isinstance(temp, (int, float)) and not isinstance(temp, bool):
            lo, hi = table_range(oil)
            if not lo <= temp <= hi:
                raise SpecError(f"temperature = {temp:g} C is outside the {oil} table: "
                                f"valid range {lo:g} to {hi:g} C")
        return data

    @model_validator(mode="after")
    def _lubricant_known(self) -> "PrecalcSpec":
        if self.lubricant == "custom":
            missing = [k for k in ("eta0", "alpha", "rho0") if getattr(self, k) is None]
            if missing:
                raise SpecError(f"lubricant = 'custom' needs {', '.join(missing)} "
                                "(eta0 > 0 Pa s, alpha >= 0 1/Pa, rho0 > 0 kg/m3)")
            return self
        if self.lubricant not in OIL_TABLES:
            raise SpecError(f"lubricant = {self.lubricant!r} is unknown: valid are "
                            f"{', '.join(sorted(OIL_TABLES))} or 'custom' (with eta0, alpha, rho0)")
        lo, hi = table_range(self.lubricant)
        if not lo <= self.temperature <= hi:
            raise SpecError(f"temperature = {self.temperature:g} C is outside the "
                            f"{self.lubricant} table: valid range {lo:g} to {hi:g} C")
        return self

    @model_validator(mode="before")
    @classmethod
    def _meniscus_outside_contact(cls, data):
        """A meniscus at or inside the contact's leading edge named as such."""
        m = data.get("inlet_meniscus") if isinstance(data, dict) else None
        if isinstance(m, (int, float)) and not isinstance(m, bool) and m <= 0.0:
            raise SpecError(f"inlet_meniscus = {m:g} a puts the meniscus at x = {-1.0 - m:g} a, "
                            "not upstream of the contact's leading edge x = -a: valid range "
                            "0 < inlet_meniscus <= 50 a (distance upstream of x = -a)")
        return data

    @model_validator(mode="after")
    def _one_inlet_supply(self) -> "PrecalcSpec":
        if self.inlet_layer is not None and self.inlet_meniscus is not None:
            raise SpecError(f"inlet_layer = {self.inlet_layer:g} m and inlet_meniscus = "
                            f"{self.inlet_meniscus:g} a are both set: give one of them (or "
                            "neither: fully flooded)")
        if self.cavitation == "twophase" and (self.inlet_layer is not None
                                              or self.inlet_meniscus is not None):
            raise SpecError("a starved inlet (inlet_layer, inlet_meniscus) needs cavitation = "
                            "'complementarity', not 'twophase'")
        return self

    # --- derived quantities (the one place they are computed) ---------------------------
    def oil(self) -> Lubricant:
        if self.lubricant == "custom":
            return Lubricant(eta0=self.eta0, alpha=self.alpha, rho0=self.rho0, name="custom")
        return lubricant_from_table(self.lubricant, self.temperature)

    def contact(self) -> Contact:
        oil = self.oil()
        return Contact(load=self.load, radius=self.radius, modulus=self.modulus,
                       speed=self.speed, eta0=oil.eta0, alpha=oil.alpha)

    def laws(self) -> PressureLaws:
        return PressureLaws(p_hertz=self.contact().p_hertz, lubricant=self.oil(),
                            viscosity=self.viscosity, density=self.density,
                            twophase_p_scale=self.twophase_p_scale
                            if self.cavitation == "twophase" else None)


def valid_range(name: str) -> str:
    """The valid range of a numeric spec field, from its constraints and unit (e.g.
    'valid range 0 < load <= 1e+05 N')."""
    field = PrecalcSpec.model_fields.get(name)
    if field is None:
        return ""
    return range_text(name, field, unit_of(field))


def make_spec(**values) -> PrecalcSpec:
    """Build a validated spec, raising :class:`SpecError` with a one-line message."""
    values = {k: v for k, v in values.items() if v is not None}
    try:
        return PrecalcSpec(**values)
    except ValidationError as err:
        raise SpecError("invalid input: "
                        + format_validation_error(err, PrecalcSpec)) from None


def load_spec(path: str | Path, **overrides) -> PrecalcSpec:
    """Read a TOML spec (keys at top level or in a ``[precalc]`` table), then apply overrides."""
    data = read_toml(path)
    data = data.get("precalc", data)
    data.update({k: v for k, v in overrides.items() if v is not None})
    return make_spec(**data)
