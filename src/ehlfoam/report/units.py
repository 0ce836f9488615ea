"""Labels and display units of the numbers a report shows.

Everything inside ehlfoam is SI (m, s, Pa, m3); pictures and tables show mm, um, nm, mm/s,
nl, kPa and GPa. Each table below maps a key to ``(label, unit, scale)``: the displayed
value is ``scale * value`` in ``unit`` (``scale`` None: shown as it is, text or a count).
"""

from __future__ import annotations

import math
from typing import Any

Unit = tuple[str, str, float | None]

#: metrics.json keys -> (label, unit, scale). Ratios to the Hertzian radius a are in "a".
METRICS: dict[str, Unit] = {
    "status": ("Run status", "", None),
    "end_reason": ("End reason", "", None),
    "steady": ("Steady state reached", "", None),
    "steady_test": ("Steady-state test that stopped the run", "", None),
    "solver_exit_code": ("Solver exit code", "", None),
    "state": ("Flow pattern state (I closed, II open)", "", None),
    "inlet_meniscus_distance_over_a": ("Inlet meniscus distance from x = -a (y = 0)", "a", 1.0),
    "inlet_meniscus_at_rim": ("Inlet meniscus at the island rim", "", None),
    "inlet_meniscus_shape": ("Inlet meniscus shape", "", None),
    "inlet_meniscus_c2": ("Inlet meniscus curvature c2 (x/a = c0 + c2 (y/a)^2)", "1/a", 1.0),
    "flooded_length_over_a": ("Flooded region length (x)", "a", 1.0),
    "flooded_width_over_a": ("Flooded region width (y)", "a", 1.0),
    "flooded_x_min_over_a": ("Flooded region upstream end x", "a", 1.0),
    "flooded_x_max_over_a": ("Flooded region downstream end x", "a", 1.0),
    "flooded_clearance_over_a": ("Flooded region's distance to the nearest open boundary",
                                 "a", 1.0),
    "flooded_nearest_boundary": ("Open boundary nearest the flooded region", "", None),
    "rear_meniscus_cell_over_a": ("In-plane cell size at the rear meniscus (y = 0)", "a", 1.0),
    "front_contact_line_cells_over_wall_cell": (
        "In-plane cells over wall cells where dry walls run into the region", "", 1.0),
    "wake_gas_length_over_a": ("Gas behind the contact on y = 0, from x = a", "a", 1.0),
    "wake_open": ("Wake open (outer air reaches the contact exit)", "", None),
    "inlet_starved": ("Inlet starved (outer air reaches the contact inlet)", "", None),
    "enclosed_bubbles": ("Enclosed gas regions", "", None),
    "oil_area_fraction": ("Oil area fraction (mid-gap, alpha >= 0.5)", "%", 100.0),
    "mean_alpha": ("Mean mid-gap oil fraction", "", 1.0),
    "oil_smeared_fraction": ("Oil in smeared interface cells (0.02 < alpha < 0.98)", "%", 100.0),
    "bubble_length_over_a": ("Bubble length from x = a", "a", 1.0),
    "bubble_width_over_a": ("Bubble width", "a", 1.0),
    "bubble_volume_m3": ("Bubble volume", "nl", 1e12),
    "bubble_enclosed": ("Bubble enclosed by oil", "", None),
    "min_pressure_Pa": ("Lowest pressure (absolute)", "kPa", 1e-3),
    "oil_volume_m3": ("Oil volume (whole contact)", "nl", 1e12),
    "oil_volume_initial_m3": ("Oil volume at t = 0", "nl", 1e12),
    "oil_inflow_m3_s": ("Oil inflow", "nl/s", 1e12),
    "oil_outflow_m3_s": ("Oil outflow", "nl/s", 1e12),
    "oil_carried_in_m3": ("Oil carried in (first to last write)", "nl", 1e12),
    "oil_carried_out_m3": ("Oil carried out (first to last write)", "nl", 1e12),
    "oil_mass_balance_residual_m3": ("Oil mass balance residual", "nl", 1e12),
    "oil_mass_balance_error": ("Oil mass balance error", "%", 100.0),
    "oil_flux_source": ("Oil fluxes read from", "", None),
    "oil_outflow_by_boundary_m3_s": ("Oil outflow per open boundary", "m3/s", None),
    "oil_outflow_off_outlet_fraction": ("Oil outflow not through the outlet", "%", 100.0),
    "oil_mass_balance_reference": ("Mass balance relative to", "", None),
    "oil_mass_balance_window_s": ("Mass balance window", "ms", 1e3),
    "gas_release_m3_s": ("Gas released (gas-release scene, at the gas's density)", "nl/s", 1e12),
    "gas_dissolution_m3_s": ("Gas dissolved back (gas-release scene, at the gas's density)",
                             "nl/s", 1e12),
    "gas_released_m3": ("Gas released, first to last write", "nl", 1e12),
    "dissolved_air_m3": ("Air the oil holds dissolved (all its oil)", "nl", 1e12),
    "gas_release_over_dissolved_air": ("Gas released / air the oil holds dissolved", "%", 100.0),
    "gas_release_over_dissolved_inflow": ("Gas release / dissolved air the supply brings, "
                                          "last transit", "%", 100.0),
    "warnings": ("Warnings (mesh, open boundaries)", "", None),
    "ball_wall_steps": ("Ball wall steps per cell (median; above 10 a film creeps)", "", 1.0),
    "contact_flow_m3_s": ("Flow through the contact, u hc 2a", "nl/s", 1e12),
    "contact_flow_over_inflow": ("Contact flow / oil inflow", "%", 100.0),
    "simulated_time_s": ("Simulated time", "ms", 1e3),
    "transit_time_s": ("Transit time (transit length / u)", "ms", 1e3),
    "cells": ("Cells", "", None),
    "time_steps": ("Time steps", "", None),
    "last_delta_t_s": ("Last time step", "us", 1e6),
    "max_delta_t_s": ("Largest time step allowed (maxDeltaT)", "us", 1e6),
    "wall_s": ("Wall time", "s", 1.0),
    "wall_s_per_simulated_ms": ("Wall time per simulated ms", "s", 1.0),
    "a_m": ("Hertzian contact radius a", "mm", 1e3),
    "speed_m_s": ("Rolling speed u", "mm/s", 1e3),
    "mesh_gap_mismatch": ("Meshed gap vs precalc gap (largest)", "%", 100.0),
}

