"""The one cache-folder rule, in Python and in tools/ensure-env (which asks Python)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from ehlfoam.paths import cache_dir

ROOT = Path(__file__).resolve().parents[1]


def test_cache_dir_rule() -> None:
    assert cache_dir({"EHLFOAM_CACHE": "/c"}) == Path("/c")
    assert cache_dir({"XDG_CACHE_HOME": "/x", "HOME": "/h"}) == Path("/x/ehlfoam")
    assert cache_dir({"HOME": "/h"}) == Path("/h/.cache/ehlfoam")


def test_the_module_prints_the_rule_for_the_shell_and_ensure_env_uses_it() -> None:
    env = {"HOME": "/h", "XDG_CACHE_HOME": "/x", "PATH": "/usr/bin:/bin"}
    out = subprocess.run([sys.executable, "-m", "ehlfoam.paths"], env=env, text=True,
                         capture_output=True, check=True).stdout.strip()
    assert out == "/x/ehlfoam"
    assert '"$VPY" -m ehlfoam.paths' in (ROOT / "tools" / "ensure-env").read_text()
