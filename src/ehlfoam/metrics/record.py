"""The metrics record: what a run measured, the one definition of every key of ``metrics.json``.

:class:`MetricsRecord` names each quantity once, with its type, a description, its SI unit
and how a report shows it (``json_schema_extra = {"unit": ..., "display": {"label",
"unit", "scale"}}``: the shown value is ``scale`` times the SI value, in the display unit;
``scale`` None: shown as it is). The run monitor writes ``metrics.json`` through it, the
batch adds its keys to it, and results.csv, the reports' tables and charts read the names,
labels and units from it. Lengths ``*_over_a`` are ratios to the Hertzian radius a.

``metrics.json`` carries :data:`SCHEMA_VERSION`; a file written before the record existed
(no ``schema_version``) is read with its keys mapped to the current ones
(:data:`LEGACY_KEYS`). Only the keys a run set are written: a key absent from a file (a gas
balance in a scene without gas, ``log_tail`` of a run that did not fail) reads as None.

The published JSON Schema, ``docs/metrics.schema.json``, is written by
``python -m ehlfoam.metrics.record --write``.
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from ehlfoam._io import atomic_write_json, atomic_write_text

__all__ = ["LEGACY_KEYS", "METRICS_FILE", "SCHEMA_VERSION", "Display", "MetricsRecord",
           "display_of", "json_schema", "read_metrics", "write_metrics"]

#: Version of the record's keys; raised when a key is renamed, dropped or changes meaning.
SCHEMA_VERSION = 1
METRICS_FILE = "metrics.json"
#: Keys of files without ``schema_version`` -> the current key (None: dropped). ``speed_m_s``
#: repeated the case spec's ``contact.speed`` (the case's ehlfoam/spec.json, the batch's
#: plan and results.csv hold it).
LEGACY_KEYS: dict[str, str | None] = {"speed_m_s": None}

#: (label, display unit, scale): the shown value is scale * SI value (scale None: as it is).
Display = tuple[str, str, float | None]


def _key(description: str, unit: str = "", label: str = "", shown: str | None = None,
         scale: float | None = 1.0, default: Any = None) -> Any:
    """A record field: its description, SI unit and display (``shown`` defaults to the SI
    unit; text, flags and counts pass ``scale=None``)."""
    display = {"label": label or description, "unit": unit if shown is None else shown,
               "scale": scale}
    return Field(default, description=description,
                 json_schema_extra={"unit": unit, "display": display})


def _text(description: str, label: str = "") -> Any:
    return _key(description, "", label, scale=None)


class MetricsRecord(BaseModel):
    """One case's ``metrics.json``. Every key is optional: a running case's record holds its
    status and cells, a failed build its reason; keys a scene does not measure are absent."""

    model_config = ConfigDict(extra="allow", validate_assignment=False)

    schema_version: int = Field(SCHEMA_VERSION, description="Version of the record's keys",
                                json_schema_extra={"unit": "", "display": {
                                    "label": "Metrics schema version", "unit": "",
                                    "scale": None}})
    # ---------------------------------------------------------------- the run's end
    status: Literal["running", "finished", "failed", "interrupted"] | None = _text(
        "Run status: running, finished (steady or at a limit), failed or interrupted",
        "Run status")
    end_reason: str | None = _text(
        "Why the run ended: steady, end_time, wall_limit, diverged (the solver failed after "
        "its first time step: a floating-point trap, a fatal error), crashed (killed by "
        "another signal after it: a segmentation fault, an out-of-memory kill; or hung, "
        "killed by the monitor), "
        "start_failed (before it: decomposition, a path OpenFOAM refuses, a solver that "
        "cannot start; reason has the log's words), case_removed (the "
        "case folder was removed mid-run), monitor_error, interrupted (Ctrl-C, SIGTERM), "
        "monitor_killed (status interrupted: metrics.json was left running by a killed run, "
        "its run lock free); a batch adds build_error, ramp_start_error, run_error, "
        "worker_lost; a cycle of passes (supply.mode = \"rig\") ends periodic, limit_cycle, "
        "passes_max", "End reason")
    steady: bool | None = _text("A steady-state test stopped the run", "Steady state reached")
    solver_exit_code: int | None = _text("The solver's exit code", "Solver exit code")
    simulated_time_s: float | None = _key("Simulated time at the last write", "s",
                                          "Simulated time", "ms", 1e3)
    transit_time_s: float | None = _key(
        "Transit time: run.transit_length over the rolling speed", "s",
        "Transit time (transit length / u)", "ms", 1e3)
    # ---------------------------------------------------------------- the flow pattern
    state: Literal["I", "II"] | None = _text(
        "Flow pattern: I (no outer air touches the contact's rim, a closed flooded region) "
        "or II (outer air reaches it: an open wake or a starved inlet)",
        "Flow pattern state (I closed, II open)")
    inlet_meniscus_distance_over_a: float | None = _key(
        "Inlet meniscus on y = 0, from x = -a upstream to the alpha = 0.5 crossing into "
        "the outer air; None when oil reaches the inlet edge", "a",
        "Inlet meniscus distance from x = -a (y = 0)")
    inlet_meniscus_at_rim: bool | None = _text(
        "The inlet meniscus is at (or hidden inside) the island rim",
        "Inlet meniscus at the island rim")
    inlet_meniscus_shape: Literal["convex", "concave"] | None = _text(
        "Shape of the inlet meniscus from the fit x/a = c0 + c2 (y/a)^2: convex (c2 > 0) or "
        "concave (c2 < 0, a starved inlet); None when flat or undefined",
        "Inlet meniscus shape")
    inlet_meniscus_c2: float | None = _key(
        "Curvature c2 of the inlet meniscus fit x/a = c0 + c2 (y/a)^2", "1/a",
        "Inlet meniscus curvature c2 (x/a = c0 + c2 (y/a)^2)")
    flooded_length_over_a: float | None = _key(
        "Length along x of the flooded region (the oil connected to the island rim)", "a",
        "Flooded region length (x)")
    flooded_width_over_a: float | None = _key("Width across y of the flooded region", "a",
                                              "Flooded region width (y)")
    flooded_x_min_over_a: float | None = _key("Upstream end x of the flooded region", "a",
                                              "Flooded region upstream end x")
    flooded_x_max_over_a: float | None = _key("Downstream end x of the flooded region", "a",
                                              "Flooded region downstream end x")
    flooded_clearance_over_a: float | None = _key(
        "Distance of the flooded region to the nearest open boundary", "a",
        "Flooded region's distance to the nearest open boundary")
    flooded_nearest_boundary: Literal["outlet", "side", "upstream"] | None = _text(
        "The open boundary nearest the flooded region", "Open boundary nearest the flooded "
        "region")
    wake_gas_length_over_a: float | None = _key(
        "Gas following the island rim downstream on y = 0, from x = a to its end (0 when oil "
        "follows the rim)", "a", "Gas behind the contact on y = 0, from x = a")
    wake_open: bool | None = _text("Outer air touches the island rim downstream (x > 0)",
                                   "Wake open (outer air reaches the contact exit)")
    inlet_starved: bool | None = _text("Outer air touches the island rim upstream (x < 0)",
                                       "Inlet starved (outer air reaches the contact inlet)")
    enclosed_bubbles: int | None = _text("Gas regions not connected to the domain edge",
                                         "Enclosed gas regions")
    bubble_length_over_a: float | None = _key(
        "The cavitation bubble (gas touching the rim downstream) from x = a to its tip", "a",
        "Bubble length from x = a")
    bubble_width_over_a: float | None = _key("Full width of the cavitation bubble", "a",
                                             "Bubble width")
    bubble_enclosed: bool | None = _text("Oil encloses the cavitation bubble",
                                         "Bubble enclosed by oil")
    oil_area_fraction: float | None = _key(
        "Share of the mid-gap area (island excluded) with alpha >= 0.5", "1",
        "Oil area fraction (mid-gap, alpha >= 0.5)", "%", 100.0)
    mean_alpha: float | None = _key("Mean oil fraction at mid-gap (island excluded)", "1",
                                    "Mean mid-gap oil fraction", "")
    bubble_volume_m3: float | None = _key(
        "Gas volume in the gap columns under the bubble (whole contact)", "m3",
        "Bubble volume", "nl", 1e12)
    oil_smeared_fraction: float | None = _key(
        "Share of the oil volume held in cells with 0.02 < alpha < 0.98 (a smeared "
        "interface)", "1", "Oil in smeared interface cells (0.02 < alpha < 0.98)", "%", 100.0)
    min_pressure_Pa: float | None = _key("Lowest absolute pressure in the gap", "Pa",
                                         "Lowest pressure (absolute)", "kPa", 1e-3)
    gas_release_m3_s: float | None = _key(
        "Gas the gas-release scene makes (at the gas's density, whole contact)", "m3/s",
        "Gas released (gas-release scene, at the gas's density)", "nl/s", 1e12)
    gas_dissolution_m3_s: float | None = _key(
        "Gas the gas-release scene dissolves back (whole contact)", "m3/s",
        "Gas dissolved back (gas-release scene, at the gas's density)", "nl/s", 1e12)
    # ---------------------------------------------------------------- oil and its balance
    oil_volume_m3: float | None = _key("Oil volume at the last write (whole contact)", "m3",
                                       "Oil volume (whole contact)", "nl", 1e12)
    oil_volume_initial_m3: float | None = _key("Oil volume at t = 0", "m3",
                                               "Oil volume at t = 0", "nl", 1e12)
    oil_inflow_m3_s: float | None = _key(
        "Oil entering through the open boundaries at the last write", "m3/s", "Oil inflow",
        "nl/s", 1e12)
    oil_outflow_m3_s: float | None = _key(
        "Oil leaving through the open boundaries at the last write", "m3/s", "Oil outflow",
        "nl/s", 1e12)
    oil_outflow_by_boundary_m3_s: dict[str, float] | None = _key(
        "Oil leaving through each open boundary but the supply, at the last write", "m3/s",
        "Oil outflow per open boundary", scale=None)
    oil_outflow_off_outlet_fraction: float | None = _key(
        "Share of the oil outflow that did not leave through the outlet", "1",
        "Oil outflow not through the outlet", "%", 100.0)
    oil_carried_in_m3: float | None = _key(
        "Oil carried in from the first to the last write (trapezoid over the writes)", "m3",
        "Oil carried in (first to last write)", "nl", 1e12)
    oil_carried_out_m3: float | None = _key("Oil carried out from the first to the last write",
                                            "m3", "Oil carried out (first to last write)",
                                            "nl", 1e12)
    oil_mass_balance_residual_m3: float | None = _key(
        "Change of the oil volume minus what the fluxes carried in and out", "m3",
        "Oil mass balance residual", "nl", 1e12)
    oil_mass_balance_error: float | None = _key(
        "The residual relative to the oil carried in (or to the oil volume when almost "
        "nothing came in)", "1", "Oil mass balance error", "%", 100.0)
    oil_mass_balance_reference: str | None = _text(
        "What the oil balance's error is relative to", "Mass balance relative to")
    oil_mass_balance_window_s: list[float] | None = _key(
        "First and last write of the oil balance", "s", "Mass balance window", "ms", 1e3)
    oil_flux_source: str | None = _text("How the oil fluxes through the boundaries were read",
                                        "Oil fluxes read from")
    gas_carried_in_kg: float | None = _key("Air carried in (compressible scenes)", "kg",
                                           "Air carried in (first to last write)", "ug", 1e9)
    gas_carried_out_kg: float | None = _key("Air carried out (compressible scenes)", "kg",
                                            "Air carried out (first to last write)", "ug", 1e9)
    gas_mass_balance_residual_kg: float | None = _key(
        "Change of the air mass minus what the fluxes carried in and out", "kg",
        "Air mass balance residual", "ug", 1e9)
    gas_mass_balance_error: float | None = _key("The air balance's residual, relative", "1",
                                                "Air mass balance error", "%", 100.0)
    gas_mass_balance_reference: str | None = _text(
        "What the air balance's error is relative to", "Air balance relative to")
    gas_mass_balance_window_s: list[float] | None = _key(
        "First and last write of the air balance", "s", "Air balance window", "ms", 1e3)
    gas_released_m3: float | None = _key(
        "Gas released from the first to the last write (gas-release scene)", "m3",
        "Gas released, first to last write", "nl", 1e12)
    dissolved_air_m3: float | None = _key(
        "Air the oil holds dissolved: the Bunsen coefficient times all the oil that was in "
        "the gap or came in", "m3", "Air the oil holds dissolved (all its oil)", "nl", 1e12)
    gas_release_over_dissolved_air: float | None = _key(
        "Gas released over the air the oil holds dissolved (above 1: more gas than the oil "
        "could hold)", "1", "Gas released / air the oil holds dissolved", "%", 100.0)
    gas_release_over_dissolved_inflow: float | None = _key(
        "Mean release rate over the rate at which the supply brings dissolved air in, last "
        "transit", "1", "Gas release / dissolved air the supply brings, last transit", "%",
        100.0)
    contact_flow_m3_s: float | None = _key("Flow through the contact, u hc 2a", "m3/s",
                                           "Flow through the contact, u hc 2a", "nl/s", 1e12)
    contact_flow_over_inflow: float | None = _key("Contact flow over the oil inflow", "1",
                                                  "Contact flow / oil inflow", "%", 100.0)
    # ---------------------------------------------------------------- a cycle of passes
    cycle_end_reason: str | None = _text(
        "How a cycle of passes (supply.mode = \"rig\") ended: periodic (settled), "
        "limit_cycle, passes_max, wall_limit, diverged, interrupted", "Cycle end reason")
    cycle_passes: int | None = _text("Passes (ball revolutions) the cycle made",
                                     "Cycle passes")
    cycle_period_passes: int | None = _text(
        "The settled cycle's period in passes (1: periodic, every pass alike)",
        "Cycle period (passes)")
    cycle_state_II_share: float | None = _key(
        "The share of the cycle's last max(2 K, 8) passes in state II; the cycle's state is "
        "that of most of them (near the transition the state flips from pass to pass)", "1",
        "Passes in state II, settled cycle", "%", 100.0)
    cycle_state_window_passes: int | None = _text(
        "The last passes the cycle's settled state is read over", "Passes the state is read over")
    cycle_pass_time_s: float | None = _key(
        "A pass of the cycle: a K-th of the disc's revolution", "s", "Cycle pass time")
    cycle_arcs: int | None = _text("K: the disc track's arcs, a pass each (round(r / R))",
                                   "Disc track arcs (passes a disc revolution)")
    cycle_inlet_supply_m3_s: float | None = _key(
        "The oil the inlet took in over the last pass, per second (whole contact)", "m3/s",
        "Inlet supply, last pass", "nl/s", 1e12)
    oil_disc_track_m3: float | None = _key("Oil on the disc's track after the last pass",
                                           "m3", "Oil on the disc's track", "nl", 1e12)
    oil_ball_track_m3: float | None = _key("Oil on the ball's track after the last pass",
                                           "m3", "Oil on the ball's track", "nl", 1e12)
    oil_rig_m3: float | None = _key(
        "Oil on the rig after the last pass: the tracks and the contact's domain", "m3",
        "Oil on the rig (tracks and contact)", "nl", 1e12)
    oil_rig_initial_m3: float | None = _key("Oil on the rig at the cycle's start", "m3",
                                            "Oil on the rig at the start", "nl", 1e12)
    oil_rig_balance_error: float | None = _key(
        "The rig's oil now less at the start, over at the start (round-off: nothing is "
        "added or lost)", "1", "Rig oil balance error", "%", 100.0)
    hc_over_hc_flooded: float | None = _key(
        "The contact's central film over the fully flooded one, its inlet meniscus where the "
        "settled cycle's last passes put it (the starved EHL precalc on the contact's grid)",
        "1",
        "Central film / flooded film (hc / hc,ff)", "%", 100.0)
    starved_meniscus_over_a: float | None = _key(
        "The inlet meniscus distance from x = -a the starved film was solved at: the mean "
        "of the cycle's last passes, rounded to 0.05 a (0.25 a beyond 1 a) and held within 0.05-3 a", "a",
        "Inlet meniscus of the starved film")
    # ---------------------------------------------------------------- the run's cost, mesh
    cells: int | None = _text("Cells of the mesh", "Cells")
    time_steps: int | None = _text("Time steps the solver took", "Time steps")
    last_delta_t_s: float | None = _key("The solver's last time step", "s", "Last time step",
                                        "us", 1e6)
    max_delta_t_s: float | None = _key("Largest time step allowed (maxDeltaT)", "s",
                                       "Largest time step allowed (maxDeltaT)", "us", 1e6)
    wall_s: float | None = _key("Wall-clock time of the run", "s", "Wall time")
    wall_s_per_simulated_ms: float | None = _key("Wall-clock time per simulated millisecond",
                                                 "s/ms", "Wall time per simulated ms", "s")
    a_m: float | None = _key("Hertzian contact radius a", "m", "Hertzian contact radius a",
                             "mm", 1e3)
    mesh_gap_mismatch: float | None = _key(
        "Largest relative difference of the meshed gap from the precalc's", "1",
        "Meshed gap vs precalc gap (largest)", "%", 100.0)
    ball_wall_steps: float | None = _key(
        "Median wall-cell heights the ball surface steps across a cell (above 10 a film "
        "creeps)", "1", "Ball wall steps per cell (median; above 10 a film creeps)", "")
    rear_meniscus_cell_over_a: float | None = _key(
        "In-plane cell size where a closed flooded region's rear meniscus crosses y = 0",
        "a", "In-plane cell size at the rear meniscus (y = 0)")
    front_contact_line_cells_over_wall_cell: float | None = _key(
        "Median in-plane cell size over wall cell height along the flooded region's front "
        "where dry walls run into it off the track", "1",
        "In-plane cells over wall cells where dry walls run into the region", "")
    supply_track_bare_fraction: float | None = _key(
        "Share of the supply track's columns upstream of the flooded region holding under a "
        "quarter of the supplied layers' oil (the layers broken into drops)", "1",
        "Supply track bare upstream of the region", "%", 100.0)
    warnings: str | None = _text("Warnings on the mesh and the open boundaries, '; '-joined",
                                 "Warnings (mesh, open boundaries)")
    log_tail: list[str] | None = _text("The solver log's last lines (a failed run)",
                                       "Solver log tail")
    steady_test: Literal["last write", "window mean"] | None = _text(
        "The steady-state test that stopped the run", "Steady-state test that stopped the run")
    # ---------------------------------------------------------------- added by a batch
    case_id: str | None = _text("The case's id in its batch", "Case id")
    reason: str | None = _text("Why the run or the batch case failed or stopped (one line)",
                               "Failure reason")
    build_wall_s: float | None = _key("Wall-clock time of building the case (a batch)", "s",
                                      "Build wall time")
    case_wall_s: float | None = _key("Wall-clock time of building and running the case",
                                     "s", "Case wall time (build and run)")
    ramp_start_method: str | None = _text(
        "How a ramp step took its start: copy (same mesh) or interpolated",
        "Ramp start method")
    ramp_start_time_s: float | None = _key(
        "Time of the state a ramp step started from", "s", "Ramp start: time of the state",
        "ms", 1e3)

    def to_json(self) -> dict[str, Any]:
        """The ``metrics.json`` data: the keys set, in the record's order, with
        ``schema_version``."""
        return {"schema_version": self.schema_version,
                **self.model_dump(exclude_unset=True, exclude={"schema_version"})}

    def get(self, key: str, default: Any = None) -> Any:
        """The value of ``key`` (a field or a key kept from an older file), or ``default``
        when it is not set."""
        value = getattr(self, key, None) if key in type(self).model_fields \
            else (self.model_extra or {}).get(key)
        return default if value is None else value

    def __getitem__(self, key: str) -> Any:
        """``record["oil_volume_m3"]``: a set key's value; KeyError for a key not set."""
        if key not in self.model_fields_set and key not in (self.model_extra or {}):
            raise KeyError(key)
        return getattr(self, key)

    def __contains__(self, key: object) -> bool:
        return key in self.model_fields_set or key in (self.model_extra or {})

    def updated(self, **values: Any) -> "MetricsRecord":
        """A copy with ``values`` set (validated)."""
        return MetricsRecord.model_validate({**self.to_json(), **values})

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> "MetricsRecord":
        """A record from ``metrics.json`` data; a file without ``schema_version`` has its
        keys mapped to the current ones (:data:`LEGACY_KEYS`). Raises ValueError (pydantic's
        ValidationError) naming a key whose value has the wrong type."""
        if "schema_version" not in data:
            data = {LEGACY_KEYS.get(k, k): v for k, v in data.items()
                    if LEGACY_KEYS.get(k, k) is not None}
            data["schema_version"] = SCHEMA_VERSION
        return cls.model_validate(data)


