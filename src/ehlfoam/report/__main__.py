"""``python -m ehlfoam.report DIR [--no-gif] [--jobs N] [--force]``: the report subcommand
without the ``ehlfoam`` front end."""

from __future__ import annotations

import argparse
import sys

from ehlfoam.report.cli import add_parser


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m ehlfoam.report")
    sub = parser.add_subparsers(dest="command", required=True)
    add_parser(sub)
    args = parser.parse_args(["report", *(sys.argv[1:] if argv is None else argv)])
    return int(args.func(args))


if __name__ == "__main__":
    sys.exit(main())
