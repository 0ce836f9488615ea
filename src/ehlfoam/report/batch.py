"""The report of a batch: ``BATCH/report/index.html``.

A batch folder (:mod:`ehlfoam.batch.folder`) holds ``plan.json`` (the planned cases),
``results.csv`` (one row per case: its parameters, the case spec's dotted keys in SI, its
status, reason, state, metrics, the case's folder and log relative to the batch),
``cases/<id>/`` and ``regime/regime.json`` (the regime analysis). Every part is optional; a
missing column or file leaves its part out.

The page: counts, the regime map (text and pictures), bubble length against speed per
temperature with the thesis's relation fitted, the flow states over the batch's parameters,
the mesh convergence of the cases run on all three resolution levels
(:mod:`ehlfoam.metrics.convergence`), an index of the cases with thumbnails (each linking to
its case report) and the failures with their reason and log. Case reports are made (in
parallel) only where none is newer than the case's results; an up-to-date report's thumbnail
is reused. Numbers are shown in the display units of :mod:`ehlfoam.report.units`.
"""

from __future__ import annotations

import json
import os
import signal
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

from ehlfoam._io import atomic_write_json
from ehlfoam.batch.regime import REGIME
from ehlfoam.foam.lifetime import set_parent_death_signal
from ehlfoam.report import units
from ehlfoam.report.batch_rows import read_results
from ehlfoam.report.batch_tables import (convergence_table, failures_table, fmt, index_table,
                                         rel)
from ehlfoam.report.case_report import REPORT, report_case
from ehlfoam.report.charts import bubble_relation_x, draw_bubble_vs_speed, draw_state_map
from ehlfoam.report.html import Figure, Page, Table, cell, write_page
from ehlfoam.report.regime import summary_lines, write_figures
from ehlfoam.report.threads import single_blas_thread
from ehlfoam.report.trust import batch_description, trust_lines
from ehlfoam.report.top_view import bubble_length

__all__ = ["after_batch", "bubble_points", "make_case_reports", "report_batch", "varying"]

#: Parameters of a batch's cases, in the order they are used as chart axes (their labels and
#: display units: ehlfoam.report.units.SPEC).
PARAMETERS = ("contact.speed", "supply.disc_layer", "supply.ball_layer", "contact.load",
              "contact.temperature")
#: Ambient minus cavitation pressure of the bubble relation when the spec has none [Pa]
#: (ambient 1.013e5 Pa, cavitation at 0 Pa absolute:
#: docs/reference.md#conditions-thesis-table-21).
DP_DEFAULT = 1.013e5
#: Frames of a case's GIF when the batch report makes the case report (a third of the
#: time of a full one).
BATCH_GIF_FRAMES = 16
SURFACE_TENSION_DEFAULT = 0.030


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


def _die_with_batch(parent: int) -> None:
    """Initializer of a report worker: it dies with the process that made the pool (a batch
    killed while its report is drawn leaves no worker behind; the pool's resource tracker
    then ends too, its last user gone)."""
    set_parent_death_signal(signal.SIGKILL, parent)


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
                             mp_context=get_context("spawn"), initializer=_die_with_batch,
                             initargs=(os.getpid(),)) as pool:
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
    points, labels = [], set()
    for r in rows:
        l_a, label = bubble_length(r)
        if r.get("status") != "finished" or l_a is None:
            continue
        u = r.get("contact.speed")
        a = r.get("a_m") or r.get("_a")
        if u is None or a is None or r.get("_eta") is None:
            continue
        sigma = float(r.get("_surface_tension") or SURFACE_TENSION_DEFAULT)
        dp = float(r.get("_ambient_pressure") or DP_DEFAULT)
        x = bubble_relation_x(float(u), float(a), float(r["_eta"]), float(r["_rho"]), sigma,
                              dp)
        points.append({"speed": float(u), "temperature": r.get("contact.temperature") or 0.0,
                       "l_over_a": l_a, "x": x, "state": r.get("state"),
                       "id": r.get("case_id")})
        labels.add("bubble length" if label == "bubble length" else
                   "gas behind the contact on y = 0")
    return points, " / ".join(sorted(labels)) or "bubble length"