def display_of(key: str) -> Display:
    """(label, display unit, scale) of a record key; an unknown key is shown as it is."""
    field = MetricsRecord.model_fields.get(key)
    extra = field.json_schema_extra if field is not None else None
    if not isinstance(extra, dict):
        return (key, "", None)
    shown = extra["display"]
    return (shown["label"], shown["unit"], shown["scale"])


def _metrics_path(case: str | os.PathLike) -> Path:
    path = Path(case)
    return path if path.suffix == ".json" else path / METRICS_FILE


def read_metrics(case: str | os.PathLike) -> MetricsRecord:
    """The record of a case folder (its ``metrics.json``; a path to a .json file is read
    as it is). Raises FileNotFoundError when there is none, ValueError when it is not
    JSON or not a metrics record."""
    path = _metrics_path(case)
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        raise FileNotFoundError(f"{path}: no such file (has the case run?)") from None
    except json.JSONDecodeError as err:
        raise ValueError(f"{path}: not JSON ({err})") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path}: not a metrics record (a JSON object)")
    return MetricsRecord.from_json(data)


def write_metrics(case: str | os.PathLike, record: MetricsRecord) -> None:
    """Write the record to the case's ``metrics.json`` atomically."""
    atomic_write_json(_metrics_path(case), record.to_json())


