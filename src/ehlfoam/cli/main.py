"""The ``ehlfoam`` command line: the parser, the dispatch to a subcommand, the exit codes.

Subcommands, one module each in :mod:`ehlfoam.cli`:
  doctor   show the OpenFOAM runtime and check its build (pitzDaily test)
  precalc  the EHL pre-calculation of one operating point
  thin-film the gap-averaged model's balanced region, a state to start a case from
  case     write an OpenFOAM case from a TOML case spec
  run      run a case to steady state and write its metrics.json
  band     bands of finer cells along a run's meniscus (for mesh.refine)
  snapshot a run case's state in one small file, to start other cases from
  report   an HTML report (pictures, plots, metrics) of a case or a batch
  batch    generate, run and report a batch of cases (sweeps, speed ramps)
  foam     any OpenFOAM application through the configured runtime

Exit codes: one table, :data:`ehlfoam.cli.common.EXIT_CODES` (0 ok, 1 failed, 2 bad input,
3 not converged, 70 internal error, 130 interrupted; ``ehlfoam foam``: the application's
own), shown by ``ehlfoam --help`` and docs/cli.md. Whatever a command raises goes through one
error path, :mod:`ehlfoam.cli.failures`: one line ``ehlfoam COMMAND: MESSAGE`` and its exit
code, or the traceback with ``ehlfoam --debug COMMAND ...``. The subcommand modules import
only the standard library at the top, so that ``--help`` is quick; numpy, scipy, pyvista,
foamlib, gmsh and dask load in the commands.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence

from ehlfoam.cli import (band, batch, case, doctor, foam, precalc, report, run, snapshot,
                         thin_film)
from ehlfoam.cli.common import EXIT_BAD_INPUT, exit_code_table
from ehlfoam.cli.failures import run_command

#: the subcommands, in the order ``ehlfoam --help`` lists them
COMMANDS = (doctor, precalc, thin_film, case, run, band, snapshot, report, batch, foam)


def version() -> str:
    """The installed package's version (its metadata)."""
    from importlib.metadata import PackageNotFoundError, version as _version

    try:
        return _version("ehlfoam")
    except PackageNotFoundError:
        return "unknown (not installed)"


def build_parser() -> argparse.ArgumentParser:
    """The parser of ``ehlfoam`` and its subcommands."""
    parser = argparse.ArgumentParser(
        prog="ehlfoam",
        description="OpenFOAM cases of the oil flow around an EHL ball-on-disc contact.",
        epilog="OpenFOAM is chosen with EHLFOAM_FOAM=embedded|native|prefix,\n"
               "EHLFOAM_FOAM_PREFIX and EHLFOAM_CACHE (docs/runtime.md; `ehlfoam doctor` checks it).\n\n"
               "exit codes (docs/cli.md; `ehlfoam foam` exits with its application's code):\n"
               + exit_code_table() + "\n\n"
               "example:\n"
               "  ehlfoam case examples/cases/nominal.toml --out runs/nominal "
               "--set mesh.resolution=coarse\n"
               "  ehlfoam run runs/nominal\n"
               "  ehlfoam COMMAND --help",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"ehlfoam {version()}")
    parser.add_argument("--debug", action="store_true",
                        help="on an error, show its traceback (for a bug report) instead of "
                             "one line")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module in COMMANDS:
        module.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``ehlfoam ARGV``; returns the exit code."""
    # One OpenBLAS thread unless the user chose otherwise, set before numpy loads (in the
    # commands): the flow-pattern raster makes thousands of tiny LAPACK calls, which an
    # OpenBLAS thread pool slows from 0.02 s to seconds on cores busy with OpenFOAM
    # (ehlfoam.report.threads).
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse: --help, --version (0) or bad usage (2)
        return exc.code if isinstance(exc.code, int) else EXIT_BAD_INPUT
    [action] = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return run_command(args, args.command, action.choices[args.command], debug=args.debug)


if __name__ == "__main__":
    sys.exit(main())
