"""What the subcommands share: the exit codes (one table: :data:`EXIT_CODES`), a subcommand's
parser (its help ends with an example), number types for options, notices printed one line
each, the check of a case folder given to a command (:func:`check_case`) and the removal of
what a failed command made (:func:`removed_on_failure`)."""

from __future__ import annotations

import argparse
import math
import os
import shutil
import sys
import textwrap
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ehlfoam.notices import Notice

#: the command did what it was asked
EXIT_OK = 0
#: the work ran and failed: a run, a case of a batch, a build check, a report
EXIT_FAILURE = 1
#: bad input, refused before any work, nothing written
EXIT_BAD_INPUT = 2
#: the EHL precalc did not converge (its outputs are written, ``converged: false``)
EXIT_NOT_CONVERGED = 3
#: a bug in ehlfoam (sysexits' EX_SOFTWARE): one line, ``ehlfoam --debug`` shows the traceback
EXIT_INTERNAL = 70
#: Ctrl-C or SIGTERM (128 + SIGINT)
EXIT_INTERRUPTED = 130

#: The exit codes of every command but ``ehlfoam foam`` (which exits with its application's
#: code): (code, name, what it means). ``ehlfoam --help``, docs/cli.md and the tests read it.
EXIT_CODES: tuple[tuple[int, str, str], ...] = (
    (EXIT_OK, "ok", "done"),
    (EXIT_FAILURE, "failed",
     "the work ran and failed: a run that failed or stopped short (metrics.json says why), "
     "a batch with a failed or unfinished case, a broken OpenFOAM build (doctor), a report "
     "that could not be made, no meniscus line to band"),
    (EXIT_BAD_INPUT, "bad input",
     "refused before any work, nothing written: a bad spec, option, --set, file or path, a "
     "read-only or full disk, a corrupt case file, a case another process runs"),
    (EXIT_NOT_CONVERGED, "not converged",
     "precalc: the EHL solution did not converge (outputs written, converged: false)"),
    (EXIT_INTERNAL, "internal error",
     "a bug in ehlfoam: one line; `ehlfoam --debug COMMAND ...` shows the traceback"),
    (EXIT_INTERRUPTED, "interrupted",
     "Ctrl-C (SIGTERM too in run and batch); a batch resumes when run again"),
)


def exit_code_table() -> str:
    """The exit codes as lines of text (``ehlfoam --help``'s epilog)."""
    return "\n".join(textwrap.fill(meaning, WIDTH, initial_indent=f"  {code:<5d}{name:<15s}",
                                   subsequent_indent=" " * 22)
                     for code, name, meaning in EXIT_CODES)

#: width the descriptions are wrapped to
WIDTH = 88


def add_command(subparsers, name: str, *, help: str, description: str,
                examples: Iterable[str]) -> argparse.ArgumentParser:
    """Register subcommand ``name``; its ``--help`` shows ``description`` (wrapped) and ends
    with ``examples`` (command lines, shown as written)."""
    paragraphs = [textwrap.fill(p, WIDTH) for p in description.split("\n\n")]
    epilog = "example:\n" + "\n".join(f"  {line}" for line in examples)
    return subparsers.add_parser(name, help=help, description="\n\n".join(paragraphs),
                                 epilog=epilog,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0 (NaN and infinity are refused: not limits)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (value > 0 and math.isfinite(value)):
        raise argparse.ArgumentTypeError(f"{value} (valid range: finite, > 0)")
    return value


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value} (valid range >= 1)")
    return value


def print_notices(command: str, notices: Iterable[Notice]) -> None:
    """Each notice on one line of stderr: ``ehlfoam COMMAND: warning [code] text (docs)``."""
    for notice in notices:
        print(f"ehlfoam {command}: warning {notice}", file=sys.stderr)


@contextmanager
def removed_on_failure(path: str | os.PathLike) -> Iterator[None]:
    """If the block raises, remove what it made at ``path``: the file or folder, if it was not
    there before, and the folders above it that it made. A failed command leaves nothing
    half-written; what was there before is never touched."""
    target = Path(os.path.abspath(path))
    top = target
    while not top.parent.exists():
        top = top.parent
    existed = target.exists() or target.is_symlink()
    try:
        yield
    except BaseException:
        if not existed and (top.exists() or top.is_symlink()):
            if top.is_dir() and not top.is_symlink():
                shutil.rmtree(top, ignore_errors=True)
            else:
                top.unlink(missing_ok=True)
        raise


def check_case(path: str | os.PathLike, name: str = "CASE", *, writes: bool = False) -> Path:
    """A case folder written by ``ehlfoam case``, checked before any work: it exists, is a
    folder, has its records (``ehlfoam/spec.json``, ``ehlfoam/geometry.json``) and they read;
    with ``writes``, OpenFOAM can take its path and it can be written (not read-only, not
    full). Raises :class:`~ehlfoam.errors.SpecError` naming ``name``, the path and why."""
    from ehlfoam.case.geometry import META, load_geometry, load_spec_of
    from ehlfoam.errors import SpecError
    from ehlfoam.paths import check_case_out

    case = Path(path)
    if not case.exists():
        raise SpecError(f"{name} {path}: no such folder")
    if not case.is_dir():
        raise SpecError(f"{name} {path}: is a file, not a case folder")
    for record in ("spec.json", "geometry.json"):
        if not (case / META / record).is_file():
            raise SpecError(f"{name} {path}: not a case folder written by `ehlfoam case` "
                            f"(it has no {META}/{record})")
    load_spec_of(case)
    load_geometry(case)
    if writes:
        check_case_out(case, name)
    return case
