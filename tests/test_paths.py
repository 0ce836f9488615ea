"""The one cache-folder rule, in Python and in tools/ensure-env (which asks Python)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from ehlfoam.errors import SpecError
from ehlfoam.paths import (FOAM_PATH_SYNTAX, cache_dir, check_case_out, check_foam_path,
                           check_output, foam_path_problem)

ROOT = Path(__file__).resolve().parents[1]


def test_cache_dir_rule() -> None:
    assert cache_dir({"EHLFOAM_CACHE": "/c"}) == Path("/c")
    assert cache_dir({"XDG_CACHE_HOME": "/x", "HOME": "/h"}) == Path("/x/ehlfoam")
    assert cache_dir({"HOME": "/h"}) == Path("/h/.cache/ehlfoam")


def test_the_module_prints_the_rule_for_the_shell_and_ensure_env_uses_it() -> None:
    env = {"HOME": "/h", "XDG_CACHE_HOME": "/x", "PATH": "/usr/bin:/bin"}
    run = subprocess.run([sys.executable, "-m", "ehlfoam.paths"], env=env, text=True,
                         capture_output=True, check=True)
    assert run.stdout.strip() == "/x/ehlfoam"
    assert run.stderr == ""        # the package's import did not load the module run
    assert '"$VPY" -m ehlfoam.paths' in (ROOT / "tools" / "ensure-env").read_text()


# ---- the checks of a path given to write into (issue 73) --------------------------------
@pytest.mark.parametrize("char", [" ", "\t", "\n", "\x07", '"', "'", "\\", *FOAM_PATH_SYNTAX])
def test_a_path_openfoam_cannot_take_is_named_with_its_character(tmp_path, char):
    path = tmp_path / f"a{char}b" / "case"
    problem = foam_path_problem(path)
    assert problem and f"character {len(str(tmp_path)) + 3} of" in problem
    assert "\n" not in problem
    with pytest.raises(SpecError, match=r"^--out .*: OpenFOAM cannot take this path"):
        check_foam_path(path, "--out")
    with pytest.raises(SpecError, match=r"^out = .*: OpenFOAM cannot take"):
        check_case_out(path)


@pytest.mark.parametrize("name", ["case-1.5_u0.02+x", "ümlaut", "a~b", "a#b", "(a)", "a,b=c@d%"])
def test_paths_openfoam_takes_pass(tmp_path, name):
    assert foam_path_problem(tmp_path / name) is None
    check_case_out(tmp_path / name, "--out")       # creatable, writable, room: no error
    assert not (tmp_path / name).exists()          # and nothing made


def test_check_output_refuses_files_folders_and_missing_room(tmp_path):
    (tmp_path / "f").write_text("x")
    (tmp_path / "d").mkdir()
    for path, kwargs, words in (
            (tmp_path / "f", {}, "--out .*/f: is a file, not a folder"),
            (tmp_path / "f" / "sub", {}, "--out .*/f/sub: .*/f is a file, not a folder"),
            (tmp_path / "d", {"folder": False}, "is a folder \\(give a file name\\)"),
            (tmp_path / "new", {"room": 1 << 60}, "no space left on device: .* MB free")):
        with pytest.raises(SpecError, match=words):
            check_output(path, "--out", **kwargs)
    assert check_output(tmp_path / "new" / "deeper", "--out") == tmp_path / "new" / "deeper"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d", "f"]


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes anywhere: the tmpfs rows of "
                                              "tests/hostile cover read-only disks")
def test_check_output_refuses_a_folder_without_permission(tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o555)
    with pytest.raises(SpecError, match="--out .*/locked/c: permission denied"):
        check_output(locked / "c", "--out")


def test_what_a_failed_block_made_is_removed_and_nothing_else(tmp_path):
    from ehlfoam.cli.common import removed_on_failure

    kept = tmp_path / "kept"
    kept.mkdir()
    (kept / "thesis.tex").write_text("mine")
    for target in (kept, kept / "thesis.tex"):      # there before: never touched
        with pytest.raises(RuntimeError), removed_on_failure(target):
            (kept / "new").write_text("half")
            raise RuntimeError
        assert (kept / "thesis.tex").read_text() == "mine"
    new = tmp_path / "a" / "b" / "out"
    with pytest.raises(OSError), removed_on_failure(new):
        new.mkdir(parents=True)
        (new / "half.npz").write_bytes(b"12")
        raise OSError(28, "No space left on device")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept"]   # a/b/out and a/b gone
    with removed_on_failure(new):                   # no failure: what it made stays
        new.mkdir(parents=True)
    assert new.is_dir()
