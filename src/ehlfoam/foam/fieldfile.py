"""A field file a solver wrote, opened only once the solver has finished writing it.

A solver killed while it writes (a crash, a kill at the wall limit, a lost machine) leaves
files cut short in its last time folder, and a running solver's newest folder is still being
written. foamlib's parser does not fail on a numeric list cut short: it backtracks for minutes
(a 24 kB ``alphaPhi0.oil`` cut by a crash ran past 60 s, foamlib 1.7.10), and a monitor, a
report or a restart that reads it hangs. OpenFOAM writes a closing banner last; every reader
of a run's written fields opens them through :func:`field_file`, which looks for it first.
"""

from __future__ import annotations

import os
from pathlib import Path

from foamlib import FoamFieldFile

__all__ = ["IncompleteField", "field_file", "is_complete"]

#: the start of the banner OpenFOAM writes at the end of a field file
CLOSING = b"// ****"
_TAIL = 200


class IncompleteField(ValueError):
    """A field file without its closing banner: cut short, or still being written."""


def is_complete(path: str | os.PathLike[str]) -> bool:
    """OpenFOAM finished writing the file ``path`` (its closing banner is in its last 200
    bytes); False for a file cut short, being written, or missing."""
    try:
        with open(path, "rb") as fh:
            fh.seek(0, os.SEEK_END)
            fh.seek(max(0, fh.tell() - _TAIL))
            return CLOSING in fh.read()
    except OSError:
        return False


def field_file(path: str | os.PathLike[str]) -> FoamFieldFile:
    """The field file ``path``, to read, once it is complete. IncompleteField (a ValueError)
    for a file cut short or still being written; FileNotFoundError without it."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no field file {path}")
    if not is_complete(path):
        raise IncompleteField(f"{path} is incomplete (cut short, or still being written)")
    return FoamFieldFile(path)
