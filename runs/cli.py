"""The ``ehlfoam`` command line.

Subcommands:
  doctor   show the OpenFOAM runtime and check its build (pitzDaily test)
  precalc  the EHL pre-calculation, registered by ``ehl_precalc.cli``

Exit codes: 0 ok, 1 failure, 2 bad input.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from ehl_precalc import cli as precalc_cli
from runs.foam_runtime import (
    FoamConfigError,
    FoamError,
    FoamRuntime,
    check_build,
)

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_BAD_INPUT = 2


def cmd_doctor(args: argparse.Namespace) -> int:
    """Print the configured OpenFOAM runtime and run the pitzDaily build check."""
    runtime = FoamRuntime.from_environment()
    print("OpenFOAM runtime")
    for key, value in runtime.describe().items():
        print(f"  {key + ':':16s}{value}")
    runtime.ensure_present()
    print("Build check: potentialFoam pitzDaily (Interpolated velocity error)")
    result = check_build(runtime, workdir=args.workdir)
    print(f"  {result.summary()}")
    return EXIT_OK if result.ok else EXIT_FAILURE


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="ehlfoam",
        description="OpenFOAM cases of the oil flow around an EHL ball-on-disc contact.",
        epilog="OpenFOAM is chosen with EHLFOAM_FOAM=embedded|native|prefix, "
               "EHLFOAM_FOAM_PREFIX and EHLFOAM_CACHE (see README.md).",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    doctor = sub.add_parser(
        "doctor", help="show the OpenFOAM runtime and check that its build is sound",
        description="Show the configured OpenFOAM runtime and run the potentialFoam "
                    "pitzDaily check; exit 1 if the build is broken or missing.")
    doctor.add_argument("--workdir", default=None,
                        help="run the check case here and keep it (default: a temp folder)")
    doctor.set_defaults(func=cmd_doctor)

    precalc_cli.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse: --help (0) or bad usage (2)
        return exc.code if isinstance(exc.code, int) else EXIT_BAD_INPUT
    try:
        return int(args.func(args))
    except FoamConfigError as exc:
        print(f"ehlfoam: configuration error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except FoamError as exc:
        print(f"ehlfoam {args.command}: {exc}", file=sys.stderr)
        return EXIT_FAILURE
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
