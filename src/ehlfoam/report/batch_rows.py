"""The rows of a batch report: results.csv, the planned cases it does not hold yet and case
folders it does not know, each filled from its case folder (metrics record, spec) where the
CSV lags behind. Keys are results.csv's: the case spec's dotted names in SI and the metrics
record's keys; private keys (``_folder``, ``_eta``, ...) start with an underscore."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

from ehlfoam.batch.plan import PARAM_KEYS
from ehlfoam.metrics.record import read_metrics
from ehlfoam.report import units
from ehlfoam.report.case_data import load_geometry_tolerant
from ehlfoam.report.charts import nan_to_none

__all__ = ["LEGACY_COLUMNS", "read_results"]

#: results.csv and plan.json columns written before the batch took the case spec's names:
#: old column -> (its key now, factor to SI)
LEGACY_COLUMNS = {"speed_mm_s": ("contact.speed", 1e-3),
                  "temperature_C": ("contact.temperature", 1.0),
                  "load_N": ("contact.load", 1.0), "supply": ("supply.mode", None),
                  "disc_layer_um": ("supply.disc_layer", 1e-6),
                  "ball_layer_um": ("supply.ball_layer", 1e-6),
                  "resolution": ("mesh.resolution", None)}
#: results.csv columns that are text
TEXT_COLUMNS = ("case_id", "state", "status", "case_dir", "log", "reason", "end_reason",
                "supply.mode", "mesh.resolution", "ramp", "ramp_direction")


def _number(text: Any) -> Any:
    """float of a CSV cell, None for empty/None/NaN; text stays text."""
    if text is None:
        return None
    if isinstance(text, (int, float)):
        return nan_to_none(float(text))
    text = str(text).strip()
    if text in ("", "None", "none", "null", "nan", "NaN"):
        return None
    if text in ("True", "true", "False", "false"):
        return text in ("True", "true")
    try:
        return nan_to_none(float(text))
    except ValueError:
        return text


def _current(row: dict[str, Any]) -> dict[str, Any]:
    """A row of results.csv cells or plan.json values: numbers parsed, text kept, and old
    column names (:data:`LEGACY_COLUMNS`) renamed, their values rescaled to SI."""
    out = {}
    for key, value in row.items():
        new, factor = LEGACY_COLUMNS.get(key, (key, None))
        if new in TEXT_COLUMNS:
            out[new] = None if value in (None, "") else str(value)
            continue
        value = _number(value)
        out[new] = value * factor if factor is not None and isinstance(value, float) else value
    return out


def read_results(batch: Path) -> list[dict]:
    """results.csv rows (numbers as floats), plus planned cases missing from it (status
    "pending") and case folders missing from both (not the dot-named folders a case is
    built or replaced in before it is renamed into place)."""
    rows: list[dict] = []
    path = batch / "results.csv"
    if path.is_file():
        with open(path, newline="") as fh:
            rows += [_current({k: v for k, v in raw.items() if k})
                     for raw in csv.DictReader(fh)]
    known = {str(r.get("case_id")) for r in rows}
    for item in _read_plan(batch):
        cid = str(item.get("id"))
        if cid in known:
            continue
        row = {"case_id": cid, "status": "pending"}
        row.update(_current(units.flatten(item.get("params") or {})))
        rows.append(row)
        known.add(cid)
    cases = batch / "cases"
    if cases.is_dir():
        for folder in sorted(p for p in cases.iterdir() if p.is_dir()):
            if folder.name not in known and not folder.name.startswith("."):  # staging
                rows.append({"case_id": folder.name, "status": None})
    for row in rows:
        cid = str(row.get("case_id"))
        folder = batch / (row.get("case_dir") or f"cases/{cid}")
        row["_folder"] = folder if folder.is_dir() else None
        if row["_folder"] is not None:
            _fill_from_case(row, folder)
    return rows


def _read_plan(batch: Path) -> list[dict]:
    try:
        data = json.loads((batch / "plan.json").read_text())
    except (OSError, ValueError):
        return []
    if isinstance(data, dict):
        data = data.get("cases") or data.get("plan") or []
    return [d for d in data if isinstance(d, dict)]


def _read_json(path: Path) -> dict:
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def _fill_from_case(row: dict, folder: Path) -> None:
    """Fill what results.csv lacks from the case folder (metrics record, spec)."""
    try:
        metrics = read_metrics(folder).to_json()
    except (OSError, ValueError):
        metrics = {}
    for key, value in metrics.items():
        if row.get(key) is None and not isinstance(value, (list, dict)):
            row[key] = value
    if row.get("status") in (None, "", "pending", "running") and metrics.get("status"):
        row["status"] = metrics["status"]       # results.csv lags behind a live batch
    elif row.get("status") in (None, "") and not metrics:
        row["status"] = "not run"
    spec = units.flatten(_read_json(folder / "ehlfoam" / "spec.json"))
    for key in PARAM_KEYS:
        if row.get(key) is None and spec.get(key) is not None:
            row[key] = spec[key]
    row["_surface_tension"] = spec.get("physics.surface_tension")
    row["_ambient_pressure"] = spec.get("physics.ambient_pressure")
    geom = load_geometry_tolerant(folder, [])
    if geom is not None:
        row["_eta"], row["_rho"], row["_a"] = geom.oil_viscosity, geom.oil_density, geom.a
        row.setdefault("cells", geom.cells)
