"""The report of one case: ``CASE/report/index.html`` with its pictures beside it.

Steps (each one guarded: a step that fails is listed on the page and the rest still shows):
fields of the newest write (pyvista) -> top view, side view, pressure map; precalc picture;
history chart; transient GIF; tables (metrics with units, settling, spec, solver and mesh,
precalc). A case that failed, is running, was interrupted or never ran says so at the top
with the last lines of its solver log.
"""

from __future__ import annotations

import json
import os
import time
import traceback
from pathlib import Path

from ehlfoam._io import atomic_write_json

from ehlfoam.report import units
from ehlfoam.report.case_data import CaseInfo, load_case
from ehlfoam.report.html import Figure, Page, Table, cell, write_page
from ehlfoam.report.threads import single_blas_thread

REPORT = "report"
#: Files a case report writes (removed first, so no stale picture survives a failed step).
OUTPUTS = ("index.html", "report.json", "top_view.png", "top_view.json", "side_view.png",
           "pressure.png", "ehl_precalc.png", "history.png", "transient.gif", "thumb.png")


class Steps:
    """Runs the report's steps, timing each and turning an exception into a problem line."""

    def __init__(self, problems: list[str]):
        self.problems = problems
        self.timings: dict[str, float] = {}

    def run(self, name: str, func, *args, **kwargs):
        start = time.perf_counter()
        try:
            return func(*args, **kwargs)
        except Exception as exc:  # a report never crashes on a broken case
            where = traceback.extract_tb(exc.__traceback__)[-1]
            self.problems.append(f"{name}: {type(exc).__name__}: {exc} "
                                 f"({Path(where.filename).name}:{where.lineno})")
            return None
        finally:
            self.timings[name] = time.perf_counter() - start


def _banner(info: CaseInfo) -> tuple[str, str]:
    kind = {"finished": "ok" if info.metrics.get("steady") else "warn", "running": "warn",
            "interrupted": "warn", "stopped": "warn", "not run": "warn"}.get(info.status,
                                                                              "fail")
    label = info.status.upper() if kind == "fail" else info.status
    return kind, f"Status: {label}. {info.status_detail}"


def metrics_table(metrics: dict, a: float | None) -> Table:
    """Every metrics.json key with its label, value, unit (and mm for lengths in a)."""
    rows = []
    for key, value in metrics.items():
        if key in units.METRICS_HIDDEN:
            continue
        unit = units.METRICS.get(key, (key, "", None))
        mm = ""
        if key.endswith("_over_a") and a and isinstance(value, (int, float)) \
                and not isinstance(value, bool):
            mm = units.fmt_number(value * a * 1e3)
        rows.append([unit[0], cell(units.display(value, unit), num=True), unit[1],
                     cell(mm, num=True), key])
    return Table("Metrics (metrics.json)", ["quantity", "value", "unit", "in mm", "key"], rows,
                 note="SI inside ehlfoam; shown in the units of the third column. "
                      "Lengths in a are ratios to the Hertzian radius.")


def spec_table(spec_dict: dict) -> Table:
    rows = []
    for key, value in units.flatten(spec_dict).items():
        unit = units.SPEC.get(key, (key, "", None))
        rows.append([unit[0], cell(units.display(value, unit), num=True), unit[1], key])
    return Table("Spec (ehlfoam/spec.json)", ["parameter", "value", "unit", "key"], rows)


