"""Where ehlfoam keeps what it makes once per machine: the one cache-folder rule.

``$EHLFOAM_CACHE``, else ``${XDG_CACHE_HOME:-$HOME/.cache}/ehlfoam``. It holds the embedded
OpenFOAM runtime (``openfoam-trixie/``) and the EHL precalcs (``precalc/<key>/``).
``tools/ensure-env`` asks this module for the folder (``python -m ehlfoam.paths``), so the
shell and Python cannot disagree.
"""

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


if __name__ == "__main__":
    print(cache_dir())
