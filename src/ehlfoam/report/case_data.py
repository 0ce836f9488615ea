"""What a case folder holds, read without ever failing: spec, geometry, metrics, history,
the solver log's tail and the precalc summary.

A report must work for a case that finished, failed, was interrupted, is still running or
never ran; whatever is missing or unreadable is recorded in :attr:`CaseInfo.problems` and
the rest is still shown.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ehlfoam._io import tail_lines
from ehlfoam.case.geometry import META, CaseGeometry
from ehlfoam.case.ownership import run_lock_held
from ehlfoam.metrics.record import read_metrics
from ehlfoam.run.history import history_columns, read_history

__all__ = ["CaseInfo", "find_log", "history_columns", "load_case", "load_geometry_tolerant",
           "log_header", "read_history", "tail_lines"]

#: Lines of the solver log shown for a case that did not finish.
LOG_TAIL_LINES = 30
#: A log written to within this many seconds counts as a live run [s].
LIVE_LOG_S = 600.0
#: What the report says of a run that was killed (metrics.json left running, or settled as
#: interrupted with end_reason monitor_killed).
KILLED = ("The run was killed before it ended (monitor_killed: no process held its run "
          "lock); this report shows its last write.")
#: metrics.json status values that mean the run is over and fine.
FINISHED = "finished"


@dataclass
class CaseInfo:
    """Everything about a case except its fields (see :mod:`ehlfoam.report.fields`).

    ``status``: "finished", "failed", "interrupted", "running", "stopped" (a log but no
    result) or "not run". ``history``: history.csv as columns (SI; ``state`` as text), or
    None. ``problems``: human-readable notes on what could not be read.
    """

    path: Path
    name: str
    geom: CaseGeometry | None
    spec: Any                 # ehlfoam.spec.case.CaseSpec or None
    spec_dict: dict
    metrics: dict
    history: dict[str, np.ndarray] | None
    status: str
    status_detail: str
    log_path: Path | None
    log_tail: list[str]
    log_header: dict[str, str]
    precalc: dict | None
    problems: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """The run finished (steady or at its time limit)."""
        return self.status == FINISHED

    @property
    def a(self) -> float | None:
        """Hertzian contact radius [m]."""
        if self.geom is not None:
            return self.geom.a
        value = self.metrics.get("a_m")
        return float(value) if value else None

    @property
    def solver(self) -> str:
        """The OpenFOAM application of the case."""
        return getattr(self.geom, "solver", None) or "interFoam"

    @property
    def scene(self) -> str:
        """"interface", "single-phase" or "cavitating"."""
        return str(self.spec_dict.get("scene", "interface"))


def _read_json(path: Path, problems: list[str]) -> dict | None:
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        return None
    except (OSError, ValueError) as exc:
        problems.append(f"{path.name}: unreadable ({exc})")
        return None


def _read_metrics(case: Path, problems: list[str]) -> dict | None:
    """The case's metrics record as metrics.json data (an older file's keys mapped to the
    current ones), or None."""
    try:
        return read_metrics(case).to_json()
    except FileNotFoundError:
        return None
    except ValueError as exc:
        problems.append(f"metrics.json: unreadable ({' '.join(str(exc).split())[:300]})")
        return None


def load_geometry_tolerant(case: Path, problems: list[str]) -> CaseGeometry | None:
    """The case's :class:`CaseGeometry`; keys unknown to this version are ignored."""
    data = _read_json(case / META / "geometry.json", problems)
    if data is None:
        problems.append("ehlfoam/geometry.json missing: not a generated case?")
        return None
    names = {f.name for f in dataclasses.fields(CaseGeometry)}
    try:
        return CaseGeometry(**{k: v for k, v in data.items() if k in names})
    except TypeError as exc:
        problems.append(f"ehlfoam/geometry.json: {exc}")
        return None


def _load_spec(case: Path, problems: list[str]) -> tuple[Any, dict]:
    raw = _read_json(case / META / "spec.json", problems) or {}
    if not raw:
        return None, {}
    try:
        from ehlfoam.spec.case import CaseSpec

        return CaseSpec.model_validate(raw), raw
    except Exception as exc:  # a spec written by another version: show the raw values
        problems.append(f"ehlfoam/spec.json does not validate here ({type(exc).__name__})")
        return None, raw


