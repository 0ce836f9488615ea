"""What a thin-film run records: a :class:`~ehlfoam.run.fields.Sample` of the march at each
write (the flow pattern read by the 3D cases' topology code, :mod:`ehlfoam.metrics.thin_film`;
the oil in the domain and what crossed its open boundaries since the write before), the
steady-state test on them, and the :class:`MetricsRecord` it ends with: the 3D runs' keys,
with the model's exact oil balance. Volumes and fluxes for the whole contact (twice the
half domain marched)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ehlfoam.case.geometry import CaseGeometry, mesh_warnings
from ehlfoam.metrics.record import MetricsRecord
from ehlfoam.metrics.thin_film import thin_film_pattern
from ehlfoam.notices import Notice, to_text
from ehlfoam.run.fields import Sample, off_outlet_share, pattern_geometry
from ehlfoam.run.history import read_history
from ehlfoam.run.steady import steady_test
from ehlfoam.run.warnings import boundary_warnings
from ehlfoam.thinfilm.march import Marcher
from ehlfoam.thinfilm.solution import ThinFilmSolution

__all__ = ["Accounts", "FLUX_SOURCE", "earlier_samples", "sample", "thin_film_record",
           "thin_film_steady"]

#: ``oil_flux_source`` of a thin-film run
FLUX_SOURCE = ("the thin-film model's face fluxes, summed over every step: exact (the "
               "model conserves the oil to round-off)")


@dataclass
class Accounts:
    """What crossed the open boundaries [m3, half domain] up to a time [s] of the run: the
    supply taken in, what left through the outlet and through the side."""

    time: float
    oil_in: float
    outlet: float
    side: float

    @classmethod
    def of(cls, m: Marcher, t0: float) -> "Accounts":
        return cls(t0 + m.time, m.oil_in, m.oil_out_outlet, m.oil_out_side)


def sample(m: Marcher, t0: float, geom: CaseGeometry, before: Accounts,
           sol: ThinFilmSolution | None = None) -> tuple[Sample, Accounts]:
    """The march ``m`` now (``t0`` [s]: the time it started from) as a write of a 3D run:
    its oil [m3, whole contact], the supply, the mean outflow through the outlet and the side
    since ``before``, and the flow pattern (:func:`thin_film_pattern`, with the lowest
    absolute pressure: the flooded cells' and the cavities'). Returns the sample and the
    accounts now."""
    sol = sol or m.solution()
    now = Accounts.of(m, t0)
    span = now.time - before.time
    rate = {k: 2.0 * (getattr(now, k) - getattr(before, k)) / span if span > 0 else 0.0
            for k in ("outlet", "side")}
    pattern, _ = thin_film_pattern(sol, pattern_geometry(geom))
    p = sol.gauge_pressure()
    pattern["min_pressure_Pa"] = (float(np.nanmin(p)) + geom.ambient_pressure
                                  if np.isfinite(p).any() else None)
    return Sample(time=now.time, oil_volume=2.0 * m.oil(), oil_in=2.0 * m.q_in,
                  oil_out=rate["outlet"] + rate["side"], pattern=pattern,
                  oil_flux_exact=True, oil_out_by_boundary=rate), now


def earlier_samples(case: Path) -> list[Sample]:
    """The samples of an earlier run of the case, read back from its history.csv (a run
    that goes on from its state counts them for its steady-state test); none without one."""
    cols = read_history(case / "history.csv")
    if not cols or "time_s" not in cols:
        return []

    def value(key: str, i: int):
        if key not in cols:
            return None
        v = cols[key][i]
        return None if isinstance(v, float) and math.isnan(v) else v

    out = []
    boundaries = [k for k in cols if k.startswith("oil_out_") and k.endswith("_m3_s")
                  and k != "oil_out_m3_s"]
    skip = {"time_s", "oil_volume_m3", "oil_in_m3_s", "oil_out_m3_s", *boundaries}
    for i in range(len(cols["time_s"])):
        by = {k[len("oil_out_"):-len("_m3_s")]: float(cols[k][i]) for k in boundaries}
        pattern = {k: value(k, i) for k in cols if k not in skip}
        out.append(Sample(time=float(cols["time_s"][i]),
                          oil_volume=float(cols["oil_volume_m3"][i]),
                          oil_in=float(cols["oil_in_m3_s"][i]),
                          oil_out=float(cols["oil_out_m3_s"][i]), pattern=pattern,
                          oil_out_by_boundary=by))
    return out


def thin_film_steady(history: list[Sample], window: float, tol: float,
                     length_scale: float) -> str | None:
    """The 3D runs' steady-state test (:func:`ehlfoam.run.steady.steady_test`) over
    ``window`` [s], passed only while the mean outflow over that window is within ``tol`` of
    the supply too: the region fills slowly, and its oil and menisci can hold within the
    tolerance over a window while it does."""
    kind = steady_test(history, window, tol, length_scale)
    if kind is None:
        return None
    now = history[-1].time
    inside = [(a, b) for a, b in zip(history, history[1:]) if b.time > now - window * (1 + 1e-9)]
    span = sum(b.time - a.time for a, b in inside)
    if span < 0.5 * window or history[-1].oil_in <= 0:
        return None
    out = sum(b.oil_out * (b.time - a.time) for a, b in inside) / span
    return kind if abs(out / history[-1].oil_in - 1.0) <= tol else None


def thin_film_record(geom: CaseGeometry, history: list[Sample], *, status: str, reason: str,
                     steady_kind: str | None, start: Accounts, end: Accounts,
                     oil_start: float, oil_end: float, oil_initial: float, steps: int,
                     dt: float, wall_s: float, log_tail: list[str] | None = None,
                     notices: list[Notice] | None = None) -> MetricsRecord:
    """The run's metrics record: its end, the last write's flow pattern and outflow, the
    oil balance from ``start`` to ``end`` (the oil in the domain then, ``oil_start`` and
    ``oil_end`` [m3, half domain]; what the accounts say crossed the boundaries), its cost.
    ``oil_initial``: the oil at t = 0 [m3, whole contact]; ``notices``: warnings of the
    model's final state beside the mesh's and the boundaries'."""
    last = history[-1] if history else None
    pattern = dict(last.pattern) if last else {}
    off_outlet = off_outlet_share(last.oil_out_by_boundary) if last else None
    carried_in, carried_out = end.oil_in - start.oil_in, \
        (end.outlet + end.side) - (start.outlet + start.side)
    residual = oil_end - oil_start - (carried_in - carried_out)
    by_inflow = carried_in > 0.01 * oil_end
    scale = carried_in if by_inflow else oil_end
    simulated = end.time
    out = {
        "status": status, "end_reason": reason, "steady": reason == "steady",
        "simulated_time_s": simulated, "transit_time_s": geom.transit_time, **pattern,
        "oil_volume_m3": 2.0 * oil_end, "oil_volume_initial_m3": oil_initial,
        "oil_inflow_m3_s": last.oil_in if last else None,
        "oil_outflow_m3_s": last.oil_out if last else None,
        "oil_outflow_by_boundary_m3_s": dict(last.oil_out_by_boundary) if last else None,
        "oil_outflow_off_outlet_fraction": off_outlet,
        "oil_carried_in_m3": 2.0 * carried_in, "oil_carried_out_m3": 2.0 * carried_out,
        "oil_mass_balance_residual_m3": 2.0 * residual,
        "oil_mass_balance_error": abs(residual) / scale if scale > 0 else None,
        "oil_mass_balance_reference": "oil carried in" if by_inflow else "oil amount",
        "oil_mass_balance_window_s": [start.time, end.time],
        "oil_flux_source": FLUX_SOURCE,
        "contact_flow_m3_s": geom.contact_flow,
        "contact_flow_over_inflow": (geom.contact_flow / last.oil_in
                                     if last and last.oil_in > 0 else None),
        "cells": geom.cells, "time_steps": steps, "last_delta_t_s": dt, "max_delta_t_s": dt,
        "wall_s": wall_s,
        "wall_s_per_simulated_ms": wall_s / (1e3 * simulated) if simulated > 0 else None,
        "a_m": geom.a,
        "warnings": to_text(mesh_warnings(geom) + boundary_warnings(off_outlet, pattern)
                            + list(notices or [])),
        "steady_test": steady_kind,
    }
    if log_tail:
        out["log_tail"] = log_tail
    return MetricsRecord.model_validate(out)
