"""The tables of a batch report: the index of its cases with thumbnails, its failures with
their reason and log, and the mesh convergence of the cases run on all three levels. Values
are shown in the display units of :mod:`ehlfoam.report.units`."""

from __future__ import annotations

import os
from pathlib import Path

from ehlfoam.batch.plan import PARAM_KEYS
from ehlfoam.metrics import convergence
from ehlfoam.report import units
from ehlfoam.report.case_data import find_log, load_geometry_tolerant, tail_lines
from ehlfoam.report.case_report import REPORT
from ehlfoam.report.html import Table, cell
from ehlfoam.report.top_view import bubble_length

__all__ = ["GROUP_KEYS", "LEVELS", "convergence_groups", "convergence_table", "failures_table",
           "fmt", "index_table", "reading_text"]

#: The resolution levels, coarsest first, that a mesh convergence reading needs all of.
LEVELS = ("coarse", "medium", "fine")
#: Parameters that tell the cases of one convergence group apart from another's.
GROUP_KEYS = tuple(k for k in PARAM_KEYS if k != "mesh.resolution")
#: The parameters of the index's columns.
INDEX_KEYS = ("contact.speed", "contact.temperature", "contact.load")
#: The metrics of the index's columns besides the bubble.
INDEX_METRICS = ("inlet_meniscus_distance_over_a", "wall_s", "cells")


def rel(target: Path, start: Path) -> str:
    return os.path.relpath(target, start)


def fmt(value) -> str:
    """A number for a table cell: whole numbers without decimals, else 3 digits."""
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e6:
        return f"{int(value)}"
    return units.fmt_number(value, 3)


def _shown(key: str, value) -> str:
    return fmt(units.scaled(key, value))


def _metric_header(key: str) -> str:
    u = units.METRICS[key]
    short = {"inlet_meniscus_distance_over_a": "inlet meniscus", "wall_s": "wall"}.get(key, key)
    return f"{short} [{u.unit}]" if u.unit else short


def index_table(rows: list[dict], out: Path) -> Table:
    """Every case with its thumbnail, parameters, status, state and main metrics; a
    picture or a name links to the case report."""
    layer = units.SPEC["supply.disc_layer"]
    header = ["", "case", *(units.short_label(k) for k in INDEX_KEYS),
              f"layers [{layer.unit}]", "status", "state",
              _metric_header(INDEX_METRICS[0]),
              f"bubble / wake gas [{units.METRICS['bubble_length_over_a'].unit}]",
              *(_metric_header(k) for k in INDEX_METRICS[1:])]
    body = []
    for r in rows:
        folder = r.get("_folder")
        index = folder / REPORT / "index.html" if folder else None
        thumb = folder / REPORT / "thumb.png" if folder else None
        href = rel(index, out) if index and index.exists() else None
        img = rel(thumb, out) if thumb and thumb.exists() else None
        layers = (f"{_shown('supply.disc_layer', r.get('supply.disc_layer'))} / "
                  f"{_shown('supply.ball_layer', r.get('supply.ball_layer'))}"
                  if r.get("supply.disc_layer") is not None else (r.get("supply.mode") or "-"))
        l_a, _ = bubble_length(r)
        body.append([cell("" if img else "(no picture)", href=href, img=img),
                     cell(r.get("case_id"), href=href),
                     *(cell(_shown(k, r.get(k)), num=True) for k in INDEX_KEYS), layers,
                     r.get("status") or "-", r.get("state") or r.get("_live_state") or "-",
                     cell(fmt(r.get(INDEX_METRICS[0])), num=True), cell(fmt(l_a), num=True),
                     *(cell(fmt(r.get(k)), num=True) for k in INDEX_METRICS[1:])])
    return Table("Cases", header, body, note="Click a picture or a name for the case report.")