def json_schema() -> dict[str, Any]:
    """The record's JSON Schema (as published in docs/metrics.schema.json)."""
    schema = {"$schema": "https://json-schema.org/draft/2020-12/schema",
              "$id": "metrics.schema.json", **MetricsRecord.model_json_schema()}
    schema["title"] = "ehlfoam metrics.json"
    return schema


#: Where ``--write`` puts the schema: docs/ of the source tree.
SCHEMA_PATH = Path(__file__).resolve().parents[3] / "docs" / "metrics.schema.json"


def schema_text() -> str:
    return json.dumps(json_schema(), indent=2) + "\n"


def main(argv: list[str] | None = None) -> int:
    """``python -m ehlfoam.metrics.record [--write [PATH]]``: print the JSON Schema, or
    write it to docs/metrics.schema.json."""
    p = argparse.ArgumentParser(prog="python -m ehlfoam.metrics.record",
                                description="The JSON Schema of metrics.json.")
    p.add_argument("--write", nargs="?", const=str(SCHEMA_PATH), metavar="PATH",
                   help=f"write it to PATH (default {SCHEMA_PATH})")
    args = p.parse_args(argv)
    if args.write:
        atomic_write_text(args.write, schema_text())
        print(args.write)
    else:
        print(schema_text(), end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
