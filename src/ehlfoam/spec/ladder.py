"""The model ladder: one key, ``rung``, picks how an operating point is modelled.

From the cheapest to the dearest (docs/ladder.md):

- ``thin-film-coarse`` / ``thin-film-medium`` / ``thin-film-fine``: the gap-averaged model
  (``scene = "thin-film"``, whatever ``scene`` says: the 3D rungs run that one) on its grid
  levels (0.4 / 0.2 / 0.1 a cells), seconds to minutes a case on one core;
- ``coarse`` / ``medium`` / ``fine``: the spec's 3D scene (OpenFOAM) on the default mesh
  levels, minutes to hours;
- ``resolved-coarse`` / ``resolved-medium`` / ``resolved-fine``: the 3D family whose flooded
  width and inlet meniscus converge (``examples/cases/nominal_resolved.toml`` generalised to
  any operating point): bands of cells along the meniscus of the state it starts from
  (``mesh.follow``), 1 um of Navier slip with the wall at the Cox-Voinov angle of the rolling
  speed, the balanced interface schemes and the isotropic compression (not in the gas-release
  scene: :data:`RESOLVED_SCENE`), started from the thin-film balance of the same point
  (``run.start = "thin-film"``); an hour to hours a transit.

The rung fills what it needs under the spec's own keys (a key the spec sets wins, except the
two that name the rung: ``scene`` for the thin-film rungs and ``mesh.resolution``, which
must agree with it). A spec without ``rung`` is given the one its scene and level are, so
that every validated spec names its rung. Lengths in units of the Hertzian radius a.
"""

from __future__ import annotations

import math
from typing import Any

from ehlfoam.spec.sections import DEFAULT_CONTACT, deep_copy, merge_tables

__all__ = ["LEVELS", "RESOLVED_FAMILY", "RESOLVED_SCENE", "RESOLVED_SLIP_RATIO", "RUNGS",
           "THIN_FILM_START", "cox_voinov", "expand_rung", "rung_family", "rung_level", "rung_of"]

#: The mesh levels of every family
LEVELS = ("coarse", "medium", "fine")
#: Every rung, cheapest family first
RUNGS: tuple[str, ...] = (tuple(f"thin-film-{lv}" for lv in LEVELS) + LEVELS
                          + tuple(f"resolved-{lv}" for lv in LEVELS))

#: What the resolved rungs set under the spec's own keys (as nominal_resolved.toml, whose
#: width and inlet converge over the three levels: docs/models/interface.md). The side band
#: starts at the track's edge (``y_min``, filled from supply.track_half_width) and the wall's
#: angle is the Cox-Voinov angle at the rolling speed (:func:`resolved_wall_angle`).
RESOLVED_FAMILY: dict[str, dict[str, Any]] = {
    "physics": {"interface_schemes": "balanced", "isotropic_compression": 1.0,
                "wall_slip_length": 1e-6},
    "domain": {"downstream": 20.0, "side": 10.0},
    "mesh": {"follow": {"half_width": 1.0, "sides": {"x_min": -8.0, "x_max": 8.0}}},
    "run": {"writes_per_transit": 80, "steady_tolerance": 0.002, "start": "thin-film"},
}
#: What the resolved rungs set instead in a scene (under the same rule: a key the spec sets
#: wins). The gas-release scene (interPhaseChangeFoam) takes its interface compression from
#: each face's flux: with the isotropic compression it turns oil into gas in the thin films
#: (18 % of it in 0.003 transit at 40 C, 17 mm/s, 1 um), its oil fraction climbs past 1 and
#: the run diverges, or it crawls at steps of 3e-7 s (8 mm/s, 0.45 um):
#: docs/ladder.md#at-thin-layer-state-i-points
RESOLVED_SCENE: dict[str, dict[str, dict[str, Any]]] = {
    "gas-release": {"physics": {"isotropic_compression": 0.0}},
}
#: The macroscopic length over the microscopic one in the resolved rungs' Cox-Voinov angle:
#: the 1 um slip the cells resolve over a molecular 1 nm (41 deg at the nominal 8 mm/s,
#: 40 C, from the static 15 deg)
RESOLVED_SLIP_RATIO = 1e3
#: The thin-film balance a 3D case with ``run.start = "thin-film"`` starts from: its grid
#: level (within 1 % of the fine one in the inlet meniscus and the width at the nominal
#: point) and the most transits it marches to its balance
THIN_FILM_START: dict[str, Any] = {"resolution": "medium", "transits_max": 150.0}


def cox_voinov(theta_s_deg: float, ca: float, ratio: float) -> float:
    """Cox-Voinov's apparent angle [deg], theta^3 = theta_s^3 + 9 Ca ln(L / lambda), for the
    static angle theta_s [deg], the capillary number Ca of the contact line's speed and the
    ratio L / lambda of the macroscopic length to the slip length."""
    t3 = math.radians(theta_s_deg) ** 3 + 9.0 * ca * math.log(ratio)
    return math.degrees(t3 ** (1 / 3)) if t3 > 0 else 0.0


