"""The report of a batch: ``BATCH/report/index.html``.

A batch folder (runs/batch, issue "batches") holds ``plan.json`` (the planned cases),
``results.csv`` (one row per case: parameters, status, reason, state, metrics, the case's
folder and log relative to the batch), ``cases/<id>/`` and ``regime/`` (regime maps and
``regime.json``). Every part is optional; a missing column or file leaves its part out.

The page: counts, the regime pictures, bubble length against speed per temperature with the
thesis's relation fitted, the flow states over the batch's parameters, the mesh convergence of
the cases run on all three resolution levels (runs/convergence.py), an index of the cases
with thumbnails (each linking to its case report) and the failures with their reason and
log. Case reports are made (in parallel) only where none is newer than the case's results;
an up-to-date report's thumbnail is reused.
"""

from __future__ import annotations

import csv
import json
import os
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

from ehlfoam._io import atomic_write_json

from ehlfoam.metrics import convergence
from ehlfoam.report import units
from ehlfoam.report.case_data import load_geometry_tolerant, tail_lines
from ehlfoam.report.case_report import REPORT, report_case
from ehlfoam.report.charts import bubble_relation_x, draw_bubble_vs_speed, draw_state_map, nan_to_none
from ehlfoam.report.html import Figure, Page, Table, cell, write_page
from ehlfoam.report.threads import single_blas_thread

#: Parameters of a batch's cases, in the order they are used as chart axes:
#: column -> (label, scale to the shown unit).
PARAMETERS = {
    "speed_mm_s": ("u [mm/s]", 1.0),
    "disc_layer_um": ("disc layer [um]", 1.0),
    "ball_layer_um": ("ball layer [um]", 1.0),
    "load_N": ("load [N]", 1.0),
    "temperature_C": ("temperature [C]", 1.0),
}
#: Ambient minus cavitation pressure of the bubble relation when the spec has none [Pa]
#: (ambient 1.013e5 Pa, cavitation at 0 Pa absolute: ball_on_disc.md).
DP_DEFAULT = 1.013e5
#: Frames of a case's GIF when the batch report makes the case report (a third of the
#: time of a full one).
BATCH_GIF_FRAMES = 16
SURFACE_TENSION_DEFAULT = 0.030


# ------------------------------------------------------------------ reading
def _number(text):
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


def read_results(batch: Path) -> list[dict]:
    """results.csv rows (numbers as floats), plus planned cases missing from it (status
    "pending") and case folders missing from both."""
    rows: list[dict] = []
    path = batch / "results.csv"
    if path.is_file():
        with open(path, newline="") as fh:
            for raw in csv.DictReader(fh):
                rows.append({k: _number(v) if k not in ("case_id", "state", "status",
                                                         "case_dir", "log", "reason",
                                                         "end_reason", "supply")
                             else (v or None) for k, v in raw.items() if k})
    known = {str(r.get("case_id")) for r in rows}
    plan = _read_plan(batch)
    for item in plan:
        cid = str(item.get("id"))
        if cid in known:
            continue
        row = {"case_id": cid, "status": "pending"}
        row.update(_plan_params(item.get("params") or {}))
        rows.append(row)
        known.add(cid)
    cases = batch / "cases"
    if cases.is_dir():
        for folder in sorted(p for p in cases.iterdir() if p.is_dir()):
            if folder.name not in known:
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


def _plan_params(params: dict) -> dict:
    """A plan entry's parameters as results.csv columns (best effort)."""
    out = {}
    flat = units.flatten(params)
    for key, value in flat.items():
        tail = key.split(".")[-1]
        if tail == "speed" and isinstance(value, (int, float)):
            out["speed_mm_s"] = value * 1e3
        elif tail == "temperature":
            out["temperature_C"] = value
        elif tail == "load":
            out["load_N"] = value
        elif tail in ("disc_layer", "ball_layer") and isinstance(value, (int, float)):
            out[f"{tail}_um"] = value * 1e6
        else:
            out.setdefault(tail, value)
    return out


