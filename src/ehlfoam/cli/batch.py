"""``ehlfoam batch SPEC``: generate, run and report every case of a batch spec.

Exit codes: 0 every planned case finished; 1 some case failed or is not finished; 2 bad
input (bad spec, more cases than --max-cases, run.n_procs beyond the usable cores without
--oversubscribe, a bad --slurm value, busy folder, a finished case with another spec;
nothing built);
130 interrupted (Ctrl-C / SIGTERM; re-run the command to resume).

Also runs on its own: ``python -m ehlfoam.cli.batch SPEC [options]``.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from ehlfoam.cli.common import EXIT_BAD_INPUT, EXIT_OK, add_command, positive_int

DESCRIPTION = (
    "Expand a batch spec (a base case spec plus sweeps over speed, temperature, load, supply "
    "and resolution, and speed ramps) into cases under runs/NAME/cases/, build and run the "
    "ones not finished yet (locally, or on Dask with --scheduler / --slurm), and write "
    "runs/NAME/results.csv, the regime map (runs/NAME/regime/) and the batch report. "
    "Re-running resumes: finished cases are kept, failed ones re-run only with "
    "--rerun-failed. Exit 1 if a case failed, 2 on bad input (nothing built).")
EXAMPLES = ("ehlfoam batch examples/batches/default.toml",
            "ehlfoam batch examples/batches/default.toml --dry-run",
            "ehlfoam batch examples/batches/regime.toml --out runs/regime --slurm "
            "cores=16,memory=16GB,walltime=01:00:00,jobs=4")


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The batch command's arguments."""
    p.add_argument("spec", help="batch spec TOML (e.g. examples/batches/default.toml)")
    p.add_argument("--out", default=None,
                   help="batch folder (default: runs/STEM/ in the working directory for "
                        "STEM.toml); its path may not hold whitespace, quotes, a backslash or "
                        "any of *?[]{}$;<>|&` (OpenFOAM cannot take them)")
    p.add_argument("--rerun-failed", action="store_true",
                   help="re-run failed cases (finished cases are never recomputed)")
    size = p.add_mutually_exclusive_group()
    size.add_argument("--jobs", type=positive_int, default=None,
                      help="cases at once on this machine (each uses run.n_procs cores)")
    size.add_argument("--cores", type=positive_int, default=None,
                      help="CPU budget on this machine (default: all cores); cases at once = "
                           "cores // run.n_procs")
    dask = p.add_mutually_exclusive_group()
    dask.add_argument("--scheduler", default=None, metavar="ADDRESS",
                      help="run on a Dask distributed scheduler (e.g. tcp://host:8786); its "
                           "workers must be started with --resources CPU=<cores>")
    dask.add_argument("--slurm", nargs="?", const="", default=None, metavar="KEY=VALUE,...",
                      help="run on Slurm through dask-jobqueue: cores=N,memory=16GB,"
                           "walltime=01:00:00,queue=NAME,jobs=N[,account=NAME]")
    p.add_argument("--max-cases", type=positive_int, default=None, metavar="N",
                   help="the most cases the batch may ask for, counted before they are "
                        "expanded (default 2000: a sweep or range that asks for more is "
                        "refused at once)")
    p.add_argument("--oversubscribe", action="store_true",
                   help="run even when run.n_procs, --cores or --jobs x run.n_procs is more "
                        "than the CPU cores this process may use (refused otherwise)")
    p.add_argument("--dry-run", action="store_true",
                   help="print the expanded plan and the estimated cost; build nothing")
    p.add_argument("--no-report", action="store_true",
                   help="skip the regime map and the batch report")
    p.add_argument("--quiet", action="store_true",
                   help="no progress bar: one line per case event (for logs)")


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``ehlfoam batch``."""
    p = add_command(
        subparsers, "batch",
        help="run a batch of cases (sweeps, speed ramps) and map the flow regimes",
        description=DESCRIPTION, examples=EXAMPLES)
    add_arguments(p)
    p.set_defaults(func=cmd_batch)
    return p


def check_batch_folder(spec: str, out: str | None, *, writes: bool = True) -> Path:
    """The batch folder (``--out``, else runs/STEM/), checked before anything is built: a
    path OpenFOAM can take (its cases are under it) and, with ``writes``, one that can be
    written. Raises :class:`~ehlfoam.errors.SpecError` naming it, the path and why."""
    from ehlfoam.batch.folder import batch_folder
    from ehlfoam.paths import check_case_out

    folder = batch_folder(Path(spec), Path(out) if out else None)
    check_case_out(folder, "--out" if out else "batch folder", writes=writes)  # ids are safe
    return folder


def cmd_batch(args: argparse.Namespace) -> int:
    """Run (or dry-run) the batch; exit code as in the module doc."""
    from ehlfoam.errors import SpecError

    from ehlfoam.batch.launch import BatchError, BatchOptions, dry_run, run_batch
    from ehlfoam.batch.executors import parse_slurm
    from ehlfoam.report import after_batch

    from ehlfoam.batch.spec import DEFAULT_MAX_CASES

    check_batch_folder(args.spec, args.out, writes=not args.dry_run)
    max_cases = args.max_cases or DEFAULT_MAX_CASES
    try:
        slurm = parse_slurm(args.slurm) if args.slurm is not None else None
        if args.dry_run:
            print(dry_run(args.spec, Path(args.out) if args.out else None,
                          max_cases=max_cases))
            return EXIT_OK
        opts = BatchOptions(out=Path(args.out) if args.out else None, jobs=args.jobs,
                            cores=args.cores, rerun_failed=args.rerun_failed,
                            scheduler=args.scheduler, slurm=slurm, quiet=args.quiet,
                            regime=not args.no_report,
                            report=None if args.no_report else after_batch,
                            max_cases=max_cases, oversubscribe=args.oversubscribe)
        outcome = run_batch(args.spec, opts)
    except (SpecError, BatchError) as err:
        print(f"ehlfoam batch: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    return outcome.exit_code


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m ehlfoam.cli.batch SPEC [options]`` (the same as ``ehlfoam batch``)."""
    from ehlfoam.cli.failures import run_command

    parser = add_parser(argparse.ArgumentParser(prog="ehlfoam").add_subparsers())
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else EXIT_BAD_INPUT
    return run_command(args, "batch", parser)


if __name__ == "__main__":
    sys.exit(main())
