"""The record a run ends with: the last write's flow pattern, the oil (and air) balance over
the run, its cost, and the warnings, as a :class:`ehlfoam.metrics.record.MetricsRecord`."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ehlfoam._io import tail_lines
from ehlfoam.case.geometry import CaseGeometry, mesh_warnings
from ehlfoam.notices import to_text
from ehlfoam.metrics.record import MetricsRecord
from ehlfoam.run import fields as case_fields
from ehlfoam.run.balance import dissolved_air_budget, mass_balance
from ehlfoam.run.warnings import (bare_track, bare_track_warnings, boundary_warnings,
                                  front_cell_warnings, front_contact_line_cells,
                                  rear_cell_warnings, rear_meniscus_cell)
from ehlfoam.spec.case import CaseSpec

__all__ = ["RunEnd", "final_record"]

#: lines of the solver log a failed run's record keeps
LOG_TAIL_LINES = 20


@dataclass(frozen=True)
class RunEnd:
    """How the solver's run ended: ``reason`` (steady, end_time, wall_limit, diverged,
    crashed, interrupted), whether it ``failed``, its ``exit_code``, the ``time_steps`` it
    took, its last time step [s], its wall-clock time [s] and the steady-state test that
    stopped it."""

    reason: str
    failed: bool
    exit_code: int | None
    time_steps: int
    last_delta_t: float
    wall_s: float
    steady_test: str | None = None

    @property
    def status(self) -> str:
        if self.failed:
            return "failed"
        return "interrupted" if self.reason == "interrupted" else "finished"


def final_record(case: Path, spec: CaseSpec, geom: CaseGeometry,
                 structure: case_fields.Structure, *, initial_oil: float,
                 history: list[case_fields.Sample], end: RunEnd) -> MetricsRecord:
    """The run's metrics record from its ``history`` of samples (``initial_oil``: the oil
    volume at t = 0 [m3, whole contact]). Writes nothing: it reads the case's last write
    and, for a failed run, its solver log."""
    last = history[-1] if history else None
    pattern = dict(last.pattern) if last else {}
    off_outlet = case_fields.off_outlet_share(last.oil_out_by_boundary) if last else None
    # where oil fills the domain (single-phase scene, submerged supply) it meets every
    # boundary by design and lays no films: these warnings are for a region surrounded by air
    surrounded = geom.open_inflow_oil == 0.0
    rear_cell = rear_meniscus_cell(spec, pattern) if surrounded else None
    front_cells = (front_contact_line_cells(spec, geom, structure, case, pattern)
                   if surrounded and not end.failed else None)
    bare = bare_track(spec, geom, structure, case, pattern) if not end.failed else None
    out = {
        "status": end.status,
        "end_reason": end.reason,
        "steady": end.reason == "steady",
        "solver_exit_code": end.exit_code,
        "simulated_time_s": last.time if last else 0.0,
        "transit_time_s": geom.transit_time,
        **pattern,
        "oil_volume_m3": last.oil_volume if last else initial_oil,
        "oil_volume_initial_m3": initial_oil,
        "oil_inflow_m3_s": last.oil_in if last else None,
        "oil_outflow_m3_s": last.oil_out if last else None,
        "oil_outflow_by_boundary_m3_s": dict(last.oil_out_by_boundary) if last else None,
        "oil_outflow_off_outlet_fraction": off_outlet,
        **mass_balance(history),
        **dissolved_air_budget(history, geom.air_solubility, geom.transit_time),
        "contact_flow_m3_s": geom.contact_flow,
        "contact_flow_over_inflow": (geom.contact_flow / last.oil_in
                                     if last and last.oil_in > 0 else None),
        "cells": geom.cells,
        "time_steps": end.time_steps,
        "last_delta_t_s": end.last_delta_t,
        "max_delta_t_s": geom.max_delta_t,
        "wall_s": end.wall_s,
        "wall_s_per_simulated_ms": (end.wall_s / (1e3 * last.time)
                                    if last and last.time > 0 else None),
        "a_m": geom.a,
        "mesh_gap_mismatch": geom.gap_mismatch,
        "ball_wall_steps": geom.ball_wall_steps,
        "rear_meniscus_cell_over_a": rear_cell,
        "front_contact_line_cells_over_wall_cell": front_cells,
        "supply_track_bare_fraction": bare,
        "warnings": to_text(
            mesh_warnings(geom) + rear_cell_warnings(rear_cell, spec.mesh.follow is not None)
            + front_cell_warnings(front_cells, spec.physics.isotropic_compression)
            + bare_track_warnings(bare)
            + (boundary_warnings(off_outlet, pattern) if surrounded else [])),
    }
    if end.failed:
        out["log_tail"] = tail_lines(case / geom.log_name, LOG_TAIL_LINES)
    out["steady_test"] = end.steady_test
    return MetricsRecord.model_validate(out)