def solver_table(info: CaseInfo, n_times: int) -> Table:
    g, m, sd = info.geom, info.metrics, info.spec_dict
    level = (sd.get("mesh") or {}).get("resolution", "-")
    rows = [["Solver", info.solver, ""],
            ["OpenFOAM build", info.log_header.get("Build", "-"), ""],
            ["MPI ranks", str(info.log_header.get("nProcs") or
                              (sd.get("run") or {}).get("n_procs", "-")), ""]]
    if g is not None:
        rows += [["Cells", units.fmt_number(g.cells), ""],
                 ["Mesh level", level, ""],
                 ["Cells across the gap", str(g.n_layers), ""],
                 ["Smallest in-plane cell (rim or refinement)", f"{g.min_cell_size * 1e6:.3g}", "um"],
                 ["Domain x", f"{g.x_min * 1e3:.3g} to {g.x_max * 1e3:.3g}", "mm"],
                 ["Domain y", f"{0 if g.symmetric else -g.y_max * 1e3:.3g} to "
                              f"{g.y_max * 1e3:.3g}"
                  + (" (half, mirrored)" if g.symmetric else ""), "mm"],
                 ["Island radius", f"{g.island_radius * 1e3:.3g}", "mm"],
                 ["Gap at the island rim", f"{g.island_gap * 1e6:.3g}", "um"],
                 ["Largest time step (maxDeltaT)", f"{g.max_delta_t * 1e6:.3g}", "us"],
                 ["Transit time", f"{g.transit_time * 1e3:.4g}", "ms"],
                 ["End time", f"{g.end_time * 1e3:.4g}", "ms"]]
    rows += [["Written times", str(n_times), ""],
             ["Time steps", units.fmt_number(m.get("time_steps")), ""],
             *([units.METRICS[k].label, units.display(m.get(k), units.METRICS[k]),
                units.METRICS[k].unit] for k in ("simulated_time_s", "wall_s"))]
    return Table("Solver and mesh", ["", "value", "unit"],
                 [[r[0], cell(r[1], num=True), r[2]] for r in rows])


def precalc_table(summary: dict) -> Table:
    rows = []
    for key, unit in units.PRECALC.items():
        if key in summary:
            rows.append([unit[0], cell(units.display(summary[key], unit), num=True), unit[1],
                         key])
    return Table("EHL precalc (precalc/summary.json)", ["quantity", "value", "unit", "key"],
                 rows)


def settling_table(st, transit_s: float | None) -> Table:
    rows = []
    for key, (change, tol, unit) in st.changes.items():
        label = units.METRICS.get(key, (key,))[0]
        shown = f"{change:+.2%}" if unit == "relative" else f"{change:+.3g} a"
        limit = f"{tol:.2%}" if unit == "relative" else f"{tol:.3g} a"
        rows.append([label, cell(shown, num=True), cell(limit, num=True),
                     "yes" if abs(change) <= tol else "no"])
    window = f"{st.window_s * 1e3:.4g} ms" if st.window_s else "-"
    return Table("Did it settle? Change over the last transit", ["quantity", "change",
                                                                 "tolerance", "within"],
                 rows, note=f"The monitor's steady-state test, on history.csv: last write "
                            f"against the write one transit ({window}) earlier.")


def settling_sentence(st) -> str:
    """One line: settled or not, with the change of each tracked quantity."""
    parts = []
    for key, (change, tol, unit) in st.changes.items():
        label = units.METRICS.get(key, (key,))[0].split(" (")[0].split(",")[0].lower()
        parts.append(f"{label} {change:+.1%} (tolerance {tol:.0%})" if unit == "relative"
                     else f"{label} {change:+.2f} a ({tol:.2g} a)")
    verdict = "settled" if st.settled else "NOT settled"
    return f"Over the last transit ({st.window_s * 1e3:.4g} ms) the run {verdict}: " + \
        "; ".join(parts) + "."


def _clean(out: Path) -> None:
    for name in OUTPUTS:
        (out / name).unlink(missing_ok=True)


def _rel(path: Path | None, start: Path) -> str | None:
    return None if path is None else os.path.relpath(path, start)


def report_case(case_dir: str | os.PathLike, *, animate: bool = True,
                gif_frames: int = 48) -> Path:
    """Write ``case_dir/report/index.html`` (and its PNGs) and return its path. Works for
    finished, failed, running, interrupted and never-run cases. ``animate``: make the
    transient's GIF (at most ``gif_frames`` frames). Raises FileNotFoundError only when
    ``case_dir`` is not a folder. OpenBLAS runs one thread meanwhile
    (:mod:`ehlfoam.report.threads`)."""
    with single_blas_thread():
        return _report_case(case_dir, animate, gif_frames)


