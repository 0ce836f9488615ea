"""The run's balances: the oil (volumes) and, in a compressible scene, the air (masses)
against the fluxes through the open boundaries; the gas-release scene's gas against the air
its oil could give up."""

from __future__ import annotations

import numpy as np

from ehlfoam.run.fields import Sample

__all__ = ["OIL_FLUX_APPROXIMATE", "OIL_FLUX_EXACT", "dissolved_air_budget", "mass_balance"]


def _balance(amount: list[float], ins: list[float], outs: list[float], t: np.ndarray,
             what: str, unit: str) -> dict:
    """``amount`` change against the time integral of the fluxes through the open boundaries,
    from the first to the last written time (trapezoid over the writes; before the first
    write the fluxes are not known). The error is relative to what came in over that window
    (or to the amount when almost nothing came in)."""
    carried_in = float(np.trapezoid(ins, t))
    carried_out = float(np.trapezoid(outs, t))
    residual = amount[-1] - amount[0] - (carried_in - carried_out)
    by_inflow = carried_in > 0.01 * amount[-1]
    scale = carried_in if by_inflow else amount[-1]
    return {f"{what}_carried_in_{unit}": carried_in, f"{what}_carried_out_{unit}": carried_out,
            f"{what}_mass_balance_residual_{unit}": residual,
            f"{what}_mass_balance_error": abs(residual) / scale if scale > 0 else None,
            f"{what}_mass_balance_reference": f"{what} carried in" if by_inflow else f"{what} amount",
            f"{what}_mass_balance_window_s": [float(t[0]), float(t[-1])]}


#: how the oil fluxes through the boundaries were read (``oil_flux_source`` in metrics.json)
OIL_FLUX_EXACT = "alphaPhi0: the oil flux the solver transported"
OIL_FLUX_APPROXIMATE = (
    "phi x face alpha at the writes (the solver writes no alphaPhi0): approximate. It closes "
    "within 1 % while no interface crosses an open boundary (state I); with an open wake it "
    "misses part of the outflow whatever the write density (6 % of it on a 20 mm/s window "
    "written every step; docs/validation.md#v-mass-balance)")


def mass_balance(history: list[Sample]) -> dict:
    """The oil balance (volumes: the oil is incompressible or nearly so) and, in a compressible
    scene, the air's (masses)."""
    if len(history) < 2:
        return {"oil_carried_in_m3": None, "oil_carried_out_m3": None,
                "oil_mass_balance_error": None}
    t = np.array([s.time for s in history])
    out = _balance([s.oil_volume for s in history], [s.oil_in for s in history],
                   [s.oil_out for s in history], t, "oil", "m3")
    out["oil_flux_source"] = (OIL_FLUX_EXACT if all(s.oil_flux_exact for s in history)
                              else OIL_FLUX_APPROXIMATE)
    if all(s.gas_mass is not None for s in history):
        out |= _balance([s.gas_mass for s in history], [s.gas_in for s in history],
                        [s.gas_out for s in history], t, "gas", "kg")
    return out


def dissolved_air_budget(history: list[Sample], air_solubility: float,
                         window: float) -> dict:
    """The gas-release scene's gas against the air its oil could give up. The scene has no
    budget of dissolved air (nothing in v1912 carries one without compiling), so this checks
    after the fact whether one would have bound it, two ways:

    - ``gas_release_over_dissolved_air``: the gas released between the first and the last
      write (trapezoid over the writes; m3 at the gas's ambient density) over the Bunsen
      coefficient ``air_solubility`` times all the oil that was in the gap at the first
      write or came in since;
    - ``gas_release_over_dissolved_inflow``: over the last ``window`` [s] (a transit), the
      mean release rate over the mean rate at which the supply brings dissolved air in
      (the steady-state budget; in a short run the first measure is diluted by the oil
      already in the gap).

    Above 1 the model made more gas than the oil could hold; below 1 is necessary, not
    sufficient (only the oil that passes the suction can give its air up). Empty for scenes
    that release nothing."""
    rates = [s.pattern.get("gas_release_m3_s") for s in history]
    if len(history) < 2 or any(r is None for r in rates):
        return {}
    t = np.array([s.time for s in history])
    rates, oil_in = np.asarray(rates, dtype=float), np.array([s.oil_in for s in history])
    released = float(np.trapezoid(rates, t))
    dissolved = air_solubility * (history[0].oil_volume + float(np.trapezoid(oil_in, t)))
    last = t >= t[-1] - window * (1.0 + 1e-9)
    inflow = air_solubility * float(oil_in[last].mean())
    rate = float(rates[last].mean())
    return {"gas_released_m3": released, "dissolved_air_m3": dissolved,
            "gas_release_over_dissolved_air": released / dissolved if dissolved > 0 else None,
            "gas_release_over_dissolved_inflow": rate / inflow if inflow > 0 else None}
