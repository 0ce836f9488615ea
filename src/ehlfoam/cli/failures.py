"""The one error path of the command line: what an exception that ends a command means to the
user, as an exit code (:data:`ehlfoam.cli.common.EXIT_CODES`) and one line naming what was
wrong, its value and what is valid.

:func:`ehlfoam.cli.main.main` catches whatever a command raises and prints
``ehlfoam COMMAND: MESSAGE`` from :func:`explain`; ``ehlfoam --debug COMMAND ...`` re-raises
instead (the traceback, for a bug report). A command returns the codes it decides itself (a
failed run, a precalc that did not converge) and raises for everything else:

- bad input (exit 2): :class:`~ehlfoam.errors.SpecError`, a ``ValueError`` (validation,
  ``json.JSONDecodeError``, a pydantic ``ValidationError``, foamlib's parse error of a corrupt
  OpenFOAM dictionary), a ``UnicodeDecodeError`` (a binary file where text belongs), the OS
  errors a user mends (no such file, not a folder, a folder, no permission, a full or
  read-only disk, ...: :data:`USER_ERRNOS`), named by the option whose path it is
  (``--out /x: read-only file system``), and an OpenFOAM configuration error;
- failed (exit 1): an OpenFOAM application that failed, another OS error, no memory left;
- interrupted (exit 130): Ctrl-C (``run`` and ``batch`` turn SIGTERM into it);
- internal error (exit 70): anything else, a bug: its type and text on one line.

The module imports only the standard library; the exception classes of pydantic, foamlib and
the OpenFOAM runtime are looked up by name, so that explaining an error loads nothing.
"""

from __future__ import annotations

import argparse
import errno
import os
import re
import shutil

from ehlfoam.cli.common import (EXIT_BAD_INPUT, EXIT_FAILURE, EXIT_INTERNAL,
                                EXIT_INTERRUPTED)

__all__ = ["USER_ERRNOS", "explain", "foam_parse_text", "one_line", "run_command"]

#: OS errors that are the user's to mend (exit 2): a path, a permission, a full or read-only
#: disk.
USER_ERRNOS = frozenset({
    errno.ENOENT, errno.ENOTDIR, errno.EISDIR, errno.EACCES, errno.EPERM, errno.ENOSPC,
    errno.EROFS, errno.EDQUOT, errno.EEXIST, errno.ENAMETOOLONG, errno.ELOOP, errno.EFBIG,
    errno.ENOTEMPTY, errno.EXDEV, errno.EBUSY, errno.ETXTBSY})

#: OS errors that ehlfoam raises with a message of its own (no errno) about a user's path
#: (a case folder that exists, a missing written time): exit 2.
USER_OS_ERRORS = (FileNotFoundError, FileExistsError, NotADirectoryError, IsADirectoryError,
                  PermissionError)

#: Where a command writes (its argument's dest): an OS error without a file name (a full disk
#: found while writing) is named by it. Commands not listed write under ``--out``.
OUTPUT_ARG = {"run": "case", "report": "dir", "doctor": "workdir"}


def one_line(text: str) -> str:
    """``text`` on one line: line breaks (and the spaces around them) become one space."""
    return re.sub(r"\s*\n\s*", " ", str(text)).strip()


def foam_parse_text(err: BaseException) -> str:
    """foamlib's parse error of an OpenFOAM dictionary on one line: ``line 1, column 9:
    expected keyword or standalone data``."""
    lines = [line.strip() for line in str(err).splitlines() if line.strip()]
    if not lines:
        return type(err).__name__
    where = lines[0].removeprefix("parsing failed on ").rstrip(":")
    expected = [line for line in lines[1:] if line.lower().startswith("expected")]
    return where + (f": expected {expected[0][len('expected'):].lstrip(': ')}" if expected
                    else "")


def _classes(exc: BaseException) -> set[str]:
    """The qualified names of ``exc``'s classes (its type and every base)."""
    return {f"{c.__module__}.{c.__qualname__}" for c in type(exc).__mro__}


def _labels(parser: argparse.ArgumentParser | None) -> dict[str, str]:
    """How the user names each argument of the command: its first option string
    (``--out``), or a positional argument's metavar or dest in capitals (``CASE``)."""
    out = {}
    for action in getattr(parser, "_actions", []):
        if action.option_strings:
            out[action.dest] = action.option_strings[0]
        else:
            out[action.dest] = (action.metavar if isinstance(action.metavar, str)
                                else action.dest.upper())
    return out


def _path_args(args: argparse.Namespace | None,
               parser: argparse.ArgumentParser | None) -> list[tuple[str, str]]:
    """The command's arguments that may be paths: (label, value), e.g. ("--out", "runs/x")."""
    labels = _labels(parser)
    given = vars(args).items() if args is not None else ()
    return [(labels[dest], str(value)) for dest, value in given
            if dest in labels and isinstance(value, (str, os.PathLike)) and str(value)]


def _inside(path: str, top: str) -> bool:
    """Whether ``path`` is ``top``, inside it, or inside the temporary sibling a folder is
    built in before it is renamed into place (``.NAME.xxxx`` next to ``top``:
    :mod:`ehlfoam._io`, the case writer)."""
    a, b = os.path.abspath(path), os.path.abspath(top).rstrip(os.sep)
    sibling = os.path.join(os.path.dirname(b), f".{os.path.basename(b)}.")
    return a == b or a.startswith(b + os.sep) or a.startswith(sibling)