def _report_case(case_dir: str | os.PathLike, animate: bool, gif_frames: int) -> Path:
    from ehlfoam.run.monitor import settle_killed_run

    start = time.perf_counter()
    settle_killed_run(case_dir)   # a run killed with metrics.json 'running': say so in it
    info = load_case(case_dir)
    case = info.path
    out = case / REPORT
    out.mkdir(exist_ok=True)
    _clean(out)
    problems = list(info.problems)
    steps = Steps(problems)
    kind, banner = _banner(info)
    page = Page(title=f"{info.name}: ehlfoam case report", status=kind, status_text=banner,
                problems=problems)
    if kind != "ok":
        page.log_tail = info.log_tail or ["(no solver log)"]
        page.log_href = _rel(info.log_path, out)

    fields = None
    thin = info.scene == "thin-film"   # the gap-averaged model's state, no OpenFOAM fields
    if info.geom is not None and thin:
        from ehlfoam.report.thin_film import load_thin_film_fields

        fields = steps.run("read state", load_thin_film_fields, case, info.geom)
        if fields is None and "read state" not in " ".join(problems):
            page.summary.append("No state.npz yet (the thin-film case has not run): nothing "
                                "to picture.")
    elif info.geom is not None:
        from ehlfoam.report.fields import load_fields

        amb = getattr(info.geom, "ambient_pressure", 1.013e5)
        fields = steps.run("read fields", load_fields, case, info.geom, info.scene, amb)
        if fields is None and "read fields" not in " ".join(problems):
            page.summary.append("No fields were written yet (no time folder after 0): "
                                "nothing to picture.")
    summary_top = None
    if fields is not None:
        summary_top = steps.run("top view", _top_view, info, fields, out, page)
        if not thin:
            steps.run("side view", _side_view, info, fields, out, page)
        steps.run("pressure map", _pressure, info, fields, out, page)
    steps.run("precalc picture", _precalc, info, out, page)
    settle = steps.run("history chart", _history, info, out, page)
    stops = (info.geom is not None and info.spec is not None
             and info.spec.stop.at is not None and (thin or fields is not None))
    if animate and fields is not None and not thin and not stops:
        # a 3D stop's GIF draws the same written times, labelled: one GIF, not two
        steps.run("transient GIF", _gif, info, fields, out, page, gif_frames)
    if animate and stops:
        steps.run("stop GIF", _stop, info, out, page, not thin)
    if summary_top:
        page.summary.extend(summary_top)
    if info.metrics and fields is not None:
        t_m = info.metrics.get("simulated_time_s")
        if t_m is not None and abs(float(t_m) - fields.time) > 1e-9 * max(1.0, fields.time):
            page.summary.append(f"The pictures show the newest write, t = "
                                f"{fields.time * 1e3:.4g} ms; metrics.json is of t = "
                                f"{float(t_m) * 1e3:.4g} ms.")
    if settle is not None and settle.changes:
        page.summary.append(settling_sentence(settle))
        page.tables.append(settling_table(settle, info.geom.transit_time if info.geom else None))
    if info.metrics:
        page.tables.append(metrics_table(info.metrics, info.a))
    n_times = 0
    try:
        from ehlfoam.run.fields import time_folders

        n_times = len(time_folders(case))
    except OSError:
        pass
    page.tables.append(solver_table(info, n_times))
    if info.precalc:
        page.tables.append(precalc_table(info.precalc))
    if info.spec_dict:
        page.tables.append(spec_table(info.spec_dict))
    page.links = [(name, f"../{name}") for name in ("metrics.json", "history.csv")
                  if (case / name).exists()]
    if info.log_path:
        page.links.append((f"solver log ({info.log_path.name})", _rel(info.log_path, out)))
    if (case / "precalc" / "precalc.png").exists():
        page.links.append(("precalc's own picture", "../precalc/precalc.png"))
    elapsed = time.perf_counter() - start
    page.footer = (f"ehlfoam report, {time.strftime('%Y-%m-%d %H:%M:%S')}, made in "
                   f"{elapsed:.1f} s (" + ", ".join(f"{k} {v:.2f} s" for k, v in
                                                   steps.timings.items()) + ").")
    index = write_page(page, out / "index.html")
    atomic_write_json(out / "report.json", {
        "case": str(case), "name": info.name, "status": info.status, "state":
        (info.metrics.get("state") or (fields.pattern.get("state") if fields else None)),
        "fields_time_s": fields.time if fields else None, "wall_s": elapsed,
        "timings_s": steps.timings, "problems": problems,
        "images": [f.src for f in page.figures]})
    (out / "report.json").chmod(0o644)
    return index


