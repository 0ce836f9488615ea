"""The curated benchmarks (bench/*.py), each run as a user runs it, in its --quick size, in a
subprocess: it exits 0, prints its table, writes its record only to --out, nothing into the
tree, and the numbers it measured are the ones its model gives."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def run_bench(name: str, tmp_path: Path, *args: str) -> tuple[str, dict]:
    """Run ``bench/NAME.py --quick --out TMP/NAME.json ARGS`` from the repository root: its
    stdout and its record. Asserts it wrote nothing but the record (into tmp_path) and
    nothing into bench/."""
    def listing() -> list[str]:
        return sorted(p.name for p in (ROOT / "bench").iterdir() if p.name != "__pycache__")

    before = listing()
    out = tmp_path / f"{name}.json"
    proc = subprocess.run([sys.executable, f"bench/{name}.py", "--quick", "--out", str(out),
                           *args], cwd=ROOT, capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert listing() == before
    assert [p.name for p in tmp_path.iterdir()] == [out.name]
    assert f"wrote {out}" in proc.stdout
    return proc.stdout, json.loads(out.read_text())


def table_rows(stdout: str, heading: str) -> list[list[str]]:
    """The words of each row of the printed table whose heading line holds ``heading``: the
    lines after it as long as it (the table pads every row to the heading's width)."""
    lines = stdout.splitlines()
    start = next(i for i, line in enumerate(lines) if heading in line)
    rows = []
    for line in lines[start + 1:]:
        if len(line) != len(lines[start]):
            break
        rows.append(line.split())
    return rows


@pytest.mark.slow
def test_precalc_cost_times_two_grids_that_agree(tmp_path):
    stdout, rec = run_bench("precalc_cost", tmp_path)
    assert [r[0] for r in table_rows(stdout, "N  wall [s]")] == ["129", "257"]
    coarse, fine = rec["rows"]
    assert coarse["converged"] and fine["converged"]
    assert 0 < fine["hmin_nm"] < fine["hc_nm"]
    assert abs(fine["hc_nm"] - coarse["hc_nm"]) < 0.1 * fine["hc_nm"]
    assert fine["cost_ratio"] == pytest.approx(fine["wall_s"] / coarse["wall_s"])
    assert fine["cycles"] > 0 and fine["peak_GiB"] > 0


@pytest.mark.slow
def test_precalc_validation_meets_hertz_and_nvm(tmp_path):
    stdout, rec = run_bench("precalc_validation", tmp_path)
    assert "1. dry limit vs Hertz" in stdout and "2. NVM" in stdout
    (dry,) = rec["dry"]
    assert dry["p_max_over_pH"] == pytest.approx(1.0, abs=1e-3)
    assert dry["max_err_r_lt_095"] < 2e-3
    assert [(r["M"], r["L"]) for r in rec["nvm"]] == [(20, 5), (20, 10), (100, 5), (100, 10)]
    for r in rec["nvm"]:
        assert r["converged"] and 0.9 < r["hc_over_nvm"] < 1.05, r
    assert len(table_rows(stdout, "M   L  grid")) == 4


@pytest.mark.openfoam
def test_case_cost_tabulates_two_levels(tmp_path):
    stdout, rec = run_bench("case_cost", tmp_path)
    coarse, medium = rec["rows"]
    assert [r[0] for r in table_rows(stdout, "level  from")] == ["coarse", "medium"]
    assert medium["cells"] > 1.5 * coarse["cells"]
    assert medium["cells_ratio"] == pytest.approx(medium["cells"] / coarse["cells"])
    for r in rec["rows"]:
        assert r["end_reason"] == "end_time" and r["time_steps"] > 0, r
        assert r["state"] in ("I", "II") and r["flooded_width_over_a"] > 0
        assert r["oil_mass_balance_error"] < 0.05
        assert r["solver_cpu_s"] > 0 and r["wall_s"] > 0


@pytest.mark.openfoam
@pytest.mark.slow
def test_single_phase_check_meets_reynolds(tmp_path):
    stdout, rec = run_bench("single_phase_check", tmp_path)
    (row,) = rec["rows"]
    assert row["status"] == "finished"
    assert row["p_ref_max_Pa"] > 0 and row["p_cfd_max_Pa"] > 0
    assert row["max_error_over_pmax"] < 0.15 and row["rms_error_over_pmax"] < 0.05
    assert table_rows(stdout, "level  cells")[0][0] == "coarse"


@pytest.mark.openfoam
@pytest.mark.slow
def test_batch_cost_runs_the_same_batch_twice_alike_and_reports_it(tmp_path):
    stdout, rec = run_bench("batch_cost", tmp_path)
    serial, local = rec["batches"]
    assert serial["cases"] == local["cases"] == serial["finished"] == local["finished"] == 2
    assert serial["cases_per_hour"] == pytest.approx(3600 * 2 / serial["wall_s"])
    same = rec["compared"]["local vs one at a time"]
    assert same["same_cases_states_steps"] and same["oil_volume_max_rel_diff"] < 1e-9
    case, cold, warm = rec["reports"]
    assert case["wall_s"] > 0 and warm["wall_s"] < cold["wall_s"]
    assert "local vs one at a time: same cases, states and steps: True" in stdout


@pytest.mark.openfoam
def test_strips_lay_films_near_landau_levich_and_hold_a_contact_line(tmp_path):
    stdout, rec = run_bench("strips", tmp_path)
    (films,) = rec["films"]
    assert films["status"] == "ok" and films["steps"] > 0
    assert 0.5 < films["over_landau_levich"] < 3.0          # coarse cells: thicker films
    assert abs(films["x_rear_last_over_a"] - films["x_landau_levich_over_a"]) < 1.0
    (line,) = rec["contact-line"]
    assert line["status"] == "ok"
    assert 4.0 < line["meniscus_over_a"] < 6.3                # dragged towards the reservoir
    assert line["static_angle_deg"] <= line["apparent_angle_deg"] < 90.0
    assert "films behind a receding meniscus" in stdout
    assert "advancing contact line on dry walls" in stdout


def test_ladder_accuracy_measures_each_rung_against_the_finest_at_rest(tmp_path):
    """Two points on the two cheapest thin-film levels: the finer one at rest is each
    point's reference (its own errors zero), the coarser one's errors are its metrics'
    distance from it, and the summary has a row per rung with its cost. Two cases at a
    time (``--jobs 2``): the rows still in point, rung order. A 3D-only option given with
    ``--set-3d`` leaves the thin-film rungs alone (``--set`` would have them refuse it)."""
    stdout, rec = run_bench("ladder_accuracy", tmp_path, "--jobs", "2",
                            "--set-3d", "physics.interface_advection=isoadvector")
    rows = rec["rows"]
    assert rec["jobs"] == 2 and rec["set_3d"] == {"physics.interface_advection": "isoadvector"}
    assert [(r["point"], r["rung"]) for r in rows] == [
        (p, r) for p in rec["points"] for r in ("thin-film-coarse", "thin-film-medium")]
    for r in rows:
        assert r["steady"] and r["reference"] == "thin-film-medium" and r["cpu_s"] > 0
        ref = next(x for x in rows if x["point"] == r["point"] and x["rung"] == r["reference"])
        assert r["err_width"] == pytest.approx(abs(r["width"] - ref["width"]) / ref["width"])
        assert r["state_ok"] == (r["state"] == ref["state"])
        # each metric the mean of the last transit's writes (two a transit: two or three)
        assert r["writes_averaged"] in (2, 3) and r["jitter_width"] >= 0
        assert r["bare_track"] is None        # the thin-film model carries its layers exactly
    assert {r["state"] for r in rows} == {"I", "II"}            # 8 mm/s I, 17 mm/s II
    assert [s["rung"] for s in rec["summary"]] == ["thin-film-coarse", "thin-film-medium"]
    assert rec["summary"][1]["max_width"] == 0 and rec["summary"][1]["cpu_over_reference"] == 1
    assert len(table_rows(stdout, "rung  points")) == 2


def test_ladder_accuracy_joins_earlier_rows_and_takes_a_named_reference(tmp_path):
    """An earlier run's rows on a rung not run here (a dear reference run once) join this
    run's before the errors: the joined rung counts as the finest, so it is the reference
    where it is at rest. Joined: the first run's medium rows relabelled as a finer rung, so
    the medium level's errors against them are nil (the thin-film runs repeat byte for
    byte) and the coarse level's are the first run's."""
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    _, first = run_bench("ladder_accuracy", tmp_path / "a")
    earlier = [r | {"rung": "thin-film-fine"} for r in first["rows"]
               if r["rung"] == "thin-film-medium"]
    join = tmp_path / "earlier.json"
    join.write_text(json.dumps({"rows": earlier}))
    _, rec = run_bench("ladder_accuracy", tmp_path / "b", "--join", str(join))
    assert rec["rungs"] == ["thin-film-coarse", "thin-film-medium", "thin-film-fine"]
    rows = {(r["point"], r["rung"]): r for r in rec["rows"]}
    assert len(rows) == 6 and all(r["reference"] == "thin-film-fine" for r in rows.values())
    before = {(r["point"], r["rung"]): r for r in first["rows"]}
    for point in rec["points"]:
        assert rows[point, "thin-film-fine"]["joined"] == str(join)
        assert rows[point, "thin-film-medium"]["err_width"] == 0
        assert rows[point, "thin-film-coarse"]["err_width"] == pytest.approx(
            before[point, "thin-film-coarse"]["err_width"], rel=1e-12)
    # --reference: that rung's rows are the references, at rest or not
    (tmp_path / "c").mkdir()
    _, rec = run_bench("ladder_accuracy", tmp_path / "c", "--join", str(join),
                       "--reference", "thin-film-coarse")
    assert rec["reference"] == "thin-film-coarse"
    rows = {(r["point"], r["rung"]): r for r in rec["rows"]}
    for point in rec["points"]:
        coarse, medium = rows[point, "thin-film-coarse"], rows[point, "thin-film-medium"]
        assert medium["reference"] == "thin-film-coarse" and coarse["err_width"] == 0
        assert medium["err_width"] == pytest.approx(
            abs(medium["width"] - coarse["width"]) / coarse["width"])
    for bad, words in ((["--join", str(tmp_path / "none.json")], "none.json"),
                       (["--reference", "fine"], "--reference fine")):
        proc = subprocess.run([sys.executable, "bench/ladder_accuracy.py", "--quick", *bad,
                               "--work", str(tmp_path / "w")],
                              cwd=ROOT, capture_output=True, text=True, timeout=120)
        assert proc.returncode == 2 and words in proc.stderr, proc.stderr
        assert not (tmp_path / "w").exists()


def test_ladder_accuracy_refuses_a_bad_spec_option_before_any_run(tmp_path):
    proc = subprocess.run([sys.executable, "bench/ladder_accuracy.py", "--quick", "--set",
                           "thin_film.courant=7", "--work", str(tmp_path / "w")],
                          cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and "thin_film.courant = 7" in proc.stderr, proc.stderr
    assert not (tmp_path / "w").exists()


@pytest.mark.parametrize("option", ["--set", "--set-3d"])
def test_ladder_accuracy_refuses_a_bad_3d_option_before_any_run(tmp_path, option):
    """``--set`` reaches the thin-film rung too, which refuses a 3D-only key; a bad value
    under ``--set-3d`` is refused on the 3D rung. Both before any run."""
    value = "isoadvector" if option == "--set" else "vof"
    proc = subprocess.run([sys.executable, "bench/ladder_accuracy.py", "--rungs",
                           "thin-film-medium", "coarse", "--points", "0", option,
                           f"physics.interface_advection={value}", "--work",
                           str(tmp_path / "w")],
                          cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and "interface_advection" in proc.stderr, proc.stderr
    assert not (tmp_path / "w").exists()


@pytest.mark.slow
def test_starved_film_follows_the_starvation_relations(tmp_path):
    stdout, rec = run_bench("starved_film", tmp_path)
    assert "Chevalier" in stdout and "Hamrock-Dowson" in stdout
    (point,) = rec["points"]
    layer, men = point["layer"], point["meniscus"]
    assert [r[0] for r in table_rows(stdout, "h_oil/hc,ff")] == ["50.00", "1.00", "0.50", "0.20"]
    assert all(r["converged"] for r in layer + men)
    ratios = [r["hc_ratio"] for r in layer]
    assert ratios == sorted(ratios, reverse=True)  # thinner layer, thinner film
    assert ratios[0] == pytest.approx(1.0, abs=3e-3)  # a thick layer floods the contact
    assert all(r["hc_ratio"] <= r["r"] * (1 + 1e-9) for r in layer)  # hc <= h_oil
    assert point["layer_mass_ok"]
    assert point["worst_chevalier"] < 0.02 and 1.0 < point["gamma_fit"] < 10.0
    assert point["worst_hamrock_dowson"] < 0.06
    assert 1.0 < point["onset_m"] < point["m_star"] + 0.5


@pytest.mark.slow
def test_stability_maps_classify_every_point_and_compare_the_levels(tmp_path, tmp_path_factory):
    maps = tmp_path_factory.mktemp("maps")
    stdout, rec = run_bench("stability_maps", tmp_path, "--maps", str(maps))
    rows = rec["rows"]
    assert sorted((r["rung"], r["speed_m_s"]) for r in rows) == [
        ("thin-film coarse", 0.045), ("thin-film coarse", 0.1),
        ("thin-film medium", 0.045), ("thin-film medium", 0.1)]
    medium = {r["speed_m_s"]: r for r in rows if r["rung"] == "thin-film medium"}
    for r in rows:
        assert r["status"] == "finished" and r["outcome"] == f"rest {r['state']}", r
        assert r["cost_s"] > 0 and r["transits"] > 0 and r["failure_reason"] == ""
        if r["rung"] == "thin-film coarse":   # each level against the next finer one
            other = medium[r["speed_m_s"]]
            assert r["vs"] == "thin-film medium" and r["vs_state"] == other["state"]
            assert r["flips"] == (r["state"] != other["state"])
            assert r["d_flooded_width_over_a"] == pytest.approx(
                r["flooded_width_over_a"] - other["flooded_width_over_a"])
            assert r["cells"] < other["cells"]
    with open(maps / "stability.csv", newline="") as fh:
        assert len(list(csv.DictReader(fh))) == len(rows)
    assert sorted(p.name for p in maps.glob("*.png")) == ["stability_tf_coarse.png",
                                                          "stability_tf_medium.png"]
    (coarse, _) = rec["summary"]
    assert coarse["points"] == 2 and coarse["rest I"] + coarse["rest II"] == 2
    assert table_rows(stdout, "rung  points")[0][:3] == ["thin-film", "coarse", "2"]


@pytest.mark.openfoam
def test_static_meniscus_runs_a_resting_puddle_and_holds_it(tmp_path):
    """The spurious-current benchmark's quick size: the 5 a puddle for 5 ms runs to its end,
    its oil volume holds and its meniscus stays within a cell of where it started; the
    gap-averaged speeds it prints are positive (the meniscus is still curving)."""
    stdout, rec = run_bench("static_meniscus", tmp_path)
    (row,) = rec["rows"]
    assert row["status"] == "finished" and row["end_time_ms"] == pytest.approx(5.0)
    assert abs(row["volume_change"]) < 1e-3 and abs(row["drift_a"]) < 0.2
    assert 0.0 < row["settled_over_u"] <= row["late_over_u"]
    assert table_rows(stdout, "configuration")[0][:3] == ["default", "step,", "5"]
