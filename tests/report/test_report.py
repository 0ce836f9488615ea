"""Reports of a case and of a batch, on a tiny real case (real OpenFOAM, a few steps).

The pictures are checked for content: the meniscus line lies in the PNG where the metrics
put it, oil and air pixels have the oil and air colours, the side view's gap grows away
from the contact. Failed, running and never-run cases get a page that says so. The pages
are opened in headless Chromium, which must load every image.
"""

from __future__ import annotations

import csv
import fcntl
import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from ehlfoam.spec.case import make_case_spec
from ehlfoam.case.geometry import load_geometry
from ehlfoam.case.writer import write_case
from ehlfoam.run.fields import time_folders
from ehlfoam.cli.main import main
from ehlfoam.report import report, report_batch, report_case
from ehlfoam.report import units
from ehlfoam.report.charts import bubble_relation_x, fit_bubble_relation
from ehlfoam.report.fields import load_fields
from ehlfoam.report.side_view import cut_at_axis
from ehlfoam.report.style import AIR_RGB, OIL_RGB
from ehlfoam.batch.regime import write_regime
from ehlfoam.run.monitor import run_case
from tests.tiny import SMALL

ROOT = Path(__file__).resolve().parents[2]

SPEC = {**SMALL, "name": "report-test"}
LOG_MARKER = "FOAM FATAL ERROR: report-test marker 0xBEEF"


@pytest.fixture(scope="module")
def finished_case(tmp_path_factory) -> Path:
    case = tmp_path_factory.mktemp("report") / "finished"
    write_case(make_case_spec(SPEC), case)
    m = run_case(case, wall_limit=120)
    assert m["status"] == "finished", m
    return case


@pytest.fixture(scope="module")
def case_report(finished_case) -> tuple[Path, float]:
    start = time.perf_counter()
    index = report_case(finished_case)
    return index, time.perf_counter() - start


def _copy(case: Path, dst: Path) -> Path:
    shutil.copytree(case, dst, ignore=shutil.ignore_patterns("report"))
    return dst


def _failed_copy(case: Path, dst: Path) -> Path:
    """The finished case made into a failed one: status failed, a log ending in an error."""
    _copy(case, dst)
    (dst / "metrics.json").write_text(json.dumps(
        {"status": "failed", "end_reason": "diverged", "cells": 1}))
    with open(dst / "log.interFoam", "a") as fh:
        fh.write("\nTime = 0.00123\n" + LOG_MARKER + "\n")
    return dst


def _png(path: Path) -> np.ndarray:
    return np.asarray(Image.open(path).convert("RGB"), dtype=float)


# ------------------------------------------------------------------ the case report
@pytest.mark.openfoam
def test_case_report_has_every_part(case_report, finished_case):
    index, _ = case_report
    assert index == finished_case / "report" / "index.html"
    html = index.read_text()
    for name in ("top_view.png", "side_view.png", "pressure.png", "ehl_precalc.png",
                 "history.png", "thumb.png"):
        assert (index.parent / name).stat().st_size > 5000, name
    for src in re.findall(r'<img src="([^"]+)"', html):
        assert (index.parent / src).is_file(), src
    info = json.loads((index.parent / "report.json").read_text())
    assert info["problems"] == [] and info["status"] == "finished"
    assert "State I" in html or "State II" in html
    # the metrics table: every key with its unit
    metrics = json.loads((finished_case / "metrics.json").read_text())
    for key in ("oil_volume_m3", "inlet_meniscus_distance_over_a", "wall_s", "cells"):
        assert f"<td>{key}</td>" in html, key
    unlabelled = [k for k in metrics if k not in units.METRICS and k not in units.METRICS_HIDDEN]
    assert unlabelled == [], unlabelled                    # every key a label and a unit
    assert "<td>nl</td>" in html and "<td>mm/s</td>" in html
    assert f"{metrics['cells']:,}" in html
    assert "interFoam" in html and "OPENFOAM=" in html            # solver and build
    # (its cost is timed elsewhere, not asserted here)


