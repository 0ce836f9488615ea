"""`ehlfoam foam APP [ARGS]`: OpenFOAM applications through the configured runtime (the real
embedded OpenFOAM), their output and exit code passed through, bad names refused with exit 2."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import ehlfoam.foam.runtime as foam_runtime

EHLFOAM = [str(Path(sys.executable).parent / "ehlfoam")]
PITZDAILY = Path(foam_runtime.__file__).parent / "pitzDaily"


def ehlfoam(*args: str, cwd: Path | None = None, env: dict | None = None):
    return subprocess.run([*EHLFOAM, *args], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=120)


@pytest.fixture
def case(tmp_path) -> Path:
    """The pitzDaily check case with two written times, in a folder whose name a shell would
    split ('c;ls': OpenFOAM itself takes no spaces in a case path)."""
    case = tmp_path / "c;ls"
    shutil.copytree(PITZDAILY, case)
    for t in ("0.5", "1"):
        shutil.copytree(case / "0", case / t)
    return case


@pytest.mark.openfoam
def test_an_application_runs_in_the_case_given_by_dash_case_or_in_the_working_folder(case):
    named = ehlfoam("foam", "foamListTimes", "-case", str(case))
    assert named.returncode == 0, named.stderr
    assert named.stdout.split() == ["0.5", "1"]
    here = ehlfoam("foam", "foamListTimes", "-withZero", cwd=case)
    assert here.returncode == 0, here.stderr
    assert here.stdout.split() == ["0", "0.5", "1"]


@pytest.mark.openfoam
def test_the_applications_exit_code_and_message_come_through(tmp_path):
    proc = ehlfoam("foam", "checkMesh", cwd=tmp_path)      # no system/controlDict
    assert proc.returncode == 1
    assert "FOAM FATAL ERROR" in proc.stdout + proc.stderr
    assert "system/controlDict" in proc.stdout + proc.stderr


@pytest.mark.openfoam
@pytest.mark.parametrize("app", ["../bin/checkMesh", "/usr/bin/checkMesh", "check Mesh",
                                 "checkMesh;ls", "$(ls)"])
def test_only_a_plain_application_name_is_run(app, tmp_path):
    proc = ehlfoam("foam", app, cwd=tmp_path)
    assert proc.returncode == 2
    assert f"APP = {app!r} is not a plain application name" in proc.stderr
    assert not any(tmp_path.iterdir())


@pytest.mark.openfoam
def test_an_application_the_runtime_lacks_is_refused_with_the_way_to_list_them():
    near = ehlfoam("foam", "checkMesch")
    assert near.returncode == 2, near.stderr
    assert "did you mean checkMesh" in near.stderr and "ehlfoam foam --list" in near.stderr
    # the runtime's Debian tools are not OpenFOAM applications
    assert ehlfoam("foam", "bash", "-c", "true").returncode == 2
    listed = ehlfoam("foam", "--list")
    assert listed.returncode == 0, listed.stderr
    names = listed.stdout.split()
    assert {"checkMesh", "foamToVTK", "blockMesh", "interFoam"} <= set(names)
    assert "bash" not in names and names == sorted(names)


def test_no_runtime_or_no_application_is_exit_2(tmp_path):
    env = {**os.environ, "EHLFOAM_CACHE": str(tmp_path / "nothing")}
    proc = ehlfoam("foam", "checkMesh", env=env)
    assert proc.returncode == 2 and "is not installed" in proc.stderr
    fake = tmp_path / "bin" / "blockMesh"       # an OpenFOAM on PATH without checkMesh
    fake.parent.mkdir()
    fake.write_text("#!/bin/sh\n")
    fake.chmod(0o755)
    env = {**os.environ, "EHLFOAM_FOAM": "native", "PATH": str(fake.parent)}
    proc = ehlfoam("foam", "checkMesh", env=env)
    assert proc.returncode == 2 and "not on PATH" in proc.stderr
    assert ehlfoam("foam").returncode == 2


def test_a_prefix_runtime_gets_the_arguments_as_a_list(tmp_path):
    """EHLFOAM_FOAM=prefix: PREFIX... APP ARGS, no shell in between (the wrapper here is
    `env`, the application `printf`)."""
    env = {**os.environ, "EHLFOAM_FOAM": "prefix", "EHLFOAM_FOAM_PREFIX": "env EHL_X=1"}
    proc = ehlfoam("foam", "printf", "%s|", "a b", "$EHL_X", ";ls", env=env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == "a b|$EHL_X|;ls|"