def varying(rows: list[dict]) -> list[str]:
    """The parameters that take more than one value in the batch, leaving out one that only
    repeats an earlier one (e.g. the ball layer always equal to the disc layer)."""
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

    def axis(key: str) -> tuple[str, float]:
        return units.short_label(key), units.shown(key).scale or 1.0

    (x_label, x_scale), (y_label, y_scale) = axis(x_key), (axis(y_key) if y_key != "_one"
                                                           else ("", 1.0))
    return draw_state_map(plotted, x_key, y_key, out, x_label=x_label, y_label=y_label,
                          x_scale=x_scale, y_scale=y_scale, panel_key=panel,
                          panel_title=(lambda v: f"{units.short_label(panel)} = "
                                       f"{fmt(units.scaled(panel, v))}") if panel else None)


def _bubble_chart(rows: list[dict], out: Path, page: Page) -> None:
    points, label = bubble_points(rows)
    if not points:
        return
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
        "Bubble relation constants", [units.short_label("contact.temperature"),
                                      "points (state I)", "C1", "C2", "note"],
        [[cell(fmt(f.temperature), num=True), cell(f.n, num=True),
          cell(units.fmt_number(f.c1), num=True),
          cell(units.fmt_number(f.c2), num=True), f.reason or "least squares"]
         for f in fits]))
    page.summary.extend(
        f"Bubble relation at {f.temperature:g} C: " +
        (f"C1 = {f.c1:.4g}, C2 = {f.c2:.4g} ({f.n} points)" if f.c1 is not None
         else f"not enough points ({f.n})") for f in fits)


# ------------------------------------------------------------------ the page
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


def _read_regime(batch: Path) -> dict | None:
    try:
        data = json.loads((batch / REGIME / "regime.json").read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def _regime(batch: Path, out: Path, page: Page) -> None:
    """The regime map from regime/regime.json: its pictures and its transitions."""
    data = _read_regime(batch)
    if data is None:
        return
    for png in write_figures(data, out):
        page.figures.append(Figure(rel(png, out), f"Regime map: {png.stem}",
                                   "From the batch's regime analysis (regime/regime.json)."))
    rows = [[cell(line)] for line in summary_lines(data)]
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
    page.summary.extend([batch_description(batch), *trust_lines(rows)])   # what, how far
    page.summary[:] = [line for line in page.summary if line]
    problems: list[str] = []
    try:
        _regime(batch, out, page)
    except Exception as exc:  # noqa: BLE001 - the page still lists the cases
        problems.append(f"regime map: {type(exc).__name__}: {exc}")
    try:
        _bubble_chart(rows, out, page)
        state_png = _state_map(rows, out / "states.png")
        if state_png:
            page.figures.append(Figure("states.png", "Flow pattern states over the batch",
                                       "State I (closed flooded region) and II (open) of "
                                       "each case over the parameters the batch varies."))
    except Exception as exc:  # noqa: BLE001 - the page still lists the cases
        problems.append(f"batch charts: {type(exc).__name__}: {exc}")
    conv = convergence_table(rows)
    if conv is not None:
        page.tables.append(conv)
    failures = failures_table(rows, batch, out, errors)
    if failures:
        page.lead_tables.append(failures)
    page.thumbnails = index_table(rows, out)
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


def after_batch(batch_dir: str | os.PathLike, log: Callable[[str], None]) -> Path:
    """What ``ehlfoam batch`` makes after its cases (:class:`ehlfoam.batch.launch.BatchOptions`
    ``report``): the regime map's transitions in the log, then the batch report."""
    batch = Path(batch_dir)
    for line in summary_lines(_read_regime(batch) or {}):
        log(f"regime: {line}")
    index = report_batch(batch)
    log(f"batch report: {index}")
    return index
