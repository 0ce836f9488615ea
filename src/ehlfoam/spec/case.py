"""The case spec: one validated description of an OpenFOAM case around the contact.

A TOML file with the tables below; every key is optional and defaults to the reference
conditions (HVI60, 40 C, 20 N, 8 mm/s, ample oil). SI units throughout (m, s, N, Pa,
kg/m3), except the contact angle in degrees and the domain and in-plane cells in units of
the Hertzian radius a; each field states its own (``json_schema_extra["unit"]``)::

    [contact]            # the EHL precalc's spec (ehlfoam.contact.spec.PrecalcSpec)
    load = 20.0          # N
    speed = 0.008        # m/s, pure rolling

    [supply]             # ehlfoam.spec.sections.Supply
    mode = "layers"      # "flooded" (ample oil), "layers", "submerged" or "rig"
    disc_layer = 2e-6    # m

    [physics]            # ehlfoam.spec.sections.Physics
    [domain]             # ehlfoam.spec.sections.Domain, units of a
    [mesh]               # ehlfoam.spec.mesh.Mesh
    resolution = "medium"   # coarse | medium | fine
    [run]                # ehlfoam.spec.sections.Run

Validation happens once, in :func:`make_case_spec`; errors name the parameter, its value and
its valid range, before anything is written.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Literal, get_origin

from pydantic import BaseModel, Field, ValidationError, model_validator

from ehlfoam._io import read_toml
from ehlfoam.contact.spec import PrecalcSpec
from ehlfoam.errors import SpecError, format_validation_error, models_in
from ehlfoam.spec.cycle import Cycle, check_rig
from ehlfoam.spec.ladder import RUNGS, THIN_FILM_START, expand_rung
from ehlfoam.spec.levels import FOLLOW_POLAR_RADIUS, POLAR_RING_SHARE
from ehlfoam.spec.mesh import Mesh
from ehlfoam.spec.sections import (DEFAULT_CONTACT, STRICT, Domain, Physics, Run, Supply,
                                   deep_copy, merge_tables)
from ehlfoam.spec.stop import Stop, check_stop, stop_end_time
from ehlfoam.spec.thin_film import (THIN_FILM_WRITES_PER_TRANSIT, THREE_D_ONLY, ThinFilm,
                                     check_thin_film)

#: The OpenFOAM application of each scene ("thin-film": none, the gap-averaged model of
#: ehlfoam.thinfilm).
SOLVERS = {"interface": "interFoam", "single-phase": "interFoam",
           "cavitating": "compressibleInterFoam", "gas-release": "interPhaseChangeFoam",
           "thin-film": "thin-film"}
#: The interface scene's application with ``physics.interface_advection = "isoadvector"``
ISOADVECTOR_SOLVER = "interIsoFoam"


class CaseSpec(BaseModel):
    """One OpenFOAM case around the EHL contact: the scene, the contact and a table each for
    the supply, the physics, the domain, the mesh and the run."""

    model_config = STRICT
    name: str = Field("case", description="Label of the case in reports.")
    rung: Literal[RUNGS] | None = Field(  # type: ignore[valid-type]
        None,
        description='The rung of the model ladder (docs/ladder.md): "thin-film-coarse", '
                    '"thin-film-medium", "thin-film-fine" (the gap-averaged model, scene = '
                    '"thin-film"); "coarse", "medium", "fine" (the 3D scene on the default '
                    'mesh levels); "resolved-coarse", "resolved-medium", "resolved-fine" (the '
                    '3D family whose width and inlet meniscus converge: the mesh follows the '
                    'meniscus, 1 um slip, the wall at the Cox-Voinov angle of the rolling '
                    'speed, started from the thin-film balance). Sets mesh.resolution (which '
                    'must agree) and fills the rest under the spec\'s own keys; none: the '
                    'rung of the scene and level.')
    scene: Literal["interface", "single-phase", "cavitating", "gas-release",
                   "thin-film"] = Field(
        "interface",
        description='The flow modelled. "interface": two-phase oil and air with surface '
                    'tension, no cavitation (interFoam); "single-phase": oil everywhere (the '
                    'check against the Reynolds solution); "cavitating": the air a perfect gas '
                    'that expands below ambient pressure, down to the cavitation pressure '
                    '(compressibleInterFoam); "gas-release": oil below the cavitation pressure '
                    'turns into gas at physics.gas_release_rate, and the air has the oil\'s '
                    'kinematic viscosity (interPhaseChangeFoam); "thin-film": the gap-averaged '
                    'model, no OpenFOAM: Reynolds flow inside Young-Laplace menisci, '
                    'Landau-Levich films, and gas at physics.cavitation_pressure where the oil '
                    'would fall below it (the [thin_film] table; seconds to minutes a case; '
                    'keys only the 3D scenes read are refused).')
    contact: PrecalcSpec = Field(
        DEFAULT_CONTACT,
        description="The EHL conditions (load, speed, oil, ball): the precalc's spec.")
    supply: Supply = Field(Supply(), description="Oil reaching the contact.")
    physics: Physics = Field(Physics(), description="Fluid properties, wetting and the "
                                                    "interface numerics.")
    domain: Domain = Field(Domain(), description="Extents of the meshed domain.")
    mesh: Mesh = Field(Mesh(), description="Resolution level, overrides and refinements.")
    run: Run = Field(Run(), description="Time stepping, steady-state detection and limits.")
    walls_moving: bool = Field(True, description="False holds both walls still (the "
                                                 "static-meniscus test).")
    thin_film: ThinFilm = Field(ThinFilm(), description='The gap-averaged model of scene = '
                                                        '"thin-film": its grid and closures '
                                                        '(the 3D scenes ignore it).')
    cycle: Cycle = Field(Cycle(), description='The cycle of passes of supply.mode = "rig": '
                                              'the tracks\' reflow and when the cycle ends '
                                              '(the other supply modes ignore it).')
    stop: Stop = Field(Stop(), description='The walls\' stop: from contact.speed to rest '
                                           'over stop.duration from stop.at (every scene; '
                                           'unset: they roll throughout).')

    @model_validator(mode="before")
    @classmethod
    def _rung_and_defaults(cls, data: Any) -> Any:
        """The rung's settings (:func:`~ehlfoam.spec.ladder.expand_rung`); the thin-film
        scene looks at its oil less often unless told (run.writes_per_transit,
        :data:`~ehlfoam.spec.thin_film.THIN_FILM_WRITES_PER_TRANSIT`)."""
        if isinstance(data, dict):
            data = expand_rung(data)
        if isinstance(data, dict) and data.get("scene") == "thin-film":
            run = data.get("run", {})
            if isinstance(run, dict) and "writes_per_transit" not in run:
                data = {**data, "run": {**run,
                                        "writes_per_transit": THIN_FILM_WRITES_PER_TRANSIT}}
        return data

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
        viscosities the frozen field is right everywhere
        (docs/models/gas-release.md#physics)."""
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
        """The OpenFOAM application of the scene (interIsoFoam for the interface scene with
        ``physics.interface_advection = "isoadvector"``)."""
        if self.physics.interface_advection == "isoadvector":
            return ISOADVECTOR_SOLVER
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
        """Simulated time limit [s]: with a stop, stop.after past rest."""
        return (stop_end_time(self.stop) or self.run.end_time
                or self.run.transits_max * self.transit_time)

    def to_toml_dict(self) -> dict[str, Any]:
        """The spec as plain TOML-able data (None values dropped)."""
        return _drop_none(self.model_dump())


