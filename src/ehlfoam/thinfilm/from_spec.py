"""A case spec's flooded region in the thin-film limit: the state a 3D case starts from.

The gap-averaged model (:mod:`ehlfoam.thinfilm`) takes a case spec's contact (its EHL
gap), oil, wetting and supply, and marches them from the spec's initial puddle, or from a
state written before (on any grid), for a number of transits or until the outflow balances
the supply. The state it ends in (:mod:`ehlfoam.thinfilm.state`, ``.npz``) starts a 3D case
(``ehlfoam case SPEC --start-from STATE.npz``): the model reaches the region's balance in
minutes on one core, where a 3D run from the puddle takes hours. ``ehlfoam thin-film`` is its
command line.

Lengths of the grid (cell, domain, normal length) are given in units of the Hertzian radius
a, as the case spec's own domain is; everything the model is handed is SI.

The thin-film scene (``scene = "thin-film"``) takes its options from the spec itself
(:func:`scene_options`: the spec's domain, its ``[thin_film]`` table and its level's cell),
and every scene that makes gas (cavitating, gas-release, thin-film) its outlet: gas at
``physics.cavitation_pressure`` where the oil would fall below it
(:mod:`ehlfoam.thinfilm.cavity`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from ehlfoam._io import atomic_write_json
from ehlfoam.spec.case import CaseSpec
from ehlfoam.spec.cycle import rig_layers
from ehlfoam.spec.thin_film import thin_film_cell
from ehlfoam.thinfilm.gas import GasBalance
from ehlfoam.thinfilm.march import solve_thin_film
from ehlfoam.thinfilm.problem import ThinFilmProblem
from ehlfoam.thinfilm.solution import ThinFilmSolution
from ehlfoam.thinfilm.state import save_state

__all__ = ["CAVITATING_SCENES", "RegionOptions", "cavitation_gauge", "gas_balance", "march",
           "problem_from_spec", "scene_options", "write_region"]

#: The scenes whose oil gives up gas below physics.cavitation_pressure: their thin-film
#: problems have the outlet model.
CAVITATING_SCENES = ("cavitating", "gas-release", "thin-film")

#: the oil viscosity [Pa s] and temperature [K] at which thin_film.gas_diffusivity is given
#: (HVI60 at 40 C)
DIFFUSIVITY_REFERENCE = (21.6e-3, 313.15)

#: the files :func:`write_region` writes into its folder
STATE_FILE, SUMMARY_FILE = "state.npz", "summary.json"


@dataclass(frozen=True)
class RegionOptions:
    """How the thin-film model grids and closes a case spec's region.

    Attributes:
        cell: the square cells' size [a].
        domain: (x_min, x_max, y_max) [a]: the half domain y >= 0 around the contact.
        film_factor: multiplies Landau-Levich's films (1: the model).
        receding: the receding meniscus's pressure: "static", "bretherton" or a factor in
            [0.5, 2] on the static one (:class:`~ehlfoam.thinfilm.problem.ThinFilmProblem`).
        advancing_angle: the apparent angle [deg] of menisci advancing onto dry walls; None:
            the static angle.
        normal_length: the smoothing [a] of the region for the menisci's normal (0.3-0.6 a
            give the same region); None: 1.5 cells.
        meniscus_position: "sub-cell" (as far into its open cell as its oil fills it) or
            "cell" (at that cell's centre).
        cavitation: the outlet model: gas at the spec's cavitation pressure where the oil
            would fall below it; None: the spec's scene says (:data:`CAVITATING_SCENES`).
        gas: the cavities' gas as a balance (:func:`gas_balance`) rather than at the
            cavitation pressure (with the outlet model only).
    """

    cell: float = 0.2
    domain: tuple[float, float, float] = (-11.0, 19.0, 11.0)
    film_factor: float = 1.0
    receding: Literal["static", "bretherton"] | float = "static"
    advancing_angle: float | None = None
    normal_length: float | None = 0.3
    meniscus_position: Literal["sub-cell", "cell"] = "sub-cell"
    cavitation: bool | None = None
    gas: bool = False


def scene_options(spec: CaseSpec) -> RegionOptions:
    """The options of ``scene = "thin-film"``: the spec's domain (its half: upstream,
    downstream, side), its ``[thin_film]`` table, and its cell (``thin_film.cell`` or the
    level's)."""
    d, tf = spec.domain, spec.thin_film
    return RegionOptions(cell=thin_film_cell(spec), domain=(-d.upstream, d.downstream, d.side),
                         film_factor=tf.film_factor, receding=tf.receding_meniscus,
                         advancing_angle=spec.physics.advancing_angle,
                         normal_length=tf.normal_length,
                         cavitation=True, gas=tf.bubble_gas == "balance")


def gas_balance(spec: CaseSpec) -> GasBalance:
    """The gas balance's constants of a case spec: physics.air_solubility (Ostwald),
    thin_film.gas_diffusivity taken to the case's temperature T and oil viscosity eta as
    T / eta^(2/3) from :data:`DIFFUSIVITY_REFERENCE`, the ambient pressure (at which the oil
    is saturated) and the cavitation pressure as the release pressure."""
    eta_ref, t_ref = DIFFUSIVITY_REFERENCE
    t = spec.temperature_k
    d = spec.thin_film.gas_diffusivity * (t / t_ref) * (eta_ref / spec.oil_viscosity) ** (2 / 3)
    p = spec.physics
    return GasBalance(solubility=p.air_solubility, diffusivity=d, temperature=t,
                      ambient=p.ambient_pressure, release=p.cavitation_pressure)


def cavitation_gauge(spec: CaseSpec) -> float:
    """The cavitation pressure as the model takes it [Pa]: gauge, against ambient."""
    return spec.physics.cavitation_pressure - spec.physics.ambient_pressure


def problem_from_spec(spec: CaseSpec, gap: Callable[[np.ndarray, np.ndarray], np.ndarray],
                      options: RegionOptions = RegionOptions()) -> ThinFilmProblem:
    """The thin-film problem of a case spec on the gap h(x, y) [m]: its contact's speed, its
    oil, wetting and supply ("layers": both layers on the track; "flooded": the whole inlet
    gap on the track; "rig": the mean layers on the tracks at the start, which a cycle's
    passes replace, :mod:`ehlfoam.run.cycle`), its island and initial puddle, its cavitation pressure (the outlet
    model, as ``options.cavitation`` or the scene says), gridded as ``options`` say.

    Raises ValueError naming the parameter, its value and the valid range: a supply mode the
    model has no counterpart of, or a cell, domain or angle out of the model's range."""
    a = spec.a
    sup = spec.supply
    x_min, x_max, y_max = options.domain
    _check_grid(options, spec.domain.island_radius)
    if sup.mode == "layers":
        supply = sup.disc_layer + sup.ball_layer
    elif sup.mode == "rig":   # the first pass's: the mean layers on the track
        supply = sum(rig_layers(spec))
    elif sup.mode == "flooded":
        supply = float(gap(np.array([x_min * a]), np.array([0.0]))[0])
    else:
        raise ValueError(f"supply.mode = {sup.mode!r}: the thin-film model takes 'layers', "
                         "'flooded' or 'rig'")
    cavitation = options.cavitation
    if cavitation is None:
        cavitation = spec.scene in CAVITATING_SCENES
    p_cav = cavitation_gauge(spec) if cavitation else None
    if p_cav is not None and not p_cav < 0:
        raise ValueError(f"physics.cavitation_pressure = {spec.physics.cavitation_pressure:g} "
                         f"Pa must be below physics.ambient_pressure = "
                         f"{spec.physics.ambient_pressure:g} Pa (the oil gives up gas below "
                         "ambient)")
    return ThinFilmProblem(
        gap=gap, speed=spec.speed, viscosity=spec.oil_viscosity,
        surface_tension=spec.physics.surface_tension, contact_angle=spec.physics.contact_angle,
        supply=supply, track_half_width=sup.track_half_width,
        x_range=(x_min * a, x_max * a), y_max=y_max * a,
        island_radius=spec.domain.island_radius * a, cell=options.cell * a,
        initial_radius=sup.initial_puddle * a, film_factor=options.film_factor,
        receding_meniscus=options.receding,
        normal_length=None if options.normal_length is None else options.normal_length * a,
        advancing_angle=options.advancing_angle, meniscus_position=options.meniscus_position,
        cavitation_pressure=p_cav,
        gas=gas_balance(spec) if options.gas and p_cav is not None else None)


def _check_grid(options: RegionOptions, island: float) -> None:
    """The model's own checks of the grid (:class:`ThinFilmProblem`), said in units of a, the
    units the options are given in."""
    x_min, x_max, y_max = options.domain
    if not (x_min < -island and x_max > island and y_max > island):
        raise ValueError(f"domain = {options.domain!r} a is out of range: must be (x_min, "
                         f"x_max, y_max) with x_min < -{island:g} < {island:g} < x_max and "
                         f"y_max > {island:g} (around the island)")
    span = min(y_max / 2, (x_max - x_min) / 8)
    if not 0 < options.cell <= span:
        raise ValueError(f"cell = {options.cell!r} a is out of range: must be in "
                         f"(0, {span:.3g}] a (two cells across, eight along the domain)")
    nl = options.normal_length
    if nl is not None and not 0.5 * options.cell <= nl <= span:
        raise ValueError(f"normal_length = {nl!r} a is out of range: must be None or in "
                         f"[{0.5 * options.cell:.3g}, {span:.3g}] a (half a cell to the "
                         "span of the cell's check)")


def march(spec: CaseSpec, prob: ThinFilmProblem, *, transits: float = 10.0,
          balance: bool = False, tolerance: float = 0.01, window: int = 5,
          courant: float = 0.25, start: ThinFilmSolution | None = None,
          progress: Callable[[dict], None] | None = None) -> ThinFilmSolution:
    """March a case spec's problem (:func:`problem_from_spec`) for ``transits`` transits of
    the spec (``run.transit_length`` a at u), or, with ``balance``, until the mean outflow
    over ``window`` transits is within ``tolerance`` of the supply and the oil changed by
    less than ``tolerance`` of itself (``transits`` then caps it). ``start``: a state (any
    grid) whose oil replaces the spec's puddle; ``courant``: the step over a cell's transit
    at u; ``progress`` is called with each transit's record."""
    return solve_thin_film(prob, transits_max=transits,
                           tolerance=tolerance if balance else 0.0,
                           transit_length=spec.run.transit_length * spec.a, start=start,
                           courant=courant, window=window, progress=progress)


def write_region(sol: ThinFilmSolution, spec: CaseSpec, folder: str | Path,
                 record: dict[str, Any] | None = None) -> dict[str, Any]:
    """Write ``folder/state.npz`` (the state, :func:`~ehlfoam.thinfilm.state.save_state`) and
    ``folder/summary.json``: the region's metrics (units of a; oil in m3), the transits
    marched, whether it balanced, each transit's record and ``record`` (how it was made).
    Both atomically. Returns the summary."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    save_state(sol, folder / STATE_FILE)
    summary = {**(record or {}), "a_m": spec.a, "transit_s": spec.transit_time,
               "transits": sol.time / spec.transit_time, "metrics": sol.metrics(spec.a),
               "history": sol.history}
    atomic_write_json(folder / SUMMARY_FILE, summary)
    return summary

