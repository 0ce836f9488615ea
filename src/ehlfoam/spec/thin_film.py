"""The thin-film scene's part of the case spec: its grid levels (:data:`THIN_FILM_CELLS`),
its ``[thin_film]`` table (:class:`ThinFilm`) and the keys of the 3D scenes it refuses
(:func:`check_thin_film`).

``scene = "thin-film"`` runs the gap-averaged model (:mod:`ehlfoam.thinfilm`) instead of
OpenFOAM: square cells over the half domain, of the size ``thin_film.cell`` or the level's
(``mesh.resolution``). It takes the contact, the supply (layers or flooded), the oil and
its wetting, the ambient and cavitation pressures, the domain and the run's limits and
steady-state tolerance from the spec's other tables; a key that only a 3D scene reads (its
mesh, interface numerics, air, time-step controls, MPI ranks) is refused when it is set to
anything but its default, so that no setting is silently dropped. The 3D scenes ignore the
``[thin_film]`` table. Lengths in units of the Hertzian radius a.
"""

from __future__ import annotations

import math
from typing import Any, Literal

from pydantic import BaseModel, Field, field_validator, model_validator

from ehlfoam.errors import SpecError
from ehlfoam.spec.sections import STRICT

#: A case spec (:class:`ehlfoam.spec.case.CaseSpec`, which holds this module's table: it is
#: not imported here)
CaseSpec = Any

__all__ = ["THIN_FILM_CELLS", "THIN_FILM_MAX_CELLS", "THIN_FILM_WRITES_PER_TRANSIT", "THREE_D_ONLY", "ThinFilm",
           "check_thin_film", "thin_film_cell", "thin_film_cells", "thin_film_cpu_s"]

#: The thin-film grid's square cells per mesh level [a]. On the nominal thin-film case
#: (docs/models/thin-film.md#grid-levels) medium is within 1 % of fine in the inlet meniscus
#: and the width and 7 % short in the bubble, in 45 s of one core; coarse within 5 % in the
#: width and 10 % in the bubble, in 10 s; fine some 6 minutes from a puddle.
THIN_FILM_CELLS: dict[str, float] = {"coarse": 0.4, "medium": 0.2, "fine": 0.1}

#: The most cells a thin-film grid may have (a 0.02 a grid over the default domain has
#: 520,000): a step solves the pressure on all of them.
THIN_FILM_MAX_CELLS = 1_000_000
#: run.writes_per_transit in the thin-film scene unless set: its flow-pattern reading (a
#: raster and the topology code, some 20 ms) costs more than ten steps of its march, and two
#: looks a transit give the same rest within 1 % (a 1 um map point: 5.5 s -> 2.3 s).
THIN_FILM_WRITES_PER_TRANSIT = 2

#: The keys only the 3D scenes read, by table, with why the thin-film scene has no use for
#: them; set to anything but their defaults they are refused there.
THREE_D_ONLY: dict[str, tuple[tuple[str, ...], str]] = {
    "supply": (("track_inner_half_width", "initial_bubble"),
               "the model's supply covers the whole track and it seeds no gas"),
    "physics": (("oil_density", "air_density", "air_viscosity", "interface_compression",
                 "isotropic_compression", "interface_schemes", "interface_advection",
                 "wall_slip_length", "oil_bulk_modulus", "gas_release_rate",
                 "gas_dissolution_rate", "receding_angle"),
                "the gap-averaged model has no inertia, no air flow, no interface numerics, "
                "no gas-release kinetics and no receding contact line (its rear menisci lay "
                "Landau-Levich films)"),
    "mesh": (("n_layers", "size_rim", "size_far", "wall_grading", "wall_cell",
              "polar_radius", "columns", "refine", "follow"),
             "the model's grid is square cells of thin_film.cell or the level's"),
    "run": (("max_courant", "max_alpha_courant", "capillary_limit",
             "capillary_safety", "air_viscosity_factor", "pressure_correctors",
             "alpha_subcycles", "n_procs"),
            "OpenFOAM's time-step and solver controls; the model steps at "
            "thin_film.courant and runs on one core"),
}