def rung_family(rung: str) -> str:
    """"thin-film", "3d" or "resolved"."""
    if rung.startswith("thin-film-"):
        return "thin-film"
    return "resolved" if rung.startswith("resolved-") else "3d"


def rung_level(rung: str) -> str:
    """The rung's mesh level: "coarse", "medium" or "fine"."""
    return rung.rsplit("-", 1)[-1]


def rung_of(scene: str, resolution: str) -> str:
    """The rung a spec without ``rung`` is on: its level, on the thin-film rungs in the
    thin-film scene (a mesh that follows the meniscus without the resolved rung's contact-line
    model is a 3D level's)."""
    return f"thin-film-{resolution}" if scene == "thin-film" else resolution


def expand_rung(data: dict[str, Any]) -> dict[str, Any]:
    """The spec data with its rung filled in (a before-validator of the case spec): with
    ``rung`` the scene (thin-film rungs), ``mesh.resolution`` and, on the resolved rungs,
    :data:`RESOLVED_FAMILY` and the wall's angle under the data's own keys; without it, the
    rung its scene and level are. Raises ValueError naming both keys when ``rung``
    and ``mesh.resolution`` (or a 3D rung and the thin-film scene) disagree."""
    mesh = _table(data, "mesh")
    rung = data.get("rung")
    if rung is None:
        scene = _scene(data)
        level = mesh.get("resolution", "medium")
        if scene in _SCENES and level in LEVELS:   # anything else: the fields' own errors
            data = {**data, "rung": rung_of(scene, level)}
        return data
    if rung not in RUNGS:
        return data                                # the field's own error names the rungs
    level, family = rung_level(rung), rung_family(rung)
    given = mesh.get("resolution")
    if given is not None and given != level:
        raise ValueError(f"rung = {rung!r} and mesh.resolution = {given!r} "
                        f"disagree: the rung sets the level ({level!r}); set one of them")
    scene = _scene(data)
    if family != "thin-film" and scene == "thin-film":
        raise ValueError(f"rung = {rung!r} is a 3D rung and scene = "
                        f"\"thin-film\" is not a 3D scene: set scene to \"interface\", "
                        f"\"gas-release\" or \"cavitating\" (or a thin-film rung: "
                        f"{', '.join(r for r in RUNGS if r.startswith('thin-film'))})")
    out = {**data, "mesh": {**mesh, "resolution": level}}
    if family == "thin-film":
        out["scene"] = "thin-film"
    if family == "resolved":
        out = _under(_resolved_family(out), out)
    return out


_SCENES = ("interface", "single-phase", "cavitating", "gas-release", "thin-film")


def _scene(data: dict[str, Any]) -> Any:
    """The data's scene, or the case spec's default (``CaseSpec.scene``: "interface")."""
    return data.get("scene", _SCENES[0])


def _resolved_family(data: dict[str, Any]) -> dict[str, Any]:
    """:data:`RESOLVED_FAMILY` with the side band's edge at the track's and the wall's angle
    at the rolling speed (left out where the contact or the supply is not valid yet: the
    fields' own errors say why)."""
    family = {k: dict(v) for k, v in RESOLVED_FAMILY.items()}
    for table, values in RESOLVED_SCENE.get(_scene(data), {}).items():
        family[table].update(values)
    try:
        from ehlfoam.contact.spec import PrecalcSpec
        from ehlfoam.spec.sections import Physics, Supply

        contact = _table(data, "contact")
        pc = PrecalcSpec(**contact) if contact else DEFAULT_CONTACT
        supply = Supply(**_table(data, "supply"))
        physics = _table(data, "physics")
        factor = physics.get("viscosity_factor", Physics.model_fields["viscosity_factor"].default)
        sigma = physics.get("surface_tension", Physics.model_fields["surface_tension"].default)
        static = Physics.model_fields["contact_angle"].default
        a = pc.contact().a
    except Exception:   # noqa: BLE001 - the spec's validation reports it
        return family
    ca = pc.oil().eta0 * factor * pc.speed / sigma
    family["physics"]["contact_angle"] = round(cox_voinov(static, ca, RESOLVED_SLIP_RATIO), 2)
    sides = dict(family["mesh"]["follow"]["sides"], y_min=round(supply.track_half_width / a, 3))
    family["mesh"] = {"follow": {**family["mesh"]["follow"], "sides": sides}}
    return family


def _table(data: dict[str, Any], name: str) -> dict[str, Any]:
    value = data.get(name)
    if value is None:
        return {}
    return value.model_dump() if hasattr(value, "model_dump") else dict(value)


def _under(defaults: dict[str, Any], data: dict[str, Any]) -> dict[str, Any]:
    """``data`` with ``defaults`` filled in where it has no key (tables key by key)."""
    out = deep_copy(defaults)
    merge_tables(out, {k: v.model_dump() if hasattr(v, "model_dump") else v
                       for k, v in data.items()})
    return out