@pytest.mark.openfoam
def test_top_view_meniscus_lies_where_the_metrics_say(case_report, finished_case):
    """Along y = 0 upstream of the island the PNG's black meniscus line is at
    x = -(1 + inlet_meniscus_distance_over_a) a, within two pixels."""
    index, _ = case_report
    metrics = json.loads((finished_case / "metrics.json").read_text())
    d = metrics["inlet_meniscus_distance_over_a"]
    assert d is not None and not metrics["inlet_meniscus_at_rim"], metrics
    geom = load_geometry(finished_case)
    x_expected = -(1.0 + d) * geom.a
    meta = json.loads((index.parent / "top_view.json").read_text())
    sx, ox, sy, oy = meta["pixel_from_mm"]
    img = _png(index.parent / "top_view.png")
    row = int(round(oy))                                  # y = 0
    col_rim = int(ox + sx * (-geom.island_radius - 0.1 * geom.a) * 1e3)
    col_end = int(ox + sx * (geom.x_min + 0.2 * geom.a) * 1e3)
    band = img[row - 1:row + 2, col_end:col_rim].min(axis=0)   # 3 rows: line width
    dark = np.flatnonzero(band.max(axis=1) < 80)               # black, not brown oil
    assert dark.size, "no meniscus line on y = 0 upstream of the island"
    col = col_end + dark[-1]                                   # the one nearest the island
    x_png = (col - ox) / sx * 1e-3
    assert abs(x_png - x_expected) <= 2.0 / sx * 1e-3, (x_png / geom.a, x_expected / geom.a)


@pytest.mark.openfoam
def test_top_view_oil_and_air_colours(case_report, finished_case):
    """A pixel inside the puddle (oil in the raster) has the oil colour, one in the far
    corner (air) the air colour."""
    index, _ = case_report
    geom = load_geometry(finished_case)
    fields = load_fields(finished_case, geom)
    r = fields.raster
    meta = json.loads((index.parent / "top_view.json").read_text())
    sx, ox, sy, oy = meta["pixel_from_mm"]
    img = _png(index.parent / "top_view.png")

    def check(x, y, rgb, alpha_range):
        i, j = np.argmin(np.abs(r.y - y)), np.argmin(np.abs(r.x - x))
        window = r.alpha[i - 2:i + 3, j - 2:j + 3]
        assert alpha_range[0] <= np.nanmin(window) and np.nanmax(window) <= alpha_range[1], \
            f"raster not {rgb} around ({x / geom.a:.2f} a, {y / geom.a:.2f} a)"
        col, row = ox + sx * x * 1e3, oy - sy * y * 1e3
        pixel = img[int(round(row)) - 1:int(round(row)) + 2,
                    int(round(col)) - 1:int(round(col)) + 2].reshape(-1, 3).mean(axis=0)
        assert np.allclose(pixel, np.array(rgb) * 255, atol=12), (pixel, rgb)

    check(-(geom.island_radius + 0.4 * geom.a), 0.6 * geom.a, OIL_RGB, (0.99, 1.0))
    check(geom.x_max - 0.6 * geom.a, geom.y_max - 1.5 * geom.a, AIR_RGB, (0.0, 0.01))


@pytest.mark.openfoam
def test_side_view_gap_grows_away_from_the_contact(finished_case):
    geom = load_geometry(finished_case)
    cut = cut_at_axis(load_fields(finished_case, geom))
    x, h = cut.profile_x, cut.profile_h
    up, down = x < -geom.island_radius, x > geom.island_radius
    assert up.sum() > 3 and down.sum() > 3
    assert np.all(np.diff(h[up]) < 0) and np.all(np.diff(h[down]) > 0)
    # the gap at the island rim plus the rigid sphere's (x^2 - R_i^2) / 2R
    sphere = geom.island_gap + (x**2 - geom.island_radius**2) / (2 * geom.radius)
    assert h[up | down] == pytest.approx(sphere[up | down], rel=0.15)
    assert np.all((cut.alpha >= 0) & (cut.alpha <= 1)) and len(cut.triangles) > 50


@pytest.mark.openfoam
def test_failed_case_says_so_with_the_log_tail(finished_case, tmp_path):
    case = _failed_copy(finished_case, tmp_path / "failed")
    index = report_case(case, animate=False)
    html = index.read_text()
    assert 'class="banner fail"' in html and "FAILED" in html and "diverged" in html
    assert LOG_MARKER in html
    assert 'href="../log.interFoam"' in html
    assert (index.parent / "top_view.png").exists()          # whatever exists is still shown
    thumb = _png(index.parent / "thumb.png")
    assert thumb[5, 5, 0] > 150 and thumb[5, 5, 1] < 80        # the red FAILED stamp