class ThinFilm(BaseModel):
    """The gap-averaged model of ``scene = "thin-film"`` (docs/models/thin-film.md): its
    grid and closures. The 3D scenes ignore this table."""

    model_config = STRICT
    cell: float | None = Field(
        None, ge=0.01, le=10.0,
        description="Size of the model's square cells; none: the level's "
                    "(THIN_FILM_CELLS[mesh.resolution]: coarse 0.4, medium 0.2, fine 0.1 a). "
                    "At most half the domain's side and an eighth of its length.",
        json_schema_extra={"unit": "a"})
    film_factor: float = Field(
        1.0, gt=0.0, le=10.0,
        description="Multiplies Landau-Levich's films that a receding meniscus lays on both "
                    "walls (1: the model).")
    receding_meniscus: Literal["static", "bretherton"] | float = Field(
        "static",
        description='The pressure of a meniscus the walls leave (the region\'s rear): '
                    '"static", Young-Laplace\'s like every other; "bretherton", that of a '
                    'meniscus laying films (Park and Homsy, 1 + 3.8 Ca^(2/3)); or a factor in '
                    '[0.5, 2] on the static one.')
    normal_length: float | None = Field(
        0.3, gt=0.0, le=20.0,
        description="Length over which the flooded region is smoothed for the menisci's "
                    "normal (0.3-0.6 a give the same region); none: 1.5 cells. At least half "
                    "a cell.",
        json_schema_extra={"unit": "a"})
    courant: float = Field(
        0.25, gt=0.0, le=1.0,
        description="The time step over a cell's transit at u (the balance converges from "
                    "a quarter down).")
    steady_window: int = Field(
        5, ge=1, le=100,
        description="Transits over which the run must hold still to count as steady: the "
                    "mean outflow within run.steady_tolerance of the supply, and the oil and "
                    "the menisci as run.steady_tolerance says. The region fills slowly, over "
                    "tens of transits, which one transit's reading takes for a balance.")

    bubble_gas: Literal["release-pressure", "balance"] = Field(
        "release-pressure",
        description='The gas of the bubble behind the contact (a cavity the flooded region '
                    'encloses): "release-pressure", at physics.cavitation_pressure whatever '
                    'its amount; "balance", the air it holds at its volume and the oil\'s '
                    'temperature (ideal gas), released from the oil saturated at '
                    'physics.ambient_pressure (Henry\'s law, physics.air_solubility) and '
                    'dissolved back at the rates of diffusion across its menisci and films, '
                    'lost to the outer air where it reaches it; its menisci at '
                    'Young-Laplace\'s pressure below it. physics.cavitation_pressure is then '
                    'the release pressure: a new cavity opens below it, and no gas is ever '
                    'below it.')
    gas_diffusivity: float = Field(
        1e-9, gt=0.0, le=1e-6,
        description='With bubble_gas = "balance": the diffusivity of air in the oil at '
                    '40 C and 21.6 mPa s (HVI60), taken to the case\'s temperature T and '
                    'viscosity eta as T / eta^(2/3) (Hiss and Cussler).',
        json_schema_extra={"unit": "m2/s"})

    @model_validator(mode="before")
    @classmethod
    def _moved_keys(cls, data: Any) -> Any:
        if isinstance(data, dict) and "advancing_angle" in data:
            raise ValueError("advancing_angle has moved to physics.advancing_angle (the 3D "
                             "scenes' walls read it too): set physics.advancing_angle")
        return data

    @field_validator("receding_meniscus")
    @classmethod
    def _factor_in_range(cls, value: Any) -> Any:
        if isinstance(value, (int, float)) and not isinstance(value, bool) \
                and not 0.5 <= value <= 2.0:
            raise ValueError('must be "static", "bretherton" or a factor in [0.5, 2] on the '
                             'static pressure')
        return value


def thin_film_cell(spec: CaseSpec) -> float:
    """The thin-film grid's cell size [a]: ``thin_film.cell``, or the level's."""
    cell = spec.thin_film.cell
    return THIN_FILM_CELLS[spec.mesh.resolution] if cell is None else cell


def thin_film_cells(spec: CaseSpec) -> int:
    """The thin-film grid's cells over the half domain (the island's included)."""
    d, cell = spec.domain, thin_film_cell(spec)
    return round((d.upstream + d.downstream) / cell) * round(d.side / cell)


def _default(model: type[BaseModel], name: str) -> Any:
    return model.model_fields[name].default


def _set_3d_keys(spec: CaseSpec) -> list[str]:
    """The 3D-only keys set to other than their defaults, as clauses."""
    out = []
    for table, (names, why) in THREE_D_ONLY.items():
        section = getattr(spec, table)
        for name in names:
            if name not in type(section).model_fields:
                continue
            value, default = getattr(section, name), _default(type(section), name)
            if value != default:
                keep = "leave it unset" if default is None else f"leave it at {default!r}"
                out.append(f"{table}.{name} = {value!r} does not apply to scene = "
                           f"\"thin-film\" ({why}; {keep})")
    return out


