"""numba's compiled kernels are kept in a folder per version of the modules that hold them:
a kernel that calls kernels of other files (the thin-film step's pass) cannot run their old
code after an update (numba keys its cache on the kernel's own file alone)."""

from __future__ import annotations

import os
import subprocess
import sys

from ehlfoam import _kernel_cache


def test_the_folder_follows_the_numba_modules_and_only_them(tmp_path, monkeypatch):
    monkeypatch.setenv("EHLFOAM_CACHE", str(tmp_path / "cache"))
    root = tmp_path / "pkg"
    (root / "sub").mkdir(parents=True)
    callee = root / "sub" / "kernels.py"
    callee.write_text("from numba import njit\n\n@njit(cache=True)\ndef f(x):\n    return x\n")
    (root / "caller.py").write_text("from numba import njit\nfrom pkg.sub.kernels import f\n")
    plain = root / "plain.py"
    plain.write_text("X = 1\n")
    monkeypatch.setattr(_kernel_cache, "_ROOT", root)
    first = _kernel_cache.kernel_cache_dir()
    assert first.parent == tmp_path / "cache" / "numba"
    plain.write_text("X = 2\n")                       # no numba in it: the same folder
    assert _kernel_cache.kernel_cache_dir() == first
    callee.write_text(callee.read_text().replace("return x", "return x + 1"))
    assert _kernel_cache.kernel_cache_dir() != first   # a callee changed: a new folder


def test_importing_the_package_points_numba_there_unless_the_user_chose(tmp_path):
    probe = ("import ehlfoam.thinfilm.kernels, numba, os; "
             "from ehlfoam._kernel_cache import kernel_cache_dir; "
             "print(numba.config.CACHE_DIR); print(kernel_cache_dir())")
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["EHLFOAM_CACHE"] = str(tmp_path / "cache")
    got, want = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True,
                               text=True, check=True).stdout.split()
    assert got == want and want.startswith(str(tmp_path / "cache" / "numba"))
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "mine")
    got, _ = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True,
                            text=True, check=True).stdout.split()
    assert got == str(tmp_path / "mine")