def _os_error(exc: OSError, command: str, args: argparse.Namespace | None,
              parser: argparse.ArgumentParser | None) -> str:
    """An OS error named by the argument whose path it is: ``--out /x: read-only file
    system``, ``SPEC specs/a: is a directory``; one raised with a message of ehlfoam's own
    (no errno), that message."""
    if not exc.errno:
        return one_line(exc)
    why = os.strerror(exc.errno).lower()
    candidates = _path_args(args, parser)
    filename = None if exc.filename is None else os.fsdecode(exc.filename)
    if filename is not None:
        owners = [(label, value) for label, value in candidates if _inside(filename, value)]
        if owners:   # the innermost argument holding the file
            label, value = max(owners, key=lambda lv: len(os.path.abspath(lv[1])))
            within = os.path.abspath(value).rstrip(os.sep) + os.sep
            at = f" ({filename})" if os.path.abspath(filename).startswith(within) else ""
            return f"{label} {value}: {why}{at}"
        return f"{filename}: {why}"
    dest = OUTPUT_ARG.get(command, "out")
    value = getattr(args, dest, None) if args is not None else None
    label = _labels(parser).get(dest, dest)
    if value:
        return f"{label} {value}: {why}"
    return why


def _first_copy_error(exc: shutil.Error) -> OSError:
    """``shutil.copytree``'s error (a list of (source, destination, why) texts) as the OS
    error of its first item: ``[Errno 28] No space left on device`` becomes ENOSPC on the
    destination."""
    items = exc.args[0] if exc.args and isinstance(exc.args[0], list) else []
    for item in items:
        if isinstance(item, tuple) and len(item) == 3:
            found = re.search(r"\[Errno (\d+)\]", str(item[2]))
            if found:
                code = int(found.group(1))
                return OSError(code, os.strerror(code), str(item[1]))
    return OSError(one_line(exc))


def _validation_text(exc: BaseException) -> str:
    """A pydantic ValidationError raised outside a spec's own formatter: one clause per
    error (its location, input and message)."""
    clauses = []
    for e in exc.errors():   # type: ignore[attr-defined]
        loc = ".".join(str(p) for p in e.get("loc", ()))
        given = e.get("input")
        shown = "" if isinstance(given, (dict, list)) else f" = {given!r}"
        clauses.append(f"{loc}{shown}: {e['msg']}" if loc else e["msg"])
    return f"invalid {exc.title}: " + "; ".join(clauses)   # type: ignore[attr-defined]


def explain(exc: BaseException, command: str, args: argparse.Namespace | None = None,
            parser: argparse.ArgumentParser | None = None) -> tuple[int, str]:
    """The exit code and the one-line message (without the ``ehlfoam COMMAND:`` prefix) for
    ``exc``, raised by ``command`` run with ``args`` (the parsed arguments; ``parser`` the
    command's parser, which names them)."""
    names = _classes(exc)
    if isinstance(exc, KeyboardInterrupt):
        return EXIT_INTERRUPTED, "interrupted"
    if "ehlfoam.foam.runtime.FoamConfigError" in names:
        return EXIT_BAD_INPUT, f"configuration error: {one_line(exc)}"
    if "ehlfoam.foam.runtime.FoamError" in names:
        return EXIT_FAILURE, one_line(exc)
    if "ehlfoam.errors.SpecError" in names:
        return EXIT_BAD_INPUT, one_line(exc)
    if "pydantic_core._pydantic_core.ValidationError" in names:
        return EXIT_BAD_INPUT, one_line(_validation_text(exc))
    if isinstance(exc, UnicodeDecodeError):
        return EXIT_BAD_INPUT, (f"a file that should be UTF-8 text is not (byte {exc.start}: "
                                f"{exc.reason}); is it the right file?")
    if any(n.endswith("FoamFileDecodeError") for n in names):
        return EXIT_BAD_INPUT, f"not a valid OpenFOAM dictionary: {foam_parse_text(exc)}"
    if type(exc).__name__ == "JSONDecodeError":
        return EXIT_BAD_INPUT, f"not valid JSON: {one_line(exc)}"
    if isinstance(exc, shutil.Error):           # a copy of a folder: its first error
        exc = _first_copy_error(exc)
    if isinstance(exc, OSError):
        user = exc.errno in USER_ERRNOS or (not exc.errno and isinstance(exc, USER_OS_ERRORS))
        code = EXIT_BAD_INPUT if user else EXIT_FAILURE
        return code, one_line(_os_error(exc, command, args, parser))
    if isinstance(exc, ValueError):
        return EXIT_BAD_INPUT, one_line(exc)
    if isinstance(exc, MemoryError):
        return EXIT_FAILURE, "out of memory: the input asks for more than this machine has"
    text = one_line(exc)
    return EXIT_INTERNAL, (f"internal error: {type(exc).__name__}"
                           + (f": {text}" if text else "")
                           + f" (a bug; `ehlfoam --debug {command} ...` shows where)")



def run_command(args: argparse.Namespace, command: str,
                parser: argparse.ArgumentParser | None = None, *, debug: bool = False) -> int:
    """Run the parsed command ``args.func(args)`` and return its exit code; what it raises
    becomes one line on stderr, ``ehlfoam COMMAND: MESSAGE``, and the code :func:`explain`
    gives (``debug``: re-raised instead, but for Ctrl-C)."""
    import sys

    try:
        return int(args.func(args))
    except (Exception, KeyboardInterrupt) as exc:
        if debug and not isinstance(exc, KeyboardInterrupt):
            raise
        code, message = explain(exc, command, args, parser)
        if code != EXIT_INTERRUPTED:
            print(f"ehlfoam {command}: {message}", file=sys.stderr)
        return code
