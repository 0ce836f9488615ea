"""Paths: where ehlfoam keeps what it makes once per machine (the one cache-folder rule), and
the checks of a path a user gives it to write into, made before any work.

``$EHLFOAM_CACHE``, else ``${XDG_CACHE_HOME:-$HOME/.cache}/ehlfoam``. It holds the embedded
OpenFOAM runtime (``openfoam-trixie/``), the EHL precalcs (``precalc/<key>/``) and the
compiled numba kernels (``numba/<hash>/``, :mod:`ehlfoam._kernel_cache`).
``tools/ensure-env`` asks this module for the folder (``python -m ehlfoam.paths``), so the
shell and Python cannot disagree.

:func:`check_output` refuses a place that cannot be written (a file where a folder is to be, a
read-only or full disk, no permission); :func:`check_foam_path` a case folder whose path
OpenFOAM cannot take. Both raise :class:`ehlfoam.errors.SpecError` (exit 2 on the command
line) with one line naming the option, the path and why.
"""

from __future__ import annotations

import errno
import os
from pathlib import Path

from ehlfoam._cache_root import cache_dir

__all__ = ["FOAM_PATH_SYNTAX", "MIN_FREE_BYTES", "cache_dir", "check_case_out",
           "check_foam_path", "check_output", "foam_path_problem"]

#: The least free space [bytes] a command needs where it writes: room for at least a little
#: (a small case is some 0.7 MB). A full disk is refused before any work.
MIN_FREE_BYTES = 1 << 20

#: Characters a case folder's path may not hold besides whitespace, control characters and
#: what OpenFOAM's fileName drops (both quotes; fileName::valid in OpenFOAM v1912 refuses
#: whitespace and quotes, and turns a backslash into '/'): the shell's syntax in the case's
#: scripts and OpenFOAM's wildcards, $-expansion and dictionary braces.
FOAM_PATH_SYNTAX = "*?[]{}$;<>|&`"


if __name__ == "__main__":
    print(cache_dir())


def _label(name: str, path: str | os.PathLike) -> str:
    """How a message names the path: ``--out DIR`` (an option), ``CASE DIR`` (an argument) or
    ``out = 'DIR'`` (a keyword of the Python API); a path with a line break or another
    control character quoted, so that the message stays one line."""
    text = str(path)
    if name.startswith("-") or name.isupper():
        return f"{name} {text if text.isprintable() else repr(text)}"
    return f"{name} = {text!r}"


def _error(message: str) -> Exception:
    from ehlfoam.errors import SpecError   # pydantic: loaded only when a check fails

    return SpecError(message)


def _why(err: OSError) -> str:
    """An OS error in words: 'read-only file system', 'permission denied', ..."""
    return os.strerror(err.errno).lower() if err.errno else str(err)


def check_output(path: str | os.PathLike, name: str = "out", *, folder: bool = True,
                 room: int = MIN_FREE_BYTES) -> Path:
    """Refuse, before any work, a place ``path`` that a command cannot write: a file where a
    folder is to be written (``folder``) or a folder where a file is; a file in the way of a
    folder to create; a folder above it in which no file can be made (a read-only file
    system, no permission); a disk with less than ``room`` bytes [B] free. Creates and
    touches nothing. Returns the absolute path. Raises
    :class:`~ehlfoam.errors.SpecError` naming ``name`` (``--out``), the path and why."""
    target = Path(os.path.abspath(path))
    label = _label(name, path)
    if target.is_dir() and not folder:
        raise _error(f"{label}: is a folder (give a file name)")
    if target.exists() and not target.is_dir() and folder:
        raise _error(f"{label}: is a file, not a folder")
    here = target if folder else target.parent
    while not here.exists() and not here.is_symlink():
        here = here.parent
    if not here.is_dir():
        raise _error(f"{label}: {here} is a file, not a folder")
    stat = os.statvfs(here)
    if stat.f_flag & os.ST_RDONLY or not os.access(here, os.W_OK | os.X_OK):
        code = errno.EROFS if stat.f_flag & os.ST_RDONLY else errno.EACCES
        where = "" if here == target else f" ({here})"
        raise _error(f"{label}: {os.strerror(code).lower()}{where}")
    free = stat.f_bavail * stat.f_frsize
    if free < room:
        raise _error(f"{label}: {os.strerror(errno.ENOSPC).lower()}: {free / 1e6:.2f} MB free "
                     f"on {here}, it needs at least {room / 1e6:.1f} MB")
    return target


def _describe(char: str) -> str:
    names = {" ": "a space", "\t": "a tab", "\n": "a line break", "\r": "a carriage return",
             '"': "a double quote (\")", "'": "a single quote (')", "\\": "a backslash (\\)",
             "`": "a backquote (`)"}
    if char in names:
        return names[char]
    if char.isspace() or not char.isprintable():
        return f"the control character U+{ord(char):04X}"
    return f"a {char!r}"


def foam_path_problem(path: str | os.PathLike) -> str | None:
    """Why OpenFOAM cannot take ``path`` as a case folder (its absolute path has whitespace,
    a control character, a quote, a backslash or one of :data:`FOAM_PATH_SYNTAX`), or None."""
    text = os.path.abspath(path)
    for i, char in enumerate(text):
        if char.isspace() or not char.isprintable() or char in "\"'":
            why = ("OpenFOAM (v1912's fileName) drops it from a path, so its tools would "
                   "read another folder")
        elif char == "\\":
            why = "OpenFOAM (v1912's fileName) turns it into '/'"
        elif char in FOAM_PATH_SYNTAX:
            why = ("the shell of the case's scripts and OpenFOAM's wildcards and "
                   "$-expansion read it as syntax")
        else:
            continue
        return (f"OpenFOAM cannot take this path: it has {_describe(char)} at character "
                f"{i + 1} of {text!r}; {why}. Choose a folder whose path has no whitespace, "
                f"quotes, backslash or any of {FOAM_PATH_SYNTAX}")
    return None


def check_foam_path(path: str | os.PathLike, name: str = "out") -> None:
    """Refuse a case folder whose path OpenFOAM cannot take (:func:`foam_path_problem`):
    :class:`~ehlfoam.errors.SpecError` naming ``name``, the path, the character and why."""
    problem = foam_path_problem(path)
    if problem:
        raise _error(f"{_label(name, path)}: {problem}")


def check_case_out(path: str | os.PathLike, name: str = "out", *, writes: bool = True) -> None:
    """A folder to write OpenFOAM cases in (a case's, a batch's): a path OpenFOAM can take
    (:func:`check_foam_path`) and, with ``writes``, one that can be written
    (:func:`check_output`)."""
    check_foam_path(path, name)
    if writes:
        check_output(path, name)