def log_header(path: Path) -> dict[str, str]:
    """Build, Exec, Case, nProcs... from the banner at the top of an OpenFOAM log."""
    out: dict[str, str] = {}
    try:
        with open(path, "rb") as fh:
            head = fh.read(4096).decode("utf-8", "replace")
    except OSError:
        return out
    for line in head.splitlines():
        key, sep, value = line.partition(":")
        key = key.strip()
        if sep and key in ("Build", "Exec", "Case", "nProcs", "Date", "Time", "Host"):
            out.setdefault(key, value.strip())
    return out


def find_log(case: Path, geom: CaseGeometry | None) -> Path | None:
    """The solver log: ``log.<solver>`` of the geometry, else any ``log.*Foam``."""
    names = [getattr(geom, "log_name", None) if geom else None, "log.interFoam",
             "log.compressibleInterFoam"]
    for name in names:
        if name and (case / name).is_file():
            return case / name
    logs = sorted(case.glob("log.*Foam"), key=lambda p: p.stat().st_mtime)
    return logs[-1] if logs else None


def _status(metrics: dict | None, log: Path | None, case: Path | None = None
            ) -> tuple[str, str]:
    """(status, a sentence about it). A metrics.json that says running while no process
    holds the case's run lock was left by a run that was killed: interrupted."""
    age = time.time() - log.stat().st_mtime if log and log.exists() else None
    if metrics is None:
        if log is None:
            return "not run", "The case has not been run (no metrics.json, no solver log)."
        if age is not None and age < LIVE_LOG_S:
            return "running", (f"No metrics.json yet; the solver log was written "
                               f"{age:.0f} s ago.")
        return "stopped", ("No metrics.json: the run stopped before writing its results "
                           "(killed?).")
    status = str(metrics.get("status") or "unknown")
    reason = metrics.get("end_reason")
    if status == FINISHED:
        steady = "steady state reached" if metrics.get("steady") else \
            f"not steady (ended at {reason})"
        return status, f"The run finished: {steady}."
    if status == "running" and case is not None and not run_lock_held(case):
        return "interrupted", KILLED
    if status == "running":
        live = (f"the solver log was written {age:.0f} s ago" if age is not None
                else "no solver log yet")
        if age is not None and age > LIVE_LOG_S:
            return "stopped", (f"metrics.json says running but {live}: the run stopped "
                               "without writing its results.")
        return status, f"The run is still going ({live}); this report shows the last write."
    if status == "failed":
        return status, f"The run FAILED ({reason or 'unknown reason'})."
    if status == "interrupted" and reason == "monitor_killed":
        return status, KILLED
    if status == "interrupted":
        return status, "The run was interrupted (Ctrl-C or SIGTERM) before its end."
    return status, f"Run status: {status}."


def load_case(case: str | os.PathLike) -> CaseInfo:
    """Read everything about the case folder ``case`` except the fields. Never raises for a
    missing or broken file (see :attr:`CaseInfo.problems`); raises FileNotFoundError only if
    ``case`` is not a folder."""
    case = Path(case)
    if not case.is_dir():
        raise FileNotFoundError(f"{case}: no such case folder")
    problems: list[str] = []
    geom = load_geometry_tolerant(case, problems)
    spec, spec_dict = _load_spec(case, problems)
    metrics = _read_metrics(case, problems)
    log = find_log(case, geom)
    status, detail = _status(metrics, log, case)
    try:
        history = read_history(case / "history.csv")
    except (OSError, csv.Error) as exc:
        problems.append(f"history.csv unreadable ({exc})")
        history = None
    tail = tail_lines(log, LOG_TAIL_LINES) if log else []
    if not tail and metrics and metrics.get("log_tail"):
        tail = list(metrics["log_tail"])
    precalc = _read_json(case / "precalc" / "summary.json", problems)
    spec_name = str(spec_dict.get("name") or "")
    name = case.resolve().name if case.name in ("", ".") else case.name
    if spec_name and spec_name not in (name, "case", "test"):
        name = f"{name} ({spec_name})"
    return CaseInfo(path=case, name=name, geom=geom, spec=spec, spec_dict=spec_dict,
                    metrics=metrics or {}, history=history, status=status,
                    status_detail=detail, log_path=log, log_tail=tail,
                    log_header=log_header(log) if log else {}, precalc=precalc,
                    problems=problems)
