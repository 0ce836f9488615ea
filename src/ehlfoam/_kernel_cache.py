"""Where numba keeps ehlfoam's compiled kernels: a folder per version of the modules that hold
them, ``<cache>/numba/<hash>`` under the cache folder (:func:`ehlfoam.paths.cache_dir`).

Numba keys a cached kernel on its own file alone ("cache invalidation fails to recognize
changes in symbols defined in a different file", its caching notes), and a kernel carries
the code of the kernels it calls. The thin-film step's pass (``thinfilm/pass_kernels.py``)
calls kernels of three files; cached beside its file, it would go on running their old code
after an update changed them but not it. A folder named by the hash of every module that
uses numba cannot serve old code. ``NUMBA_CACHE_DIR``, where the user sets it, wins."""

from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path

from ehlfoam._cache_root import cache_dir

#: the package's root folder, whose numba modules are hashed
_ROOT = Path(__file__).resolve().parent


def kernel_cache_dir() -> Path:
    """The folder for the compiled kernels of these sources: the hash of every module of the
    package that mentions numba, its path and its bytes."""
    digest = hashlib.sha256()
    for path in sorted(_ROOT.rglob("*.py")):
        text = path.read_bytes()
        if b"numba" in text:
            digest.update(path.relative_to(_ROOT).as_posix().encode() + b"\0" + text + b"\0")
    return cache_dir() / "numba" / digest.hexdigest()[:16]


def use_kernel_cache_dir() -> None:
    """Point numba's cache at :func:`kernel_cache_dir`, for this process (numba's config,
    where numba is loaded already) and the processes it starts (``NUMBA_CACHE_DIR``); nothing
    where ``NUMBA_CACHE_DIR`` is set."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    folder = str(kernel_cache_dir())
    os.environ["NUMBA_CACHE_DIR"] = folder
    if "numba" in sys.modules:
        sys.modules["numba"].config.CACHE_DIR = folder