#: metrics.json keys not shown in the metrics table (shown elsewhere).
METRICS_HIDDEN = ("log_tail",)

#: precalc/summary.json keys -> (label, unit, scale).
PRECALC: dict[str, Unit] = {
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
}

#: Spec keys (dotted) -> (label, unit, scale); unlisted keys are shown as they are.
SPEC: dict[str, Unit] = {
    "contact.load": ("Load F", "N", 1.0),
    "contact.speed": ("Rolling speed u", "mm/s", 1e3),
    "contact.temperature": ("Temperature", "C", 1.0),
    "contact.radius": ("Ball radius R", "mm", 1e3),
    "contact.modulus": ("Reduced modulus E'", "GPa", 1e-9),
    "contact.eta0": ("Viscosity eta0 (custom oil)", "mPa s", 1e3),
    "contact.alpha": ("Pressure-viscosity alpha (custom oil)", "1/GPa", 1e9),
    "contact.rho0": ("Density rho0 (custom oil)", "kg/m3", 1.0),
    "contact.twophase_p_scale": ("Two-phase pressure scale", "kPa", 1e-3),
    "supply.disc_layer": ("Oil layer on the disc", "um", 1e6),
    "supply.ball_layer": ("Oil layer on the ball", "um", 1e6),
    "supply.track_half_width": ("Track half-width", "mm", 1e3),
    "supply.initial_puddle": ("Initial puddle radius", "a", 1.0),
    "physics.surface_tension": ("Surface tension", "mN/m", 1e3),
    "physics.contact_angle": ("Contact angle", "deg", 1.0),
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
    "mesh.size_rim": ("Cell size at the island rim", "a", 1.0),
    "mesh.size_far": ("Cell size far away", "a", 1.0),
    "run.end_time": ("End time", "ms", 1e3),
    "run.transit_length": ("Transit length", "a", 1.0),
    "run.wall_limit": ("Wall-clock limit", "s", 1.0),
}


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
    _, _, scale = unit
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