@pytest.mark.openfoam
def test_running_and_never_run_cases(finished_case, tmp_path):
    running = _copy(finished_case, tmp_path / "running")
    (running / "metrics.json").write_text(json.dumps({"status": "running", "cells": 1}))
    with open(running / "ehlfoam" / "run.lock", "a") as lock:   # a live run holds it
        fcntl.flock(lock, fcntl.LOCK_EX)
        html = report_case(running, animate=False).read_text()
    assert "Status: running" in html and "still going" in html
    assert "Last lines of the solver log" in html
    # no process holds the lock: the run was killed and left metrics.json running
    html = report_case(running, animate=False).read_text()
    assert "Status: interrupted" in html and "monitor_killed" in html
    settled = json.loads((running / "metrics.json").read_text())   # and metrics.json says so
    assert (settled["status"], settled["end_reason"]) == ("interrupted", "monitor_killed")

    fresh = _copy(finished_case, tmp_path / "fresh")
    for _, folder in time_folders(fresh):
        shutil.rmtree(folder)
    for name in ("metrics.json", "history.csv", "log.interFoam"):
        (fresh / name).unlink()
    html = report_case(fresh).read_text()
    assert "not been run" in html and "No fields were written yet" in html
    assert "What could not be shown" not in html


@pytest.mark.openfoam
def test_broken_case_reports_problems_instead_of_crashing(finished_case, tmp_path):
    case = _copy(finished_case, tmp_path / "broken")
    last = time_folders(case)[-1][1]
    (last / "alpha.oil").write_text("garbage")            # incomplete: an older time is used
    (case / "history.csv").write_text("time_s,oil_volume_m3\n0.001,oops\n")
    (case / "precalc" / "solution.npz").write_bytes(b"not a zip")
    index = report_case(case, animate=False)
    html = index.read_text()
    assert "top_view.png" in html
    info = json.loads((index.parent / "report.json").read_text())
    assert info["fields_time_s"] < float(last.name)


@pytest.mark.openfoam
def test_report_detects_case_and_batch_and_bad_input(finished_case, tmp_path):
    with pytest.raises(FileNotFoundError):
        report(tmp_path / "nowhere")
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="neither a case"):
        report(tmp_path / "empty")
    assert main(["report", str(tmp_path / "empty")]) == 2
    assert main(["report", str(tmp_path / "nowhere")]) == 2