# ----------------------------------------------------------------- the steps
def _top_view(info: CaseInfo, fields, out: Path, page: Page) -> list[str]:
    from ehlfoam.report.top_view import axes_box, draw_top_view, thumbnail

    g = info.geom
    pattern = dict(fields.pattern)
    oil = info.metrics.get("oil_volume_m3") if _same_time(info, fields) else None
    tv = draw_top_view(fields.raster, pattern, out / "top_view.png",
                       title=f"{info.name}: mid-gap oil fraction seen through the disc",
                       time_s=fields.time, speed=g.speed, transit_s=g.transit_time,
                       oil_volume=oil)
    stamp = None if info.status == "finished" else info.status.upper()
    thumbnail(tv.path, out / "thumb.png", box=axes_box(tv), stamp=stamp)
    what = ("Oil fraction at mid-gap (amber: oil, pale: air)" if info.scene != "thin-film"
            else "The thin-film model's oil as a mid-gap oil fraction (amber: the flooded "
                 "region, its menisci where the model puts them within their cells; pale: "
                 "air or gas, with films or layers on the walls)")
    page.figures.append(Figure(
        "top_view.png", "Top view (as through the glass disc)",
        f"{what}, the metrics' own raster (a/20) and "
        "alpha = 0.5 meniscus line (black); grey disc: the island wall around the unmeshed "
        "contact, dashed: the Hertzian circle; red: the bubble (gas enclosed at the contact "
        "exit) and its length l from x = a along y = 0."))
    return tv.caption[:2]


def _same_time(info: CaseInfo, fields) -> bool:
    t = info.metrics.get("simulated_time_s")
    return t is not None and abs(float(t) - fields.time) <= 1e-9 * max(1.0, fields.time)


def _side_view(info: CaseInfo, fields, out: Path, page: Page) -> None:
    from ehlfoam.report.side_view import draw_side_view

    sv = draw_side_view(fields, out / "side_view.png", title=f"{info.name}: cut at y = 0")
    e1, e2 = sv.exaggeration
    page.figures.append(Figure(
        "side_view.png", "Side view along y = 0",
        f"Gap between the disc (z = 0) and the ball, z exaggerated {e1:g} times (top, whole "
        f"length, coloured by oil fraction) and {e2:g} times (bottom, around the contact, oil "
        f"coloured by u_x / u: blue is reverse flow, the recirculation; arrows: velocity in "
        f"the oil). Grey bands: the island wall and the Hertzian contact."))


def _pressure(info: CaseInfo, fields, out: Path, page: Page) -> None:
    from ehlfoam.report.pressure import draw_pressure

    pv = draw_pressure(fields, out / "pressure.png", title=info.name)
    if pv is None:
        page.problems.append("pressure map: no p or p_rgh written")
        return
    page.figures.append(Figure(
        "pressure.png", "Pressure around the contact ("
        + ("thin-film model: the gas in a cavity at the cavitation pressure, the outer air at "
           "ambient)" if info.scene == "thin-film" else "CFD)"),
        f"Mid-gap gauge pressure; hatched: sub-ambient (p < -{pv.threshold / 1e3:.2g} kPa, "
        f"1 % of the largest |p|). Lowest {pv.p_min / 1e3:.3g} kPa, highest "
        f"{pv.p_max / 1e3:.3g} kPa. Below: along y = 0."))


