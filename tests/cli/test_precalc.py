"""`ehlfoam precalc`: the JSON/npz/png output contract, the TOML route, exit codes and bad input.

Exit codes: 0 converged, 3 not converged (outputs written), 2 bad input (nothing written).
"""

from __future__ import annotations

import io
import json
import math
import re
import struct
import subprocess
import sys
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import numpy as np
import pytest

from ehlfoam.errors import SpecError

from ehlfoam.contact.spec import load_spec, make_spec
from ehlfoam.cli.main import main

REPO = Path(__file__).resolve().parents[2]
F, R, E = 20.0, 9.525e-3, 1.11e11
A_REF = (3 * F * R / (2 * E)) ** (1 / 3)  # Hertz radius [m]
PH_REF = 3 * F / (2 * math.pi * A_REF**2)  # Hertz pressure [Pa]
SUMMARY_KEYS = {"a_m": float, "p_hertz_Pa": float, "M": float, "L": float, "hc_m": float,
                "hmin_m": float, "p_max_Pa": float, "h0_m": float, "converged": bool,
                "residual": float, "load_error": float, "grid": list, "wall_s": float}
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def strict_json(path: Path) -> dict:
    def no_constant(name):
        raise ValueError(f"{path.name}: non-standard JSON constant {name}")
    return json.loads(path.read_text(), parse_constant=no_constant)


def moes_M(speed: float, eta0: float) -> float:
    U = eta0 * speed / (E * R)
    W = F / (E * R**2)
    return W * (2 * U) ** -0.75


def run_cli(capsys, *argv) -> tuple[int, str, str]:
    rc = main(["precalc", *map(str, argv)])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


@pytest.fixture(scope="module")
def converged_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("precalc") / "out"
    so, se = io.StringIO(), io.StringIO()
    with redirect_stdout(so), redirect_stderr(se):
        rc = main(["precalc", "--load", "20", "--speed", "0.5", "--temperature", "40",
                   "--grid", "129", "--out", str(out)])
    return rc, so.getvalue(), se.getvalue(), out


# --- converged run: the output contract ----------------------------------------------------------

def test_exit_code_and_files(converged_run):
    rc, stdout, stderr, out = converged_run
    assert rc == 0, stderr
    assert sorted(p.name for p in out.iterdir()) == ["precalc.png", "solution.npz",
                                                     "summary.json"]


def test_summary_contract(converged_run):
    _, _, _, out = converged_run
    s = strict_json(out / "summary.json")
    for key, typ in SUMMARY_KEYS.items():
        assert key in s, key
        assert isinstance(s[key], typ), (key, s[key])
    assert s["grid"] == [129, 129] and all(type(n) is int for n in s["grid"])
    assert s["a_m"] == pytest.approx(1.37e-4, rel=0.01)
    assert s["a_m"] == pytest.approx(A_REF, rel=1e-9)
    assert s["p_hertz_Pa"] == pytest.approx(5.09e8, rel=0.01)
    assert s["p_hertz_Pa"] == pytest.approx(PH_REF, rel=1e-9)
    assert s["M"] == pytest.approx(moes_M(0.5, 21.6e-3), rel=1e-9)
    assert s["converged"] is True
    assert 1e-9 < s["hmin_m"] < s["hc_m"] < 1e-6  # metres: nm..um
    assert s["p_max_Pa"] == pytest.approx(s["p_hertz_Pa"], rel=0.03)
    # h0 = H0 a^2/R with H0 ~ -(1 - hc R/a^2): negative, about minus the Hertz approach a^2/R
    assert -1.2 * A_REF**2 / R < s["h0_m"] < 0
    assert 0 <= s["residual"] < 1e-3 and 0 <= s["load_error"] < 1e-4
    assert 0 < s["wall_s"] < 600


def test_stdout_line_is_the_summary(converged_run):
    _, stdout, _, out = converged_run
    line = json.loads(stdout.strip().splitlines()[-1])
    s = strict_json(out / "summary.json")
    for key in ("M", "L", "hc_m", "hmin_m", "p_max_Pa", "converged", "grid"):
        assert line[key] == s[key]


def test_solution_npz(converged_run):
    _, _, _, out = converged_run
    s = strict_json(out / "summary.json")
    d = np.load(out / "solution.npz")
    x, y, p, h = d["x"], d["y"], d["p"], d["h"]
    nx, ny = s["grid"]
    assert x.shape == (nx,) and y.shape == (ny,) and p.shape == h.shape == (ny, nx)
    assert np.all(np.diff(x) > 0) and np.all(np.diff(y) > 0)
    assert 1.5 * A_REF < x[-1] - x[0] < 20 * A_REF  # metres, a few contact radii
    assert y[0] == pytest.approx(-y[-1], rel=1e-9)
    assert p.max() == pytest.approx(s["p_max_Pa"], rel=1e-12)
    assert h.min() == pytest.approx(s["hmin_m"], rel=1e-12)
    j, i = np.argmin(np.abs(y)), np.argmin(np.abs(x))
    assert h[j, i] == pytest.approx(s["hc_m"], rel=1e-12)
    # the exported pressure carries the load: sum p dx dy = F
    load = p.sum() * (x[1] - x[0]) * (y[1] - y[0])
    assert load == pytest.approx(F, rel=1e-4)