def _fill_from_case(row: dict, folder: Path) -> None:
    """Fill what results.csv lacks from the case folder (metrics.json, spec)."""
    try:
        metrics = json.loads((folder / "metrics.json").read_text())
    except (OSError, ValueError):
        metrics = {}
    for key, value in metrics.items():
        if row.get(key) is None and not isinstance(value, (list, dict)):
            row[key] = value
    if row.get("status") in (None, "", "pending", "running") and metrics.get("status"):
        row["status"] = metrics["status"]       # results.csv lags behind a live batch
    elif row.get("status") in (None, "") and not metrics:
        row["status"] = "not run"
    try:
        spec = json.loads((folder / "ehlfoam" / "spec.json").read_text())
    except (OSError, ValueError):
        spec = {}
    contact, supply = spec.get("contact") or {}, spec.get("supply") or {}
    physics = spec.get("physics") or {}
    defaults = {"speed_mm_s": _scaled(contact.get("speed"), 1e3),
                "temperature_C": contact.get("temperature"), "load_N": contact.get("load"),
                "disc_layer_um": _scaled(supply.get("disc_layer"), 1e6),
                "ball_layer_um": _scaled(supply.get("ball_layer"), 1e6)}
    for key, value in defaults.items():
        if row.get(key) is None and value is not None:
            row[key] = value
    row["_surface_tension"] = physics.get("surface_tension")
    row["_ambient_pressure"] = physics.get("ambient_pressure")
    geom = load_geometry_tolerant(folder, [])
    if geom is not None:
        row["_eta"], row["_rho"], row["_a"] = geom.oil_viscosity, geom.oil_density, geom.a
        row.setdefault("cells", geom.cells)


def _scaled(value, scale):
    return None if value is None else float(value) * scale


# ------------------------------------------------------------------ case reports
def _needs_report(folder: Path) -> bool:
    """No case report yet, or one made before the case's results last changed
    (metrics.json, history.csv); an up-to-date report and its thumbnail are reused."""
    done = folder / REPORT / "report.json"
    if not done.exists() or not (folder / REPORT / "index.html").exists():
        return True
    made = done.stat().st_mtime
    return any((folder / name).exists() and (folder / name).stat().st_mtime > made
               for name in ("metrics.json", "history.csv"))


def _case_worker(folder: str, animate: bool) -> tuple[str, str | None]:
    """Make one case report in a worker process; (folder, error or None)."""
    try:
        report_case(folder, animate=animate, gif_frames=BATCH_GIF_FRAMES)
        return folder, None
    except Exception as exc:  # noqa: BLE001 - reported on the batch page
        return folder, f"{type(exc).__name__}: {exc}"


def make_case_reports(folders: list[Path], jobs: int, animate: bool) -> dict[Path, str]:
    """Case reports of ``folders``, ``jobs`` at a time (separate processes); returns the
    folders whose report failed, with the error."""
    errors: dict[Path, str] = {}
    if not folders:
        return errors
    if jobs <= 1 or len(folders) == 1:
        for f in folders:
            _, err = _case_worker(str(f), animate)
            if err:
                errors[f] = err
        return errors
    with ProcessPoolExecutor(max_workers=min(jobs, len(folders)),
                             mp_context=get_context("spawn")) as pool:
        for folder, err in pool.map(_case_worker, [str(f) for f in folders],
                                    [animate] * len(folders)):
            if err:
                errors[Path(folder)] = err
    return errors


# ------------------------------------------------------------------ charts
def bubble_points(rows: list[dict]) -> tuple[list[dict], str]:
    """Points (speed [m/s], temperature, l/a, X of the relation, state) of the finished
    cases, and the label of the length used: the bubble length where the cases have it,
    else the gas behind the contact on y = 0 standing in for it (see
    :func:`ehlfoam.report.top_view.bubble_length`)."""
    from ehlfoam.report.top_view import bubble_length

    points, labels = [], set()
    for r in rows:
        l_a, label = bubble_length(r)
        if r.get("status") != "finished" or l_a is None:
            continue
        speed = r.get("speed_mm_s")
        a = r.get("a_m") or r.get("_a")
        if speed is None or a is None or r.get("_eta") is None:
            continue
        u = float(speed) * 1e-3
        sigma = float(r.get("_surface_tension") or SURFACE_TENSION_DEFAULT)
        dp = float(r.get("_ambient_pressure") or DP_DEFAULT)
        x = bubble_relation_x(u, float(a), float(r["_eta"]), float(r["_rho"]), sigma, dp)
        points.append({"speed": u, "temperature": r.get("temperature_C") or 0.0,
                       "l_over_a": l_a, "x": x, "state": r.get("state"),
                       "id": r.get("case_id")})
        labels.add("bubble length" if label == "bubble length" else
                   "gas behind the contact on y = 0")
    return points, " / ".join(sorted(labels)) or "bubble length"


def varying(rows: list[dict]) -> list[str]:
    """The parameter columns that take more than one value in the batch, leaving out one
    that only repeats an earlier one (e.g. the ball layer always equal to the disc layer)."""
    out: list[str] = []
    for key in PARAMETERS:
        values = [r.get(key) for r in rows]
        if len({v for v in values if isinstance(v, (int, float))}) < 2:
            continue
        if any(_same_partition(values, [r.get(k) for r in rows]) for k in out):
            continue
        out.append(key)
    return out


