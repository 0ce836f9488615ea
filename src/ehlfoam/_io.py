"""Atomic file writes, TOML reading and a huge file's last lines: the bottom of the package,
used by every layer.

Every file is written to a temporary sibling and renamed into place, so a reader (another
process, a resumed batch, a report) never sees a half-written file.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import tempfile
import tomllib
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

from ehlfoam.errors import SpecError

__all__ = ["MAX_SPEC_BYTES", "atomic_write", "atomic_write_json", "atomic_write_text",
           "finite_or_none", "link_tree", "read_toml", "tail_lines"]

#: The largest spec file read [bytes]: a spec is a few kB (a mesh.refine band of 10,000
#: points some 0.3 MB); a larger file is refused by its size, before it is read.
MAX_SPEC_BYTES = 8 << 20


def atomic_write(path: str | os.PathLike[str], write: Callable[[IO[bytes]], Any]) -> None:
    """Write ``path`` through ``write(binary file)`` to a temporary sibling, then rename it."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            write(fh)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def link_tree(src: str | os.PathLike[str], dst: str | os.PathLike[str]) -> None:
    """``dst``, a new folder, with ``src``'s files: hard links where the file system allows
    (no room taken: an EHL precalc is some 14 MB on its finest grid, and every case keeps
    one), copies elsewhere. For files never changed in place: this package writes files by
    renaming a new one over the old (:func:`atomic_write`), which leaves a link's other
    names as they were."""
    def link(a: str, b: str) -> str:
        try:
            os.link(a, b)
        except OSError:
            shutil.copy2(a, b)
        return b

    shutil.copytree(src, dst, copy_function=link)


def finite_or_none(value: Any) -> Any:
    """JSON has no NaN/inf: a blown-up run reports null (recursively in dicts and lists)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: finite_or_none(v) for k, v in value.items()}
    if isinstance(value, list):
        return [finite_or_none(v) for v in value]
    return value


def atomic_write_text(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` (UTF-8) atomically."""
    atomic_write(path, lambda fh: fh.write(text.encode()))


def atomic_write_json(path: str | os.PathLike[str], data: Any) -> None:
    """Write ``data`` as indented JSON atomically; NaN and inf become null."""
    atomic_write_text(path, json.dumps(finite_or_none(data), indent=2, allow_nan=False) + "\n")


def read_toml(path: str | os.PathLike[str]) -> dict[str, Any]:
    """A TOML spec file as a dict; :class:`SpecError` naming the file and what is wrong if it
    is missing, not a file, unreadable, larger than :data:`MAX_SPEC_BYTES`, not UTF-8 text
    (a binary file) or not valid TOML."""
    path = Path(path)
    name = f"spec file = {str(path)!r}"
    try:
        size = path.stat().st_size
        if path.is_dir():
            raise SpecError(f"{name}: is a folder, not a TOML file")
        if size > MAX_SPEC_BYTES:
            raise SpecError(f"{name}: {size / 1e6:.1f} MB is too large for a spec (at most "
                            f"{MAX_SPEC_BYTES / 1e6:.1f} MB); is it the right file?")
        data = path.read_bytes()
    except OSError as err:
        why = os.strerror(err.errno).lower() if err.errno else str(err)
        raise SpecError(f"{name}: {why}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise SpecError(f"{name}: not a text file (byte {err.start} is not UTF-8): a TOML spec "
                        f"is UTF-8 text") from None
    if "\x00" in text:
        raise SpecError(f"{name}: not a text file (it holds NUL bytes): a TOML spec is UTF-8 "
                        f"text")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise SpecError(f"{name}: not valid TOML ({err})") from None


def tail_lines(path: str | os.PathLike[str], n: int | None = None,
               chunk: int = 65536) -> list[str]:
    """The last ``n`` lines (None: all) of the last ``chunk`` bytes of a (possibly huge) text
    file, reading only its end (a long run's solver log is hundreds of MB); the line the
    chunk cuts is dropped; none without the file."""
    try:
        with open(path, "rb") as fh:
            fh.seek(0, os.SEEK_END)
            size = fh.tell()
            fh.seek(max(0, size - chunk))
            data = fh.read()
    except OSError:
        return []
    lines = data.decode("utf-8", "replace").splitlines()
    if size > chunk and lines:
        lines = lines[1:]          # the first line is cut
    return lines if n is None else lines[-n:]