def test_png(converged_run):
    _, _, _, out = converged_run
    data = (out / "precalc.png").read_bytes()
    assert data[:8] == PNG_MAGIC
    assert len(data) > 10_000
    assert data[12:16] == b"IHDR"
    width, height = struct.unpack(">II", data[16:24])
    assert width > 300 and height > 300


# --- TOML route ----------------------------------------------------------------------------------

def test_a_coarse_grid_warns_with_its_error_estimate(tmp_path, capsys):
    """The nominal contact (M 3886) on 257 points a side is some 15 % off its grid-converged
    hc: the summary's estimate is above the warning's limit and stderr warns, naming --grid;
    the default grid (0.8 % off) stays below it."""
    from ehlfoam.contact.solver import GRID_ERROR_WARN

    rc, _, err = run_cli(capsys, "--speed", "0.01", "--grid", "257", "--out", tmp_path / "c")
    s = strict_json(tmp_path / "c" / "summary.json")
    assert rc == 0 and GRID_ERROR_WARN < s["hc_grid_error"] < 0.20
    assert "warning" in err and "--grid" in err and f"{s['hc_grid_error']:.1%}" in err
    rc, _, err = run_cli(capsys, "--speed", "0.01", "--out", tmp_path / "d")
    s = strict_json(tmp_path / "d" / "summary.json")
    assert rc == 0 and s["grid"] == [1025, 1025] and s["hc_grid_error"] < 0.015
    assert "warning" not in err


def test_toml_spec_with_cli_override(tmp_path, capsys):
    spec = tmp_path / "spec.toml"
    spec.write_text("[precalc]\nload = 20.0\nspeed = 0.01\ntemperature = 40.0\ngrid = 129\n")
    out = tmp_path / "out"
    rc, _, err = run_cli(capsys, spec, "--speed", "1.0", "--out", out)
    assert rc == 0, err
    s = strict_json(out / "summary.json")
    assert s["spec"]["speed"] == 1.0  # the option overrides the file
    assert s["spec"]["load"] == 20.0 and s["spec"]["temperature"] == 40.0
    assert s["grid"] == [129, 129]
    assert s["M"] == pytest.approx(moes_M(1.0, 21.6e-3), rel=1e-9)


def test_toml_top_level_keys_and_override(tmp_path):
    spec = tmp_path / "spec.toml"
    spec.write_text('load = 10.0\ntemperature = 25.0\nviscosity = "barus"\ngrid = 257\n')
    s = load_spec(spec, temperature=60.0, grid=None)
    assert s.load == 10.0 and s.viscosity == "barus" and s.grid == 257
    assert s.temperature == 60.0
    assert s.oil().eta0 == pytest.approx(10.2e-3, rel=1e-12)
    assert s.speed == 0.01  # default


# --- not converged ---------------------------------------------------------------------------------

def test_not_converged_exit_3_with_outputs(tmp_path, capsys):
    out = tmp_path / "out"
    rc, _, err = run_cli(capsys, "--load", "20", "--speed", "0.01", "--temperature", "40",
                         "--grid", "65", "--max-cycles", "1", "--out", out)
    assert rc == 3                    # EXIT_NOT_CONVERGED: not the bad-input 2
    assert "not converged" in err.lower()
    s = strict_json(out / "summary.json")
    assert s["converged"] is False
    assert s["failure"]
    assert (out / "solution.npz").is_file() and (out / "precalc.png").is_file()


def test_twophase_cli_exits_cleanly(tmp_path, capsys):
    out = tmp_path / "out"
    rc, _, _ = run_cli(capsys, "--speed", "1.0", "--grid", "65", "--cavitation", "twophase",
                       "--out", out)
    assert rc in (0, 1)
    s = strict_json(out / "summary.json")
    assert "cavity_length_over_a" in s


# --- bad input -------------------------------------------------------------------------------------

