"""``ehlfoam doctor``: show the configured OpenFOAM runtime and check its build (pitzDaily).

Exit codes: 0 the build is sound, 1 it is broken, 2 the configuration is invalid or
--workdir cannot be written.
"""

from __future__ import annotations

import argparse

from ehlfoam.cli.common import EXIT_FAILURE, EXIT_OK, add_command


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``ehlfoam doctor``."""
    p = add_command(
        subparsers, "doctor", help="show the OpenFOAM runtime and check that its build is sound",
        description="Show the configured OpenFOAM runtime (EHLFOAM_FOAM=embedded|native|prefix) "
                    "and run the potentialFoam pitzDaily check; exit 1 if the build is broken "
                    "or missing.",
        examples=["ehlfoam doctor", "EHLFOAM_FOAM=native ehlfoam doctor --workdir /tmp/check"])
    p.add_argument("--workdir", default=None,
                   help="run the check case here and keep it (default: a temp folder)")
    p.set_defaults(func=cmd_doctor)
    return p


def cmd_doctor(args: argparse.Namespace) -> int:
    """Print the configured OpenFOAM runtime and run the pitzDaily build check."""
    from ehlfoam.foam.runtime import FoamRuntime, check_build

    if args.workdir is not None:
        from ehlfoam.paths import check_case_out

        check_case_out(args.workdir, "--workdir")
    runtime = FoamRuntime.from_environment()
    print("OpenFOAM runtime")
    for key, value in runtime.describe().items():
        print(f"  {key + ':':16s}{value}")
    runtime.ensure_present()
    print("Build check: potentialFoam pitzDaily (Interpolated velocity error)")
    result = check_build(runtime, workdir=args.workdir)
    print(f"  {result.summary()}")
    return EXIT_OK if result.ok else EXIT_FAILURE
