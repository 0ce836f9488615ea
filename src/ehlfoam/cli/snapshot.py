"""``ehlfoam snapshot``: a run case's state in one small file, to start other cases from
(:mod:`ehlfoam.seed.snapshot`).

Exit codes: 0 written, 2 bad input (no such case or write, a file name not ending in .npz,
unknown fields).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ehlfoam.cli.common import EXIT_OK, add_command, check_case


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``ehlfoam snapshot``."""
    p = add_command(
        subparsers, "snapshot", help="a run case's state in one small file (--start-from)",
        description="Keep the oil fraction (and the velocity) of a run case's write per column "
                    "and layer in a compressed .npz of some 0.1-0.5 MB, with where it came "
                    "from (spec, time, history), so that other cases can start from it "
                    "(ehlfoam case --start-from FILE.npz) after the run folder is gone.",
        examples=["ehlfoam snapshot runs/nominal nominal.npz",
                  "ehlfoam case examples/cases/nominal.toml --out runs/u10 "
                  "--set contact.speed=0.01 --start-from nominal.npz"])
    p.add_argument("case", type=Path, help="a run case folder")
    p.add_argument("out", type=Path, help="the snapshot file to write (.npz)")
    p.add_argument("--time", default="last",
                   help="transits of the write to keep, or 'last' (default)")
    p.add_argument("--fields", nargs="+", default=None, metavar="FIELD",
                   help="fields to keep: alpha.oil (always) and U (default both; U makes the "
                        "file some 4 times larger and the first steps calmer)")
    p.set_defaults(func=cmd_snapshot)
    return p


def cmd_snapshot(args: argparse.Namespace) -> int:
    """Check the case and where to write, write the snapshot and print what it holds. Bad
    input raises (exit 2, :mod:`ehlfoam.cli.failures`): nothing is written."""
    from ehlfoam.paths import check_output
    from ehlfoam.seed.snapshot import save_snapshot

    check_case(args.case, "CASE")
    check_output(args.out, "OUT", folder=False)
    fields = {"fields": tuple(args.fields)} if args.fields else {}
    record = save_snapshot(args.case, args.out, args.time, **fields)
    size = args.out.stat().st_size
    print(f"snapshot {args.out}: {record['source']} at t = {record['time_s']:.6g} s "
          f"({record['transits']:.4f} transits), {record['cells']} cells, "
          f"{', '.join(record['fields'])}, {size / 1e6:.2f} MB")
    return EXIT_OK