def _drop_none(value):
    if isinstance(value, dict):
        return {k: _drop_none(v) for k, v in value.items() if v is not None}
    return value


def make_case_spec(data: dict[str, Any] | None = None, **overrides: Any) -> CaseSpec:
    """Validate a case spec from nested data; ``overrides`` are dotted keys
    (``{"contact.speed": 0.017}``) applied on top; a table value merges key by key into the
    data's table (``{"mesh": {"n_layers": 4}}`` keeps its other mesh keys); None clears an
    optional key (``{"mesh.polar_radius": None}``: free quads). Types are strict: no bool
    or string for a number. Raises :class:`SpecError`."""
    data = deep_copy(data or {})
    for dotted, value in overrides.items():
        _set_dotted(data, dotted, value)
    try:
        spec = CaseSpec(**data)
    except ValidationError as err:
        raise SpecError(f"invalid case spec: {format_validation_error(err, CaseSpec)}") from None
    except SpecError as err:  # raised by PrecalcSpec's own validators
        raise SpecError(f"invalid case spec: contact: {err}") from None
    _check_supply_fits(spec)
    check_thin_film(spec)
    check_rig(spec)
    check_stop(spec)
    _check_scene_options(spec)
    if spec.run.start == "thin-film" and spec.scene != "thin-film":
        thin_film_counterpart(spec)   # the start must exist: refused now, not after a build
    return spec


