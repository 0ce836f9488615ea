"""results.csv: one row per planned case, rebuilt atomically (temporary file + rename) from the
cases' metrics.json files, so that a kill can neither duplicate nor lose rows."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Any

from ehlfoam._io import atomic_write_text
from ehlfoam.metrics.record import MetricsRecord

from ehlfoam.batch.folder import CASES, RESULTS, case_status, metrics_or_none
from ehlfoam.batch.plan import PARAM_KEYS, PlannedCase

LOG = "log.interFoam"

#: results.csv: these columns first (the case's parameters: the case spec's dotted keys in
#: SI), then any other swept key, then every other scalar of the metrics record, by its key.
FIXED_COLUMNS = ("case_id", *PARAM_KEYS, "ramp", "ramp_step", "ramp_direction", "confirms",
                 "status",
                 "end_reason", "reason", "state", "wall_s", "cells", "case_dir", "log")


def _scalar(value: Any) -> bool:
    return value is None or isinstance(value, (str, int, float, bool))


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else ""
    return str(value)


def solver_log(case: Path) -> str:
    """The name of the case's solver log (log.interFoam, log.compressibleInterFoam)."""
    try:
        from ehlfoam.case.geometry import load_geometry

        return load_geometry(case).log_name
    except Exception:  # noqa: BLE001 - not built (yet), or an older geometry.json
        return LOG


def result_row(batch_dir: Path, pc: PlannedCase, live: bool = False,
               blocked: str = "") -> dict[str, Any]:
    """The results.csv row of a planned case (typed values)."""
    case = batch_dir / CASES / pc.id
    m = metrics_or_none(case) or MetricsRecord()
    status = case_status(case, live)
    ramp = pc.ramp or {}
    reason = m.get("reason", "") if status in ("failed", "interrupted") else ""
    end_reason = m.get("end_reason") if status != "pending" else None
    if status == "interrupted" and m.status == "running":   # its lock is free: killed
        end_reason = "monitor_killed"
        reason = ("the process running it was killed before the run ended (metrics.json "
                  "said running, its run lock was free); rebuilt on the next run")
    if status == "interrupted" and not reason:
        reason = "stopped before the end of its run (rebuilt on the next run)"
    if status == "pending" and blocked:
        reason = blocked
    log = solver_log(case)
    row = {"case_id": pc.id, **pc.params, "ramp": ramp.get("name"),
           "ramp_step": ramp.get("step"), "ramp_direction": ramp.get("direction"),
           "confirms": ramp.get("confirms"), "status": status, "end_reason": end_reason,
           "reason": reason, "state": m.get("state") if status == "finished" else None,
           "wall_s": m.get("wall_s"), "cells": m.get("cells"),
           "case_dir": f"{CASES}/{pc.id}",
           "log": f"{CASES}/{pc.id}/{log}" if (case / log).is_file() else None}
    if status in ("finished", "failed"):
        row.update({k: v for k, v in m.to_json().items()
                    if k not in row and k != "schema_version" and _scalar(v)})
    return row


def results_rows(batch_dir: Path, plan: list[PlannedCase], live: set[str] = frozenset(),
                 blocked: dict[str, str] | None = None) -> list[dict[str, Any]]:
    """One row per planned case, in plan order."""
    blocked = blocked or {}
    return [result_row(batch_dir, pc, pc.id in live, blocked.get(pc.id, "")) for pc in plan]


def write_results(batch_dir: Path, plan: list[PlannedCase], live: set[str] = frozenset(),
                  blocked: dict[str, str] | None = None) -> list[dict[str, Any]]:
    """Rewrite results.csv atomically from the metrics.json files; returns the rows."""
    rows = results_rows(batch_dir, plan, live, blocked)
    columns = list(FIXED_COLUMNS)
    for row in rows:
        columns += [k for k in row if k not in columns]
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({c: _cell(row.get(c)) for c in columns})
    atomic_write_text(batch_dir / RESULTS, buf.getvalue())
    return rows


def read_results(batch_dir: Path) -> list[dict[str, str]]:
    """results.csv as a list of dicts (strings)."""
    with open(Path(batch_dir) / RESULTS, newline="") as fh:
        return list(csv.DictReader(fh))