def failures_table(rows: list[dict], batch: Path, out: Path,
                   report_errors: dict[Path, str]) -> Table | None:
    """The failed, interrupted or stopped cases and those whose report failed: reason, log
    and its last line; None without any."""
    body = []
    for r in rows:
        folder = r.get("_folder")
        failed = r.get("status") in ("failed", "interrupted", "stopped")
        err = report_errors.get(folder) if folder else None
        if not failed and not err:
            continue
        log_rel = r.get("log")
        log = batch / log_rel if log_rel else (
            find_log(folder, load_geometry_tolerant(folder, [])) if folder else None)
        last = tail_lines(log, 1) if log and log.exists() else []
        reason = r.get("reason") or r.get("end_reason") or "-"
        if err:
            reason = f"{reason}; the case report could not be made: {err}"
        body.append([cell(r.get("case_id"),
                          href=rel(folder / REPORT / "index.html", out)
                          if folder and (folder / REPORT / "index.html").exists() else None),
                     r.get("status") or "-", reason,
                     cell(log.name if log and log.exists() else "(no log)",
                          href=rel(log, out) if log and log.exists() else None),
                     last[0] if last else ""])
    if not body:
        return None
    return Table("Failures", ["case", "status", "reason", "log", "last log line"], body)


def convergence_groups(rows: list[dict]) -> list[tuple[dict, list[Path]]]:
    """Finished cases that differ only in their resolution level and cover all three:
    (the shared parameters, the case folders coarse, medium, fine) per group."""
    groups: dict[tuple, dict[str, Path]] = {}
    for r in rows:
        if r.get("status") != "finished" or r.get("_folder") is None \
                or r.get("mesh.resolution") not in LEVELS:
            continue
        key = tuple((k, r.get(k)) for k in GROUP_KEYS)
        groups.setdefault(key, {})[r["mesh.resolution"]] = r["_folder"]
    return [(dict(key), [levels[lv] for lv in LEVELS]) for key, levels in groups.items()
            if all(lv in levels for lv in LEVELS)]


def reading_text(o: dict, unit: units.Unit) -> str:
    """One line for a metric's convergence reading
    (:func:`ehlfoam.metrics.convergence.observed_order`)."""
    if o["behaviour"] == "within noise":
        return (f"within noise: the spread {units.display(o['spread'], unit)} {unit.unit} is "
                f"no more than twice the jitter of its last transit")
    if o["behaviour"] == "divergent":
        r = "" if o.get("R") is None else f" (R = {o['R']:+.2g})"
        return f"divergent: the changes do not shrink{r}; no extrapolation"
    if o.get("order") is None:
        return f"{o['behaviour']}: no change on the two finest"
    text = (f"{o['behaviour']}, order {o['order']:.2f}: extrapolated "
            f"{units.display(o['extrapolated'], unit)} {unit.unit}, GCI of the fine level "
            f"{100 * o['gci_fine']:.2g} %")
    if not o["asymptotic"]:
        text += " (order outside 0.5-3: not asymptotic, not to be trusted)"
    return text


def _group_label(params: dict) -> str:
    return ", ".join(f"{units.short_label(k)} {_shown(k, v)}" if units.shown(k).scale
                     else f"{units.short_label(k)} {v}"
                     for k, v in params.items() if v is not None)


def convergence_table(rows: list[dict]) -> Table | None:
    """Per group of cases run on all three levels: each metric's values and reading."""
    body = []
    for params, folders in convergence_groups(rows):
        try:
            readings = convergence.over_cases(folders)
        except (OSError, ValueError, KeyError):
            continue
        label = _group_label(params)
        for key, o in readings.items():
            unit = units.METRICS[key]
            body.append([label, unit.label + (f" [{unit.unit}]" if unit.unit else ""),
                         *(cell(units.display(v, unit), num=True) for v in o["values"][::-1]),
                         reading_text(o, unit)])
    if not body:
        return None
    return Table("Mesh convergence over the three levels",
                 ["cases", "metric", "coarse", "medium", "fine", "reading"], body,
                 note="Each metric's mean over its case's last transit; the reading is Celik "
                      "et al. 2008 (J. Fluids Eng. 130, 078001) with the levels' far-field "
                      "cell sizes: observed order, Richardson extrapolation and the fine "
                      "level's grid convergence index (ehlfoam.metrics.convergence).")
