"""Labels and display units of the numbers a report shows.

Everything inside ehlfoam is SI (m, s, Pa, m3); pictures and tables show mm, um, nm, mm/s,
nl, kPa and GPa. Each table below maps a key to a :class:`Unit` ``(label, unit, scale)``:
the displayed value is ``scale * value`` in ``unit`` (``scale`` None: shown as it is, text or
a count). The metrics' displays are defined with the metrics record's fields
(:mod:`ehlfoam.metrics.record`); the inputs' (the case spec's dotted keys) here.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

from ehlfoam.metrics.record import MetricsRecord, display_of


class Unit(NamedTuple):
    """How a quantity is shown: ``label``, display ``unit``, ``scale`` (shown value = scale *
    SI value; None: as it is) and the ``symbol`` of a short column or axis label
    ("u" -> "u [mm/s]")."""

    label: str
    unit: str
    scale: float | None
    symbol: str = ""


#: metrics.json keys -> their display, read from the metrics record's fields
#: (:class:`ehlfoam.metrics.record.MetricsRecord`). Ratios to the Hertzian radius a are in "a".
METRICS: dict[str, Unit] = {key: Unit(*display_of(key)) for key in MetricsRecord.model_fields}

#: metrics.json keys not shown in the metrics table (shown elsewhere).
METRICS_HIDDEN = ("log_tail", "schema_version")

#: precalc/summary.json keys -> (label, unit, scale).
PRECALC: dict[str, Unit] = {k: Unit(*v) for k, v in {
    "converged": ("Converged", "", None),
    "a_m": ("Hertzian radius a", "mm", 1e3),
    "p_hertz_Pa": ("Hertzian pressure pH", "GPa", 1e-9),
    "p_max_Pa": ("Largest pressure", "GPa", 1e-9),
    "hc_m": ("Central film hc", "nm", 1e9),
    "hmin_m": ("Minimum film hmin", "nm", 1e9),
    "hc_nvm_m": ("Central film, Nijenbanning-Venner-Moes formula", "nm", 1e9),
    "M": ("Moes M", "", 1.0),
    "L": ("Moes L", "", 1.0),
    "cavity_length_over_a": ("Sub-ambient (cavity) length", "a", 1.0),
    "grid": ("Grid", "", None),
    "residual": ("Residual", "", 1.0),
    "load_error": ("Load balance error", "%", 100.0),
    "wall_s": ("Wall time", "s", 1.0),
}.items()}

#: Spec keys (dotted: the case spec's, the batch's parameters and results.csv's columns) ->
#: (label, unit, scale[, symbol]); unlisted keys are shown as they are. The one table of the
#: inputs' display units: report tables and chart axes take theirs from here.
SPEC: dict[str, Unit] = {k: Unit(*v) for k, v in {
    "contact.load": ("Load F", "N", 1.0, "F"),
    "contact.speed": ("Rolling speed u", "mm/s", 1e3, "u"),
    "contact.temperature": ("Temperature", "C", 1.0, "T"),
    "contact.radius": ("Ball radius R", "mm", 1e3),
    "contact.modulus": ("Reduced modulus E'", "GPa", 1e-9),
    "contact.eta0": ("Viscosity eta0 (custom oil)", "mPa s", 1e3),
    "contact.alpha": ("Pressure-viscosity alpha (custom oil)", "1/GPa", 1e9),
    "contact.rho0": ("Density rho0 (custom oil)", "kg/m3", 1.0),
    "contact.twophase_p_scale": ("Two-phase pressure scale", "kPa", 1e-3),
    "supply.mode": ("Oil supply", "", None, "supply"),
    "supply.disc_layer": ("Oil layer on the disc", "um", 1e6, "disc layer"),
    "supply.ball_layer": ("Oil layer on the ball", "um", 1e6, "ball layer"),
    "supply.track_half_width": ("Track half-width", "mm", 1e3),
    "supply.initial_puddle": ("Initial puddle radius", "a", 1.0),
    "physics.surface_tension": ("Surface tension", "mN/m", 1e3),
    "physics.contact_angle": ("Contact angle", "deg", 1.0),
    "physics.advancing_angle": ("Advancing contact angle", "deg", 1.0),
    "physics.receding_angle": ("Receding contact angle", "deg", 1.0),
    "physics.oil_density": ("Oil density", "kg/m3", 1.0),
    "physics.air_density": ("Air density", "kg/m3", 1.0),
    "physics.air_viscosity": ("Air viscosity", "uPa s", 1e6),
    "physics.ambient_pressure": ("Ambient pressure", "kPa", 1e-3),
    "physics.cavitation_pressure": ("Cavitation pressure", "kPa", 1e-3),
    "physics.oil_bulk_modulus": ("Oil bulk modulus", "GPa", 1e-9),
    "domain.upstream": ("Domain upstream", "a", 1.0),
    "domain.downstream": ("Domain downstream", "a", 1.0),
    "domain.side": ("Domain side", "a", 1.0),
    "domain.island_radius": ("Island radius", "a", 1.0),
    "mesh.resolution": ("Mesh level", "", None, "mesh"),
    "scene": ("Scene", "", None, "scene"),
    "rung": ("Rung of the model ladder", "", None, "rung"),
    "mesh.size_rim": ("Cell size at the island rim", "a", 1.0),
    "mesh.size_far": ("Cell size far away", "a", 1.0),
    "run.end_time": ("End time", "ms", 1e3),
    "run.transit_length": ("Transit length", "a", 1.0),
    "run.wall_limit": ("Wall-clock limit", "s", 1.0),
}.items()}


def shown(key: str) -> Unit:
    """The display of a spec key or a metrics key (a key in neither: as it is)."""
    return SPEC.get(key) or METRICS.get(key) or Unit(key, "", None)


def short_label(key: str) -> str:
    """A column or axis label: "u [mm/s]" (the symbol, else the label, and the unit)."""
    u = shown(key)
    name = u.symbol or u.label
    return f"{name} [{u.unit}]" if u.unit else name


def scaled(key: str, value: Any) -> Any:
    """``value`` (SI) of ``key`` in its display unit (None, text and flags as they are)."""
    scale = shown(key).scale
    if scale is None or value is None or isinstance(value, (bool, str)):
        return value
    return float(value) * scale


def fmt_number(value: Any, digits: int = 4) -> str:
    """A number with ``digits`` significant digits, integers and text as they are."""
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return f"{value:,}"
    if isinstance(value, float):
        if not math.isfinite(value):
            return "-"
        if value != 0 and (abs(value) >= 1e6 or abs(value) < 1e-3):
            return f"{value:.{digits - 1}e}"
        return f"{value:.{digits}g}"
    if isinstance(value, (list, tuple)):
        return ", ".join(fmt_number(v, digits) for v in value)
    return str(value)


def display(value: Any, unit: Unit) -> str:
    """``value`` (SI) converted with ``unit``'s scale and formatted, without the unit."""
    scale = unit[2]
    if scale is None or isinstance(value, (bool, str)) or value is None:
        return fmt_number(value)
    if isinstance(value, (list, tuple)):
        return ", ".join(display(v, unit) for v in value)
    try:
        return fmt_number(float(value) * scale)
    except (TypeError, ValueError):
        return str(value)


def flatten(data: dict, prefix: str = "") -> dict[str, Any]:
    """Nested dicts as ``{"a.b": value}``."""
    out: dict[str, Any] = {}
    for key, value in data.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            out.update(flatten(value, name + "."))
        else:
            out[name] = value
    return out