def _same_partition(a: list, b: list) -> bool:
    """a and b group the cases the same way (one is a one-to-one function of the other)."""
    pairs = set(zip(a, b))
    return len(pairs) == len(set(a)) == len(set(b))


def _state_map(rows: list[dict], out: Path) -> Path | None:
    keys = varying(rows)
    if not keys:
        return None
    x_key = keys[0]
    y_key = keys[1] if len(keys) > 1 else None
    panel = keys[2] if len(keys) > 2 else None
    plotted = rows
    if y_key is None:
        y_key = "_one"
        plotted = [{**r, "_one": 0.0} for r in rows]
    label = PARAMETERS.get(y_key, ("", 1.0))[0] if y_key != "_one" else ""
    return draw_state_map(plotted, x_key, y_key, out, x_label=PARAMETERS[x_key][0],
                          y_label=label, panel_key=panel)


# ------------------------------------------------------------------ the page
def _rel(target: Path, start: Path) -> str:
    return os.path.relpath(target, start)


def _live_states(rows: list[dict]) -> None:
    """State of a running case from its report (the newest write), as ``_live_state``."""
    for r in rows:
        folder = r.get("_folder")
        if r.get("state") or folder is None or r.get("status") == "finished":
            continue
        try:
            made = json.loads((folder / REPORT / "report.json").read_text())
        except (OSError, ValueError):
            continue
        if made.get("state") and made.get("fields_time_s"):
            r["_live_state"] = f"{made['state']} (t = {made['fields_time_s'] * 1e3:.3g} ms)"


def _index_table(rows: list[dict], batch: Path, out: Path) -> Table:
    from ehlfoam.report.top_view import bubble_length

    header = ["", "case", "u [mm/s]", "T [C]", "F [N]", "layers [um]", "status", "state",
              "inlet meniscus [a]", "bubble / wake gas [a]", "wall [s]", "cells"]
    body = []
    for r in rows:
        folder = r.get("_folder")
        index = folder / REPORT / "index.html" if folder else None
        thumb = folder / REPORT / "thumb.png" if folder else None
        href = _rel(index, out) if index and index.exists() else None
        img = _rel(thumb, out) if thumb and thumb.exists() else None
        layers = (f"{units.fmt_number(r.get('disc_layer_um'), 3)} / "
                  f"{units.fmt_number(r.get('ball_layer_um'), 3)}"
                  if r.get("disc_layer_um") is not None else (r.get("supply") or "-"))
        l_a, _ = bubble_length(r)
        body.append([cell("" if img else "(no picture)", href=href, img=img),
                     cell(r.get("case_id"), href=href), cell(_f(r.get("speed_mm_s")), num=True),
                     cell(_f(r.get("temperature_C")), num=True),
                     cell(_f(r.get("load_N")), num=True), layers,
                     r.get("status") or "-", r.get("state") or r.get("_live_state") or "-",
                     cell(_f(r.get("inlet_meniscus_distance_over_a")), num=True),
                     cell(_f(l_a), num=True), cell(_f(r.get("wall_s")), num=True),
                     cell(_f(r.get("cells")), num=True)])
    return Table("Cases", header, body, note="Click a picture or a name for the case report.")


def _f(value) -> str:
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e6:
        return f"{int(value)}"
    return units.fmt_number(value, 3)


def _failures_table(rows: list[dict], batch: Path, out: Path,
                    report_errors: dict[Path, str]) -> Table | None:
    body = []
    for r in rows:
        folder = r.get("_folder")
        failed = r.get("status") in ("failed", "interrupted", "stopped")
        err = report_errors.get(folder) if folder else None
        if not failed and not err:
            continue
        log_rel = r.get("log")
        log = batch / log_rel if log_rel else (_find_log(folder) if folder else None)
        last = tail_lines(log, 1) if log and log.exists() else []
        reason = r.get("reason") or r.get("end_reason") or "-"
        if err:
            reason = f"{reason}; the case report could not be made: {err}"
        body.append([cell(r.get("case_id"),
                          href=_rel(folder / REPORT / "index.html", out)
                          if folder and (folder / REPORT / "index.html").exists() else None),
                     r.get("status") or "-", reason,
                     cell(log.name if log and log.exists() else "(no log)",
                          href=_rel(log, out) if log and log.exists() else None),
                     last[0] if last else ""])
    if not body:
        return None
    return Table("Failures", ["case", "status", "reason", "log", "last log line"], body)


