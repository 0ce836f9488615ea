"""Tests of ehlfoam.foam.runtime and `ehlfoam doctor`, with real OpenFOAM (no mocks).

The configured runtime (EHLFOAM_FOAM, default: the embedded Debian 13 build
installed by tools/ensure-env) must be present: run ./Alltest.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from ehlfoam.foam.runtime import (GOOD_BUILD_MAX_ERROR, BuildCheck, FoamConfigError, FoamError, FoamRuntime, FoamRuntimeMissing, check_build, parse_velocity_error)
from ehlfoam.paths import cache_dir

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def runtime() -> FoamRuntime:
    rt = FoamRuntime.from_environment()
    rt.ensure_present()  # fails (does not skip): ./Alltest installs it
    return rt


@pytest.fixture(scope="session")
def embedded() -> FoamRuntime:
    rt = FoamRuntime.embedded(cache_dir() / "openfoam-trixie")
    if os.environ.get("EHLFOAM_FOAM", "embedded") != "embedded":
        try:
            rt.ensure_present()
        except FoamRuntimeMissing:
            pytest.skip("EHLFOAM_FOAM chooses another OpenFOAM and the embedded one is absent")
    rt.ensure_present()
    return rt


def _ehlfoam(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    exe = Path(sys.executable).parent / "ehlfoam"
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "ehlfoam.cli.main"]
    return subprocess.run([*cmd, *args], capture_output=True, text=True, env=env,
                          cwd=REPO, timeout=120, check=False)


# ------------------------------------------------------------------ real runs
@pytest.mark.openfoam
def test_embedded_runtime_passes_build_check(embedded: FoamRuntime, tmp_path: Path) -> None:
    result = check_build(embedded, workdir=tmp_path)
    assert result.error is not None, result.log[-2000:]
    assert result.error < 1e-2
    assert result.ok
    assert (tmp_path / "pitzDaily" / "log.potentialFoam").is_file()


@pytest.mark.openfoam
def test_configured_runtime_passes_build_check(runtime: FoamRuntime) -> None:
    result = check_build(runtime)
    assert result.ok, result.summary()


@pytest.mark.openfoam
def test_missing_app_raises_clear_error(runtime: FoamRuntime, tmp_path: Path) -> None:
    with pytest.raises(FoamError) as info:
        runtime.run("noSuchFoamApp", [], cwd=tmp_path)
    msg = str(info.value)
    assert "noSuchFoamApp" in msg
    assert str(tmp_path) in msg


@pytest.mark.openfoam
def test_failing_app_reports_app_case_and_log_tail(runtime: FoamRuntime,
                                                   tmp_path: Path) -> None:
    log = tmp_path / "log.blockMesh"
    with pytest.raises(FoamError) as info:  # an empty folder is no case
        runtime.run("blockMesh", [], cwd=tmp_path, log_path=log)
    msg = str(info.value)
    assert "blockMesh failed" in msg and str(tmp_path) in msg and str(log) in msg
    assert "last lines:" in msg
    assert log.read_text().strip(), "the log must hold the application's output"


@pytest.mark.openfoam
def test_failing_app_with_check_false_returns(runtime: FoamRuntime, tmp_path: Path) -> None:
    res = runtime.run("blockMesh", [], cwd=tmp_path, check=False)
    assert res.returncode != 0
    assert res.stdout


@pytest.mark.openfoam
def test_embedded_host_tools_unaffected(embedded: FoamRuntime) -> None:
    # the runtime's library path must never leak into the environment
    env = embedded.env({"PATH": "/usr/bin:/bin"})
    assert "LD_LIBRARY_PATH" not in env
    assert subprocess.run(["ls", "/"], env=env, capture_output=True,
                          check=False).returncode == 0


def test_debian12_native_build_is_refused() -> None:
    """Where the host has Debian 12's own OpenFOAM, the check must refuse it."""
    if not Path("/usr/bin/potentialFoam").exists() or shutil.which("dpkg-query") is None:
        pytest.skip("no host OpenFOAM in /usr/bin")
    version = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "openfoam"],
                             capture_output=True, text=True, check=False).stdout
    if not version.startswith("1912.200626-1"):
        pytest.skip(f"host openfoam {version!r} is not the Debian 12 build")
    native = FoamRuntime(kind="native", project_dir=Path("/usr/share/openfoam"))
    env_path = os.environ.get("PATH", "")
    if shutil.which("potentialFoam", path=env_path) != "/usr/bin/potentialFoam":
        native = FoamRuntime.with_prefix(["env", "PATH=/usr/bin:/bin",
                                          "WM_PROJECT_DIR=/usr/share/openfoam"])
    result = check_build(native)
    assert not result.ok
    assert result.error is not None and result.error > 100  # 1218.37 measured
    assert "BROKEN" in result.summary()


