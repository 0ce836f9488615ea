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
from ehlfoam.errors import SpecError, format_validation_error, range_text
from ehlfoam.contact.formulas import Contact
from ehlfoam.contact.lubricant import OIL_TABLES, Lubricant, PressureLaws, lubricant_from_table, table_range

#: Ambient pressure [Pa] (reference, assumed).
P_AMBIENT_PA = 1.013e5
GRID_MIN, GRID_MAX = 65, 8193


class PrecalcSpec(BaseModel):
    """Operating conditions and numerical settings of one EHL precalc (SI units).

    Attributes:
        load: normal load F [N].
        speed: mean rolling speed u [m/s] (pure rolling: ball and disc both at u).
        temperature: oil temperature [C] (selects eta0 and alpha of a tabulated oil).
        lubricant: a tabulated oil name ("HVI60") or "custom" with eta0, alpha, rho0.
        eta0: ambient viscosity [Pa s] (custom oil only).
        alpha: pressure-viscosity coefficient [1/Pa] (custom oil only).
        rho0: density [kg/m3] (custom oil only).
        radius: ball radius R [m] (disc flat).
        modulus: reduced modulus E' [Pa].
        viscosity: "roelands" or "barus".
        density: "dowson-higginson" or "incompressible".
        cavitation: "complementarity" (p >= 0) or "twophase" (density drop below ambient,
            zero-gradient outlet, domain x in [-2a, 6a], y in [-2a, 2a]).
        twophase_p_scale: pressure scale p_s [Pa] of the two-phase density,
            rho/rho0 = max(0, 1 + p/p_s) for gauge p < 0 (default p_ambient: density
            proportional to absolute pressure).
        grid: grid points along y (2^k + 1); None chooses from the Moes load parameter.
        max_cycles: multigrid cycle limit.
        tol_residual, tol_load: convergence tolerances (relative).
    """

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    load: float = Field(20.0, gt=0.0, le=1e5)
    speed: float = Field(0.01, gt=0.0, le=100.0)
    temperature: float = Field(40.0, ge=-40.0, le=300.0)
    lubricant: str = "HVI60"
    eta0: float | None = Field(None, gt=0.0, le=1e4)
    alpha: float | None = Field(None, ge=0.0, le=1e-7)
    rho0: float | None = Field(None, gt=0.0, le=1e4)
    radius: float = Field(9.525e-3, gt=0.0, le=10.0)
    modulus: float = Field(1.11e11, gt=0.0, le=1e13)
    viscosity: Literal["roelands", "barus"] = "roelands"
    density: Literal["dowson-higginson", "incompressible"] = "dowson-higginson"
    cavitation: Literal["complementarity", "twophase"] = "complementarity"
    twophase_p_scale: float = Field(P_AMBIENT_PA, gt=0.0, le=1e7)
    grid: int | None = None
    max_cycles: int = Field(100, ge=1, le=1000)
    tol_residual: float = Field(3e-5, gt=0.0, lt=1.0)
    tol_load: float = Field(3e-5, gt=0.0, lt=1.0)

    @field_validator("grid")
    @classmethod
    def _grid_power_of_two(cls, v: int | None) -> int | None:
        if v is None:
            return v
        if not (GRID_MIN <= v <= GRID_MAX) or ((v - 1) & (v - 2)) != 0:
            raise ValueError(
                f"must be 2**k + 1 with {GRID_MIN} <= grid <= {GRID_MAX} (e.g. 257, 513, 1025)")
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


UNITS = {"load": "N", "speed": "m/s", "temperature": "C", "eta0": "Pa s", "alpha": "1/Pa",
         "rho0": "kg/m3", "radius": "m", "modulus": "Pa", "twophase_p_scale": "Pa"}


def valid_range(name: str) -> str:
    """The valid range of a numeric spec field, from its constraints (e.g. '0 < load <= 1e+05 N')."""
    field = PrecalcSpec.model_fields.get(name)
    if field is None:
        return ""
    return range_text(name, field, UNITS.get(name, ""))


def make_spec(**values) -> PrecalcSpec:
    """Build a validated spec, raising :class:`SpecError` with a one-line message."""
    values = {k: v for k, v in values.items() if v is not None}
    try:
        return PrecalcSpec(**values)
    except ValidationError as err:
        raise SpecError("invalid input: "
                        + format_validation_error(err, PrecalcSpec, units=UNITS)) from None


def load_spec(path: str | Path, **overrides) -> PrecalcSpec:
    """Read a TOML spec (keys at top level or in a ``[precalc]`` table), then apply overrides."""
    data = read_toml(path)
    data = data.get("precalc", data)
    data.update({k: v for k, v in overrides.items() if v is not None})
    return make_spec(**data)