def _find_log(folder: Path) -> Path | None:
    from ehlfoam.report.case_data import find_log

    return find_log(folder, load_geometry_tolerant(folder, []))


#: The resolution levels, coarsest first, that a mesh convergence reading needs all of.
LEVELS = ("coarse", "medium", "fine")
#: Parameters that tell the cases of one convergence group apart from another's.
GROUP_KEYS = ("speed_mm_s", "temperature_C", "load_N", "supply", "disc_layer_um",
              "ball_layer_um")


def convergence_groups(rows: list[dict]) -> list[tuple[dict, list[Path]]]:
    """Finished cases that differ only in their resolution level and cover all three:
    (the shared parameters, the case folders coarse, medium, fine) per group."""
    groups: dict[tuple, dict[str, Path]] = {}
    for r in rows:
        if r.get("status") != "finished" or r.get("_folder") is None \
                or r.get("resolution") not in LEVELS:
            continue
        key = tuple((k, r.get(k)) for k in GROUP_KEYS)
        groups.setdefault(key, {})[r["resolution"]] = r["_folder"]
    return [(dict(key), [levels[lv] for lv in LEVELS]) for key, levels in groups.items()
            if all(lv in levels for lv in LEVELS)]


def reading_text(o: dict, unit: units.Unit) -> str:
    """One line for a metric's convergence reading (:func:`ehlfoam.metrics.convergence.observed_order`)."""
    if o["behaviour"] == "within noise":
        return (f"within noise: the spread {units.display(o['spread'], unit)} {unit[1]} is no "
                f"more than twice the jitter of its last transit")
    if o["behaviour"] == "divergent":
        r = "" if o.get("R") is None else f" (R = {o['R']:+.2g})"
        return f"divergent: the changes do not shrink{r}; no extrapolation"
    if o.get("order") is None:
        return f"{o['behaviour']}: no change on the two finest"
    text = (f"{o['behaviour']}, order {o['order']:.2f}: extrapolated "
            f"{units.display(o['extrapolated'], unit)} {unit[1]}, GCI of the fine level "
            f"{100 * o['gci_fine']:.2g} %")
    if not o["asymptotic"]:
        text += " (order outside 0.5-3: not asymptotic, not to be trusted)"
    return text


def _convergence_table(rows: list[dict]) -> Table | None:
    """Per group of cases run on all three levels: each metric's values and reading."""
    body = []
    for params, folders in convergence_groups(rows):
        try:
            readings = convergence.over_cases(folders)
        except (OSError, ValueError, KeyError):
            continue
        label = ", ".join(f"{PARAMETERS[k][0]} {_f(v)}" if k in PARAMETERS else f"{k} {v}"
                          for k, v in params.items() if v is not None)
        for key, o in readings.items():
            unit = units.METRICS[key]
            body.append([label, unit[0] + (f" [{unit[1]}]" if unit[1] else ""),
                         *(cell(units.display(v, unit), num=True) for v in o["values"][::-1]),
                         reading_text(o, unit)])
    if not body:
        return None
    return Table("Mesh convergence over the three levels",
                 ["cases", "metric", "coarse", "medium", "fine", "reading"], body,
                 note="Each metric's mean over its case's last transit; the reading is Celik "
                      "et al. 2008 (J. Fluids Eng. 130, 078001) with the levels' far-field "
                      "cell sizes: observed order, Richardson extrapolation and the fine "
                      "level's grid convergence index (runs/convergence.py).")


def _regime(batch: Path, out: Path, page: Page) -> None:
    regime = batch / "regime"
    if not regime.is_dir():
        return
    for png in sorted(regime.glob("*.png")):
        page.figures.append(Figure(_rel(png, out), f"Regime map: {png.stem}",
                                   "Drawn by the batch (regime/)."))
    try:
        data = json.loads((regime / "regime.json").read_text())
    except (OSError, ValueError):
        return
    if not isinstance(data, dict):
        return
    rows = [[cell(line)] for line in data.get("summary", [])]
    page.tables.insert(0, Table("Transitions I -> II (regime/regime.json)",
                                ["line or ramp branch: transition speed"], rows))


def report_batch(batch_dir: str | os.PathLike, *, jobs: int | None = None,
                 animate: bool = True, force: bool = False) -> Path:
    """Write ``batch_dir/report/index.html`` and return its path. Case reports missing or
    older than their case's results are made first (``jobs`` processes, default up to 2;
    ``force``: all of them)."""
    batch = Path(batch_dir)
    if not batch.is_dir():
        raise FileNotFoundError(f"{batch}: no such batch folder")
    with single_blas_thread():     # and OPENBLAS_NUM_THREADS=1 in the workers
        return _report_batch(batch, jobs, animate, force)