def check_thin_film(spec: CaseSpec) -> None:
    """Refuse a thin-film spec (:class:`SpecError`, every problem in one line) whose keys
    only the 3D scenes read are set, or whose values the model cannot take: a submerged
    supply, a full domain, still walls, a contact angle of 90 deg or more, a cavitation
    pressure at or above ambient, a grid too coarse for the domain or over
    :data:`THIN_FILM_MAX_CELLS`, a normal length under half a cell, an advancing angle below
    the static one. Nothing for the other scenes."""
    if spec.scene != "thin-film":
        return
    problems = _set_3d_keys(spec)
    p, tf, d = spec.physics, spec.thin_film, spec.domain
    if spec.supply.mode == "submerged":
        problems.append('supply.mode = "submerged" does not apply to scene = "thin-film" '
                        '(valid: "layers", "flooded" or "rig"; the model has outer air)')
    if d.symmetry != "half":
        problems.append(f'domain.symmetry = "{d.symmetry}" does not apply to scene = '
                        '"thin-film" (the model is marched on the half domain: "half")')
    if not spec.walls_moving:
        problems.append('walls_moving = false does not apply to scene = "thin-film" (the '
                        'model needs the walls rolling: true)')
    if not p.contact_angle < 90.0:
        problems.append(f"physics.contact_angle = {p.contact_angle:g} deg is out of range "
                        "for scene = \"thin-film\": must be in [0, 90) deg (a meniscus that "
                        "holds the oil in the gap)")
    if not p.cavitation_pressure < p.ambient_pressure:
        problems.append(f"physics.cavitation_pressure = {p.cavitation_pressure:g} Pa must be "
                        f"below physics.ambient_pressure = {p.ambient_pressure:g} Pa for scene "
                        "= \"thin-film\" (the oil gives up gas below ambient)")
    if tf.bubble_gas != "balance":
        for table, name in (("physics", "air_solubility"), ("thin_film", "gas_diffusivity")):
            section = getattr(spec, table)
            value, default = getattr(section, name), _default(type(section), name)
            if value != default:
                problems.append(f'{table}.{name} = {value!r} applies only with '
                                f'thin_film.bubble_gas = "balance" (the bubble\'s gas '
                                f'balance; leave it at {default!r})')
    cell = thin_film_cell(spec)
    span = min(d.side / 2, (d.upstream + d.downstream) / 8)
    where = "thin_film.cell" if tf.cell is not None else \
        f"the {spec.mesh.resolution} level's cell (mesh.resolution)"
    nl = tf.normal_length
    if not cell <= span:
        problems.append(f"{where} = {cell:g} a is out of range: must be in [0.01, {span:.3g}] "
                        "a (two cells across the domain's side, eight along its length)")
    elif thin_film_cells(spec) > THIN_FILM_MAX_CELLS:
        problems.append(f"{where} = {cell:g} a gives {thin_film_cells(spec):,} cells over the "
                        f"domain, more than {THIN_FILM_MAX_CELLS:,}: choose a larger cell or a "
                        "smaller domain")
    elif nl is not None and not 0.5 * cell <= nl <= span:
        problems.append(f"thin_film.normal_length = {nl:g} a is out of range: must be none "
                        f"or in [{0.5 * cell:.3g}, {span:.3g}] a (half a cell to the span of "
                        "the grid)")
    if p.advancing_angle is not None and not p.contact_angle <= p.advancing_angle < 90.0:
        problems.append(f"physics.advancing_angle = {p.advancing_angle:g} deg is out of range "
                        f"for scene = \"thin-film\": must be none or in [{p.contact_angle:g}, "
                        "90) deg (the static angle, physics.contact_angle, up to a right "
                        "angle)")
    if problems:
        raise SpecError("invalid case spec: " + "; ".join(problems))


def thin_film_cpu_s(spec: CaseSpec) -> float:
    """A rough CPU cost [s] of a thin-film run to its time limit (for a batch's ordering and
    first ETA): some 1 us per cell and step (a sparse solve a step), at
    1 / thin_film.courant steps per cell's transit at u, over the run's time limit (a
    cycle of passes, supply.mode = "rig": over cycle.passes_max passes)."""
    cell = thin_film_cell(spec)
    steps = (spec.end_time * spec.speed / (cell * spec.a)) / spec.thin_film.courant
    if spec.supply.mode == "rig":   # a cycle: its passes, a K-th of a disc turn each
        r = spec.supply.track_radius
        arcs = max(1, round(r / spec.contact.radius))
        steps = spec.cycle.passes_max * 2 * math.pi * r / (
            arcs * spec.thin_film.courant * cell * spec.a)
    return 1.0 + 1e-6 * thin_film_cells(spec) * steps if math.isfinite(steps) else 1.0

