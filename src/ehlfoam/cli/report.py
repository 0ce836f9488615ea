"""``ehlfoam report DIR``: the HTML report of a case or a batch (:mod:`ehlfoam.report`).

Exit codes: 0 the report was written (also for a failed or running case: the page says so),
1 the report could not be written, 2 bad input (DIR missing, neither a case nor a batch, a
corrupt case record, DIR read-only or its disk full).
"""

from __future__ import annotations

import argparse
import sys
import time

from ehlfoam.cli.common import EXIT_FAILURE, EXIT_OK, add_command, check_case, positive_int


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``ehlfoam report``."""
    p = add_command(
        subparsers, "report",
        help="write the HTML report of a case or a batch (DIR/report/index.html)",
        description="Pictures (top view of the oil as through the glass disc, side view, "
                    "pressure, EHL precalc, history) and tables of a case, or an index of a "
                    "batch's cases with its charts, written off-screen to "
                    "DIR/report/index.html. A failed or running case gets a report that "
                    "says so. Exit 0 written, 1 could not be written, 2 bad input.",
        examples=["ehlfoam report runs/nominal", "ehlfoam report runs/default --jobs 2"])
    p.add_argument("dir", help="a case folder (ehlfoam case) or a batch folder")
    p.add_argument("--no-gif", action="store_true", help="skip the transient's GIF")
    p.add_argument("--jobs", type=positive_int, default=None,
                   help="batch: case reports made in parallel (default: up to 2)")
    p.add_argument("--force", action="store_true",
                   help="batch: remake every case report, even the up-to-date ones")
    p.set_defaults(func=cmd_report)
    return p


def cmd_report(args: argparse.Namespace) -> int:
    """Check DIR, write the report of a case or a batch folder and print where it is."""
    from pathlib import Path

    from ehlfoam.case.geometry import META
    from ehlfoam.errors import SpecError
    from ehlfoam.paths import check_output
    from ehlfoam.report import report

    folder = Path(args.dir)
    if not folder.is_dir():
        raise SpecError(f"DIR {args.dir}: " + ("is a file, not a case or batch folder"
                                               if folder.exists() else "no such folder"))
    if (folder / META).is_dir():
        check_case(folder, "DIR")
    check_output(folder, "DIR")
    start = time.perf_counter()
    kwargs = {"animate": not args.no_gif}
    if args.jobs is not None:
        kwargs["jobs"] = args.jobs
    if args.force:
        kwargs["force"] = True
    try:
        index = report(args.dir, **kwargs)
    except (OSError, ValueError):
        raise                  # bad input, a full disk: the one error path (exit 2)
    except Exception as exc:  # noqa: BLE001 - the command reports, the page could not be made
        print(f"ehlfoam report: could not write the report of {args.dir}: "
              f"{type(exc).__name__}: {exc}", file=sys.stderr)
        return EXIT_FAILURE
    print(f"{index}  ({time.perf_counter() - start:.1f} s)")
    return EXIT_OK