@pytest.mark.openfoam
def test_cli_module_off_screen(finished_case, tmp_path):
    """``python -m ehlfoam report CASE`` in a process with no display at all."""
    case = _copy(finished_case, tmp_path / "cli")
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    proc = subprocess.run([sys.executable, "-m", "ehlfoam", "report", str(case),
                           "--no-gif"], cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip().split()[0] == str(case / "report" / "index.html")


# ------------------------------------------------------------------ the batch report
@pytest.fixture(scope="module")
def batch(finished_case, case_report, tmp_path_factory) -> Path:
    """cases/ok (its report already made: reused), cases/bad (failed), a pending case."""
    root = tmp_path_factory.mktemp("batch") / "b1"
    ok = root / "cases" / "ok"
    shutil.copytree(finished_case, ok)                       # with its report/
    _failed_copy(finished_case, root / "cases" / "bad")
    m = json.loads((ok / "metrics.json").read_text())
    columns = ["case_id", "contact.speed", "contact.temperature", "contact.load",
               "supply.mode", "supply.disc_layer", "supply.ball_layer", "status", "end_reason",
               "reason", "state", "wall_s", "cells", "case_dir", "log",
               "inlet_meniscus_distance_over_a", "wake_gas_length_over_a"]
    rows = [{"case_id": "ok", "contact.speed": 0.02, "contact.temperature": 40,
             "contact.load": 20, "supply.mode": "layers", "supply.disc_layer": 3e-6,
             "supply.ball_layer": 3e-6,
             "status": "finished", "end_reason": "end_time", "reason": "", "state": m["state"],
             "wall_s": m["wall_s"], "cells": m["cells"], "case_dir": "cases/ok",
             "log": "cases/ok/log.interFoam",
             "inlet_meniscus_distance_over_a": m["inlet_meniscus_distance_over_a"],
             "wake_gas_length_over_a": m["wake_gas_length_over_a"]},
            {"case_id": "bad", "contact.speed": 0.04, "contact.temperature": 40,
             "contact.load": 20, "supply.mode": "layers", "supply.disc_layer": 3e-6,
             "supply.ball_layer": 3e-6, "status": "failed",
             "end_reason": "diverged", "reason": "solver diverged: time step collapsed",
             "state": "", "wall_s": 3.0, "cells": m["cells"], "case_dir": "cases/bad",
             "log": "cases/bad/log.interFoam"}]
    with open(root / "results.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=columns)
        writer.writeheader()
        writer.writerows(rows)
    plan = [{"id": "ok", "params": {"contact.speed": 0.02}, "ramp": None},
            {"id": "bad", "params": {"contact.speed": 0.04}, "ramp": None},
            {"id": "later", "params": {"contact.speed": 0.06}, "ramp": None}]
    (root / "plan.json").write_text(json.dumps(plan))
    line = [{"case_id": f"u{u}", "contact.speed": u * 1e-3, "contact.temperature": 40.0,
             "contact.load": 20.0, "supply.mode": "layers", "supply.disc_layer": 1e-6,
             "supply.ball_layer": 1e-6, "mesh.resolution": "coarse", "status": "finished",
             "state": state} for u, state in ((10, "I"), (15, "II"))]
    write_regime(root, line)
    return root


@pytest.mark.openfoam
def test_batch_report_index_failures_and_reuse(batch):
    before = (batch / "cases" / "ok" / "report" / "report.json").stat().st_mtime
    index = report_batch(batch, jobs=1)
    html = index.read_text()
    made = json.loads((index.parent / "report.json").read_text())
    assert made["case_reports_made"] == 1                    # bad only; ok reused
    assert (batch / "cases" / "ok" / "report" / "report.json").stat().st_mtime == before
    assert 'src="../cases/ok/report/thumb.png"' in html
    assert 'href="../cases/ok/report/index.html"' in html
    # failures: reason and a working relative link to the log
    assert "solver diverged: time step collapsed" in html
    assert 'href="../cases/bad/log.interFoam"' in html
    assert (index.parent / "../cases/bad/log.interFoam").resolve().is_file()
    assert LOG_MARKER in html                                  # its last log line
    assert "later" in html and "pending" in html
    assert "T 40 C, F 20 N, 1um, coarse: I -&gt; II at 12.5 +- 2.5 mm/s" in html  # regime.json
    assert 'src="regime_speed_supply.png"' in html and "u [mm/s]" in html
    assert "3 / 3" in html                                      # the layers in um
    assert "not enough points" in html                          # one state I point only
    for src in re.findall(r'<img src="([^"]+)"', html):
        assert (index.parent / src).resolve().is_file(), src


def test_bubble_relation_fit_recovers_constants():
    eta, rho, sigma, dp, a = 21.6e-3, 870.0, 0.030, 1.013e5, 1.37e-4
    u = np.array([0.005, 0.01, 0.02, 0.04])
    x = np.array([bubble_relation_x(v, a, eta, rho, sigma, dp) for v in u])
    assert x[1] / x[0] == pytest.approx(2.0)                    # X is proportional to u
    # Re, Ca, We in the thesis's ranges at 10 mm/s
    re_, ca, we = rho * 0.01 * a / eta, dp / (0.5 * rho * 0.01**2), rho * 0.01**2 * a / sigma
    assert 1e-3 < re_ < 1e-1 and 1e5 < ca < 1e8 and 1e-6 < we < 1e-3
    fit = fit_bubble_relation(x, 3.0e5 * x + 0.4, 40.0)
    assert fit.c1 == pytest.approx(3.0e5) and fit.c2 == pytest.approx(0.4)
    assert fit_bubble_relation(x[:1], x[:1], 40.0).reason == "not enough points"


# ------------------------------------------------------------------ in a browser
def _chromium() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    if os.environ.get("EHLFOAM_NO_BROWSER") == "1":
        pytest.skip("EHLFOAM_NO_BROWSER=1: no browser test")
    pytest.fail("headless Chromium is needed for the report test: apt-get install chromium "
                "(./Alltest installs it), or set EHLFOAM_NO_BROWSER=1 to skip")


def _loaded_images(page: Path, tmp_path: Path) -> tuple[int, int]:
    """(images loaded, images on the page) as the page's own script counted them in
    headless Chromium."""
    if os.environ.get("EHLFOAM_NO_BROWSER") == "1":
        pytest.skip("EHLFOAM_NO_BROWSER=1: no browser test")
    proc = subprocess.run(
        [_chromium(), "--headless", "--no-sandbox", "--disable-gpu",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--no-first-run", f"--user-data-dir={tmp_path / 'chromium'}",
         "--virtual-time-budget=5000", "--dump-dom", page.resolve().as_uri()],
        capture_output=True, text=True, timeout=120)
    body = re.search(r"<body[^>]*>", proc.stdout)
    assert body, proc.stderr[-2000:]
    loaded = re.search(r'data-images-loaded="(\d+)"', body.group(0))
    total = re.search(r'data-images-total="(\d+)"', body.group(0))
    assert loaded and total, f"the page's image counter did not run: {body.group(0)}"
    return int(loaded.group(1)), int(total.group(1))


@pytest.mark.openfoam
def test_pages_load_every_image_in_chromium(case_report, batch, tmp_path):
    index, _ = case_report
    loaded, total = _loaded_images(index, tmp_path)
    assert total >= 6 and loaded == total
    batch_index = batch / "report" / "index.html"
    if not batch_index.exists():
        report_batch(batch, jobs=1)
    loaded, total = _loaded_images(batch_index, tmp_path)
    assert total >= 3 and loaded == total


@pytest.mark.openfoam
def test_browser_check_sees_a_missing_image(case_report, tmp_path):
    """The counter is not a formality: a page with a broken link counts one image short."""
    index, _ = case_report
    broken = index.parent / "broken.html"
    broken.write_text(index.read_text().replace('src="side_view.png"', 'src="nothing.png"'))
    try:
        loaded, total = _loaded_images(broken, tmp_path)
    finally:
        broken.unlink()
    assert loaded == total - 1


@pytest.mark.openfoam
def test_batch_report_reads_the_mesh_convergence_of_three_levels(finished_case, case_report,
                                                                  tmp_path):
    """Three copies of a real case, filed as coarse / medium / fine with far-field cells of
    0.8 / 0.55 / 0.38 a, their histories rewritten: a width that follows 12 + 3 h^2 reads as
    converging at order 2 towards 12 a; an inlet meniscus whose level means differ by less
    than its own jitter reads as within noise. A fourth case at another speed is left out."""
    from ehlfoam.report.batch_tables import convergence_groups

    root = tmp_path / "conv"
    sizes = {"coarse": 0.8, "medium": 0.55, "fine": 0.38}
    inlet = {"coarse": 6.64, "medium": 6.57, "fine": 6.45}
    rows = []
    for level, h in sizes.items():
        case = _copy(finished_case, root / "cases" / level)
        spec = json.loads((case / "ehlfoam" / "spec.json").read_text())
        spec["mesh"]["size_far"] = h
        (case / "ehlfoam" / "spec.json").write_text(json.dumps(spec))
        with open(case / "history.csv", newline="") as fh:
            hist = list(csv.DictReader(fh))
        for i, r in enumerate(hist):
            r["flooded_width_over_a"] = 12.0 + 3.0 * h ** 2
            r["inlet_meniscus_distance_over_a"] = inlet[level] + (0.2 if i % 2 else -0.2)
        with open(case / "history.csv", "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(hist[0]))
            w.writeheader()
            w.writerows(hist)
        rows.append({"case_id": level, "contact.speed": 0.02, "contact.temperature": 40,
                     "contact.load": 20, "supply.mode": "layers", "supply.disc_layer": 3e-6,
                     "supply.ball_layer": 3e-6, "mesh.resolution": level,
                     "status": "finished", "case_dir": f"cases/{level}"})
    _copy(finished_case, root / "cases" / "other")
    rows.append({**rows[0], "case_id": "other", "contact.speed": 0.04,
                 "case_dir": "cases/other"})
    with open(root / "results.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    # no case report to remake: the copies keep theirs, made after their results
    for level in [*sizes, "other"]:
        shutil.copytree(finished_case / "report", root / "cases" / level / "report",
                        dirs_exist_ok=True)
        for f in (root / "cases" / level / "report").iterdir():
            os.utime(f)

    read = report_batch(root, jobs=1, animate=False)
    groups = convergence_groups(
        [{**r, "_folder": root / r["case_dir"]} for r in rows])
    assert [[p.name for p in folders] for _, folders in groups] == [["coarse", "medium", "fine"]]
    html = read.read_text()
    assert "Mesh convergence over the three levels" in html
    assert "monotone, order 2.00: extrapolated 12 a" in html
    assert "within noise" in html
    assert json.loads((read.parent / "report.json").read_text())["case_reports_made"] == 0