def _precalc(info: CaseInfo, out: Path, page: Page) -> None:
    from ehlfoam.report.pressure import draw_precalc, load_precalc_solution

    solution = load_precalc_solution(info.path)
    if solution is None:
        if info.precalc is None:
            page.problems.append("EHL precalc: no precalc/solution.npz or summary.json")
        return
    draw_precalc(solution, info.precalc, out / "ehl_precalc.png", title=info.name)
    s = info.precalc or {}
    hc = s.get("hc_m")
    page.figures.append(Figure(
        "ehl_precalc.png", "EHL precalc: pressure and film in the contact",
        "The elastohydrodynamic solution the gap was built from: pressure (GPa) with film "
        "contours (nm), and both along y = 0"
        + (f"; central film {hc * 1e9:.3g} nm" if hc else "") + "."))


def _history(info: CaseInfo, out: Path, page: Page):
    from ehlfoam.report.charts import draw_history

    if not info.history or "time_s" not in info.history:
        page.summary.append("No history.csv yet: no history chart.")
        return None
    sd = info.spec_dict.get("run") or {}
    _, st = draw_history(info.history, out / "history.png", title=info.name,
                         transit_s=info.geom.transit_time if info.geom else None,
                         tol=float(sd.get("steady_tolerance", 0.01)),
                         length_scale=float(sd.get("transit_length", 10.0)))
    page.figures.append(Figure(
        "history.png", "History: did the run settle?",
        "The quantities the steady-state test tracks, at every write. Shaded: the last "
        "transit window and the test's tolerance around the last value (oil volume relative, "
        "lengths in a)."))
    return st


def _gif(info: CaseInfo, fields, out: Path, page: Page, max_frames: int) -> None:
    from ehlfoam.report.animation import make_gif

    gif = make_gif(info.path, info.geom, fields.structure, out / "transient.gif",
                   max_frames=max_frames)
    if gif is not None:
        page.figures.append(Figure("transient.gif", "The transient (top view at each write)",
                                   "Mid-gap oil fraction at the written times; black: the "
                                   "alpha = 0.5 meniscus."))


def _stop(info: CaseInfo, out: Path, page: Page, written: bool) -> None:
    """The stop's GIF, strip and summary: a thin-film run's kept states, or (``written``) a
    3D run's written times."""
    from ehlfoam.report.stop import make_stop_pictures

    stop = info.spec.stop
    gif, png, recs = make_stop_pictures(info.path, info.geom, stop, info.spec.speed, out,
                                        written)
    if gif is None:
        page.summary.append("No frames of the stop yet ("
                            + ("written times" if written else "DIR/frames/")
                            + "): no stop GIF.")
        return
    every = ("at each write" if written
             else f"a frame every {stop.frame_interval * 1e3:g} ms")
    page.figures.append(Figure(
        "stop.gif", f"The sudden stop ({every})",
        f"The walls slow from {info.spec.speed * 1e3:g} mm/s to rest over "
        f"{stop.duration * 1e3:g} ms from t = {stop.at * 1e3:g} ms; the model's oil as a "
        "mid-gap oil fraction (amber: flooded; pale: air, the bubble's gas inside the "
        "region), the time from the stop, the walls' speed and the metrics' reading on each."))
    page.figures.append(Figure("stop_frames.png", "The stop: six frames",
                               "Before the stop, during it and 0-0.1 s after rest."))
    last = recs[-1]
    enclosed = [r for r in recs if r["cavities"] > 0 and r["from_stop_s"] >= 0]
    page.summary.append(
        f"The stop: {len(recs)} frames; at the end ({last['from_stop_s'] * 1e3:.0f} ms from "
        f"the stop) the region is {last['flooded_length_over_a'] or 0:.2f} a long and "
        f"{last['flooded_width_over_a'] or 0:.2f} a wide with {last['cavities']} enclosed "
        f"gas pocket(s); the last frame with gas enclosed: "
        + (f"{enclosed[-1]['from_stop_s'] * 1e3:.0f} ms from the stop." if enclosed
           else "none after the stop began."))


def read_report_json(case: Path) -> dict | None:
    """A case report's report.json, or None."""
    try:
        return json.loads((Path(case) / REPORT / "report.json").read_text())
    except (OSError, ValueError):
        return None