def _check_scene_options(spec: CaseSpec) -> None:
    default = Run.model_fields["air_viscosity_factor"].default
    if spec.scene == "gas-release" and spec.run.air_viscosity_factor != default:
        raise SpecError(
            f"invalid case spec: run.air_viscosity_factor = {spec.run.air_viscosity_factor:g} "
            f"does not apply to scene = \"gas-release\", whose air has the oil's kinematic "
            f"viscosity (leave it at {default:g})")
    compression = spec.physics.isotropic_compression
    if spec.scene == "gas-release" and compression > 0:
        raise SpecError(
            f"invalid case spec: physics.isotropic_compression = {compression:g} does not apply "
            f"to scene = \"gas-release\": interPhaseChangeFoam then turns the thin films' oil "
            f"into gas and diverges (docs/models/gas-release.md; valid range: 0)")
    advection = spec.physics.interface_advection
    if advection == "isoadvector" and spec.scene not in ("interface", "thin-film"):
        raise SpecError(
            f'invalid case spec: physics.interface_advection = "isoadvector" needs scene = '
            f'"interface" (here {spec.scene!r}): interIsoFoam has one incompressible oil and '
            f'air, no phase change (valid otherwise: "compression")')
    rate = spec.physics.gas_dissolution_rate
    if rate > 0 and (spec.scene != "gas-release" or spec.supply.mode != "submerged"):
        raise SpecError(
            f"invalid case spec: physics.gas_dissolution_rate = {rate:g} 1/s needs scene = "
            f"\"gas-release\" and supply.mode = \"submerged\" (here {spec.scene!r}, "
            f"{spec.supply.mode!r}): the scene has one gas, and where outer air meets the oil "
            f"it would dissolve the air too (valid range otherwise: 0)")


def thin_film_counterpart(spec: CaseSpec, level: str = THIN_FILM_START["resolution"],
                          transits_max: float = THIN_FILM_START["transits_max"]) -> CaseSpec:
    """The thin-film case of a 3D spec's operating point (``run.start = "thin-film"``): the
    same contact, supply, oil, wetting, pressures, domain and ``[thin_film]`` table on the
    model's ``level``, marched to its balance within ``transits_max`` transits and the
    spec's ``run.wall_limit``; the keys only the 3D scenes read are left out, and on a
    resolved rung the wall's contact angle (the model takes the static one). Raises
    :class:`SpecError` where the model has no counterpart of the spec (a submerged supply,
    a full domain, still walls, two tracks, a contact angle of 90 deg or more)."""
    data = spec.to_toml_dict()
    for table, (names, _) in THREE_D_ONLY.items():
        for name in names:
            if table != "supply":   # a supply the model cannot take is refused below
                data[table].pop(name, None)
    if spec.mesh.follow is not None or str(spec.rung).startswith("resolved-"):
        data["physics"].pop("contact_angle", None)   # the wall's, at the slip's scale: the
        # model's menisci hold the static angle (docs/ladder.md)
    data.pop("stop", None)   # the start is the balance at speed, before any stop
    data.update(scene="thin-film", rung=f"thin-film-{level}", mesh={},
                run={"transits_max": transits_max, "wall_limit": spec.run.wall_limit})
    try:
        return make_case_spec(data)
    except SpecError as err:
        raise SpecError(f'invalid case spec: run.start = "thin-film": the thin-film model has '
                        f'no counterpart of this case ({str(err).removeprefix("invalid case spec: ")})'
                        ) from None


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


def _set_dotted(data: dict[str, Any], dotted: str, value: Any) -> None:
    """Set the override ``dotted`` = ``value`` in ``data``: each key before the last must be
    a table of the case spec (:class:`SpecError` naming the key otherwise: ``contact.speed.x``
    names no key, ``contact.speed`` is a number); a table value merges into the table there."""
    *parents, leaf = dotted.split(".")
    if not leaf or not all(parents):
        raise SpecError(f"invalid case spec: {dotted!r} is not a dotted key (e.g. "
                        f"contact.speed)")
    model: type[BaseModel] = CaseSpec
    node = data
    for i, part in enumerate(parents):
        name = ".".join(parents[:i + 1])
        field = model.model_fields.get(part)
        if field is None:
            raise SpecError(f"invalid case spec: {name}: unknown key (valid here: "
                            f"{', '.join(model.model_fields)}), in {dotted}")
        tables = models_in(field.annotation)
        if len(tables) != 1 or get_origin(field.annotation) in (tuple, list):
            raise SpecError(f"invalid case spec: {dotted}: {name} is a value, not a table "
                            f"(set it as {name}=VALUE)")
        model = tables[0]
        child = node.get(part)
        if child is None:
            child = node[part] = {}
        elif isinstance(child, BaseModel):      # a table given as a model: its values
            child = node[part] = child.model_dump()
        elif not isinstance(child, dict):
            raise SpecError(f"invalid case spec: {dotted}: {name} = {child!r} is not a table")
        node = child
    if isinstance(value, dict) and isinstance(node.get(leaf), dict):
        merge_tables(node[leaf], value)
    else:
        node[leaf] = value


def load_case_spec(path: str | Path, **overrides: Any) -> CaseSpec:
    """Read and validate a TOML case spec; ``overrides`` as in :func:`make_case_spec`."""
    return make_case_spec(read_toml(path), **overrides)