# ----------------------------------------------------------------- the CLI
@pytest.mark.openfoam
def test_doctor_exits_0() -> None:
    res = _ehlfoam("doctor")
    assert res.returncode == 0, res.stdout + res.stderr
    assert "OK: Interpolated velocity error" in res.stdout


def test_doctor_missing_runtime_exits_1(tmp_path: Path) -> None:
    env = {**os.environ, "EHLFOAM_FOAM": "embedded", "EHLFOAM_CACHE": str(tmp_path)}
    res = _ehlfoam("doctor", env=env)
    assert res.returncode == 1
    assert "not installed" in res.stderr and "./Allrun" in res.stderr


def test_doctor_bad_config_exits_2() -> None:
    res = _ehlfoam("doctor", env={**os.environ, "EHLFOAM_FOAM": "bogus"})
    assert res.returncode == 2
    assert "EHLFOAM_FOAM" in res.stderr


def test_cli_bad_subcommand_exits_2() -> None:
    assert _ehlfoam("no-such-command").returncode == 2


# ------------------------------------------------------ construction, parsing
def test_native_command_and_env() -> None:
    rt = FoamRuntime.from_environment({"EHLFOAM_FOAM": "native"})
    assert rt.kind == "native"
    assert rt.command("blockMesh", "-case", Path("/x")) == ["blockMesh", "-case", "/x"]
    assert rt.env({"PATH": "/bin"})["WM_PROJECT_DIR"] == "/usr/share/openfoam"
    rt2 = FoamRuntime.from_environment({"EHLFOAM_FOAM": "native",
                                        "WM_PROJECT_DIR": "/opt/OpenFOAM-v2312"})
    assert rt2.env({})["WM_PROJECT_DIR"] == "/opt/OpenFOAM-v2312"


def test_prefix_command_and_env() -> None:
    rt = FoamRuntime.from_environment({"EHLFOAM_FOAM": "prefix",
                                       "EHLFOAM_FOAM_PREFIX": "/opt/of/run 'a b' --x"})
    assert rt.kind == "prefix"
    assert rt.prefix == ("/opt/of/run", "a b", "--x")
    assert rt.command("interFoam", "-parallel") == ["/opt/of/run", "a b", "--x",
                                                    "interFoam", "-parallel"]
    assert rt.env({"A": "1"}) == {"A": "1"}  # environment left alone
    with pytest.raises(FoamConfigError):
        FoamRuntime.from_environment({"EHLFOAM_FOAM": "prefix"})


def test_embedded_command_construction(tmp_path: Path) -> None:
    env = {"EHLFOAM_CACHE": str(tmp_path / "c"), "HOME": "/nonexistent"}
    rt = FoamRuntime.from_environment(env)
    root = tmp_path / "c" / "openfoam-trixie"
    assert rt.kind == "embedded" and rt.root == root
    cmd = rt.command("blockMesh", "-help")
    assert cmd[0] == str(root / "lib64/ld-linux-x86-64.so.2")
    assert cmd[1] == "--library-path"
    assert cmd[3:] == [str(root / "usr/bin/blockMesh"), "-help"]
    assert rt.env({})["WM_PROJECT_DIR"] == str(root / "usr/share/openfoam")
    with pytest.raises(FoamRuntimeMissing, match="Allrun"):
        rt.run("blockMesh", [], cwd=tmp_path)


@pytest.mark.openfoam
def test_embedded_library_path_is_real(embedded: FoamRuntime) -> None:
    dirs = embedded.library_path()
    assert dirs and all(Path(d).is_dir() for d in dirs)
    assert len({os.path.realpath(d) for d in dirs}) == len(dirs)
    assert str(embedded.root / "usr/lib") in dirs


def test_bad_kind_is_config_error() -> None:
    with pytest.raises(FoamConfigError):
        FoamRuntime.from_environment({"EHLFOAM_FOAM": "docker"})


@pytest.mark.parametrize(
    ("log", "error", "ok"),
    [
        ("Interpolated velocity error = 1218.37\n", 1218.37, False),   # Debian 12 build
        ("Interpolated velocity error = 0.000114117\n", 1.14117e-4, True),  # Debian 13
        ("Interpolated velocity error = 1.14e-4\nEnd\n", 1.14e-4, True),
        ("Interpolated velocity error = nan\n", None, False),
        ("blockMesh output without the line\n", None, False),
    ],
)
def test_build_check_from_log(log: str, error: float | None, ok: bool) -> None:
    check = BuildCheck.from_log(log)
    if error is not None:
        assert check.error == pytest.approx(error)
    assert check.ok is ok
    assert check.summary().startswith("OK" if ok else "BROKEN")
    assert check.threshold == GOOD_BUILD_MAX_ERROR


def test_parse_takes_last_value() -> None:
    text = "Interpolated velocity error = 5\n...\nInterpolated velocity error = 2e-5\n"
    assert parse_velocity_error(text) == pytest.approx(2e-5)