BAD = [
    # (argv, parameter, value as given, words of the valid range / choices)
    (["--load", "-1"], "load", "-1", ["greater than 0", "0 < load <= 100000 N"]),
    (["--load", "0"], "load", "0", ["greater than 0"]),
    (["--speed", "0"], "speed", "0", ["greater than 0"]),
    (["--lubricant", "custom", "--eta0", "-0.02", "--alpha", "2e-8", "--rho0", "870"],
     "eta0", "-0.02", ["greater than 0"]),
    (["--lubricant", "FOO"], "lubricant", "FOO", ["HVI60", "custom"]),
    (["--temperature", "80"], "temperature", "80", ["25", "60"]),
    (["--temperature", "500"], "temperature", "500", ["HVI60", "25 to 60 C"]),
    (["--grid", "100"], "grid", "100", ["2**k + 1", "65", "8193"]),
    (["--grid", "33"], "grid", "33", ["2**k + 1", "65", "8193"]),
    (["--grid", "641"], "grid", "641", ["3*2**k + 1", "769"]),
    (["--load", "abc"], "load", "abc", ["not a number", "0 < load <= 100000 N"]),
    (["--viscosity", "sutherland"], "viscosity", "sutherland", ["roelands", "barus"]),
    (["--max-cycles", "0"], "max_cycles", "0", ["greater than or equal to 1"]),
]


def names_value(err: str, name: str, value: str) -> bool:
    """The message names the parameter followed closely by its value ("load = -1.0")."""
    return re.search(rf"\b{re.escape(name)}\W{{1,5}}{re.escape(value)}", err) is not None


@pytest.mark.parametrize("argv, name, value, words", BAD, ids=[" ".join(b[0]) for b in BAD])
def test_bad_input_exit_2_nothing_written(tmp_path, capsys, argv, name, value, words):
    out = tmp_path / "out"
    rc, stdout, err = run_cli(capsys, *argv, "--out", out)
    assert rc == 2
    assert names_value(err, name, value), err
    for w in words:
        assert w in err, (w, err)
    assert stdout == ""
    assert not out.exists()


def test_temperature_error_names_the_oil_range_only(tmp_path, capsys):
    """Beyond the field's generic bounds (-40 to 300 C) the message still gives the oil's own
    table range, not the generic one."""
    rc, _, err = run_cli(capsys, "--temperature", "500", "--out", tmp_path / "out")
    assert rc == 2
    assert "valid range 25 to 60 C" in err and "300" not in err, err


def test_bad_input_leaves_existing_out_untouched(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    rc, _, err = run_cli(capsys, "--speed", "-3", "--out", out)
    assert rc == 2 and names_value(err, "speed", "-3"), err
    assert list(out.iterdir()) == []


def test_toml_unknown_key(tmp_path, capsys):
    spec = tmp_path / "spec.toml"
    spec.write_text("[precalc]\nload = 20.0\nspeeed = 0.01\n")
    out = tmp_path / "out"
    rc, _, err = run_cli(capsys, spec, "--out", out)
    assert rc == 2
    assert "speeed" in err and "unknown" in err
    assert "speed" in err.replace("speeed", "")  # the valid keys are listed
    assert not out.exists()


def test_toml_bad_value(tmp_path, capsys):
    spec = tmp_path / "spec.toml"
    spec.write_text("[precalc]\nload = -5.0\n")
    out = tmp_path / "out"
    rc, _, err = run_cli(capsys, spec, "--out", out)
    assert rc == 2 and names_value(err, "load", "-5"), err
    assert not out.exists()


def test_toml_missing_file(tmp_path, capsys):
    missing = tmp_path / "nope.toml"
    out = tmp_path / "out"
    rc, _, err = run_cli(capsys, missing, "--out", out)
    assert rc == 2
    assert "nope.toml" in err and "no such file" in err
    assert not out.exists()


def test_toml_invalid_syntax(tmp_path, capsys):
    spec = tmp_path / "spec.toml"
    spec.write_text("[precalc\nload = = 3\n")
    out = tmp_path / "out"
    rc, _, err = run_cli(capsys, spec, "--out", out)
    assert rc == 2 and "spec.toml" in err
    assert not out.exists()


def test_make_spec_raises_spec_error():
    with pytest.raises(SpecError, match=r"load = -1"):
        make_spec(load=-1.0)
    with pytest.raises(SpecError, match=r"temperature = 80"):
        make_spec(temperature=80.0)
    with pytest.raises(SpecError, match=r"eta0"):
        make_spec(lubricant="custom", alpha=2e-8, rho0=870.0)  # eta0 missing


def test_console_entry_point_bad_input(tmp_path):
    """The real process: `python -m ehlfoam.cli.main precalc --load -1` exits 2, message on stderr."""
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "ehlfoam.cli.main", "precalc", "--load", "-1",
                           "--out", str(out)], cwd=REPO, capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 2
    assert names_value(proc.stderr, "load", "-1"), proc.stderr
    assert proc.stdout == ""
    assert not out.exists()
