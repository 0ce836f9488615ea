"""The per-machine cache folder (:mod:`ehlfoam.paths` has the rule's story and re-exports
:func:`cache_dir`). A module of its own so that the package's import (the kernel cache,
:mod:`ehlfoam._kernel_cache`) reads it without loading :mod:`ehlfoam.paths`, which
``python -m ehlfoam.paths`` runs as a script."""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path

__all__ = ["cache_dir"]


def cache_dir(environ: Mapping[str, str] | None = None) -> Path:
    """The per-machine cache folder (not created here)."""
    env = os.environ if environ is None else environ
    if env.get("EHLFOAM_CACHE"):
        return Path(env["EHLFOAM_CACHE"]).expanduser()
    home = env.get("HOME") or str(Path.home())
    xdg = env.get("XDG_CACHE_HOME") or str(Path(home) / ".cache")
    return Path(xdg).expanduser() / "ehlfoam"