def _report_batch(batch: Path, jobs: int | None, animate: bool, force: bool) -> Path:
    start = time.perf_counter()
    out = batch / REPORT
    out.mkdir(exist_ok=True)
    rows = read_results(batch)
    todo = [r["_folder"] for r in rows if r.get("_folder") is not None
            and (force or _needs_report(r["_folder"]))]
    jobs = jobs or max(1, min(2, os.cpu_count() or 1))
    t0 = time.perf_counter()
    errors = make_case_reports(todo, jobs, animate)
    t_cases = time.perf_counter() - t0

    with_folder = sum(1 for r in rows if r.get("_folder") is not None)
    _live_states(rows)
    counts: dict[str, int] = {}
    for r in rows:
        counts[r.get("status") or "unknown"] = counts.get(r.get("status") or "unknown", 0) + 1
    states = {s: sum(1 for r in rows if r.get("state") == s and r.get("status") == "finished")
              for s in ("I", "II")}
    bad = counts.get("failed", 0) + len(errors)
    page = Page(title=f"{batch.resolve().name}: ehlfoam batch report",
                status="fail" if bad else ("ok" if counts.get("finished", 0) == len(rows)
                                           else "warn"),
                status_text=f"{len(rows)} cases: " + ", ".join(
                    f"{n} {k}" for k, n in sorted(counts.items())) +
                f". Finished cases in state I: {states['I']}, state II: {states['II']}.")
    problems: list[str] = []
    _regime(batch, out, page)
    points, label = bubble_points(rows)
    try:
        if points:
            _, fits = draw_bubble_vs_speed(points, out / "bubble_vs_speed.png", label=label)
            page.figures.append(Figure(
                "bubble_vs_speed.png", "Bubble length against speed",
                f"l/a ({label}) of the finished cases; filled: state I, fitted by linear least "
                f"squares per temperature to l/a = C1 Re^-1/2 (Ca/2)^-5/4 We^-1/2 + C2 with "
                f"Re = rho u a / eta, Ca = (p_atm - p_cav) / (rho u^2 / 2), "
                f"We = rho u^2 a / sigma, p_atm - p_cav = 101.3 kPa (cavitation at 0 Pa "
                f"absolute), eta and rho of the oil at the case's temperature, sigma from "
                f"the spec. Hollow: state II (open wake), not fitted."))
            page.tables.append(Table(
                "Bubble relation constants", ["temperature [C]", "points (state I)", "C1",
                                              "C2", "note"],
                [[cell(_f(f.temperature), num=True), cell(f.n, num=True),
                  cell(units.fmt_number(f.c1), num=True),
                  cell(units.fmt_number(f.c2), num=True), f.reason or "least squares"]
                 for f in fits]))
            page.summary.extend(
                f"Bubble relation at {f.temperature:g} C: " +
                (f"C1 = {f.c1:.4g}, C2 = {f.c2:.4g} ({f.n} points)" if f.c1 is not None
                 else f"not enough points ({f.n})") for f in fits)
        state_png = _state_map(rows, out / "states.png")
        if state_png:
            page.figures.append(Figure("states.png", "Flow pattern states over the batch",
                                       "State I (closed flooded region) and II (open) of "
                                       "each case over the parameters the batch varies."))
    except Exception as exc:  # noqa: BLE001 - the page still lists the cases
        problems.append(f"batch charts: {type(exc).__name__}: {exc}")
    conv = _convergence_table(rows)
    if conv is not None:
        page.tables.append(conv)
    failures = _failures_table(rows, batch, out, errors)
    if failures:
        page.lead_tables.append(failures)
    page.thumbnails = _index_table(rows, batch, out)
    page.problems = problems
    elapsed = time.perf_counter() - start
    page.footer = (f"ehlfoam batch report, {time.strftime('%Y-%m-%d %H:%M:%S')}, made in "
                   f"{elapsed:.1f} s ({len(todo)} case reports made in {t_cases:.1f} s with "
                   f"{jobs} process(es), {with_folder - len(todo)} reused).")
    index = write_page(page, out / "index.html")
    atomic_write_json(out / "report.json", {
        "batch": str(batch), "cases": len(rows), "counts": counts, "states": states,
        "case_reports_made": len(todo), "case_report_errors": {str(k): v for k, v in
                                                               errors.items()},
        "wall_s": elapsed, "case_reports_s": t_cases})
    (out / "report.json").chmod(0o644)
    return index



