"""What the subcommands share: exit codes, a subcommand's parser (its help ends with an
example), number types for options, and notices printed one line each."""

from __future__ import annotations

import argparse
import math
import sys
import textwrap
from collections.abc import Iterable
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ehlfoam.notices import Notice

EXIT_OK, EXIT_FAILURE, EXIT_BAD_INPUT, EXIT_INTERRUPTED = 0, 1, 2, 130

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
        raise argparse.ArgumentTypeError(f"{text} (valid range > 0, finite)")
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
