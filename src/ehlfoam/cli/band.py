"""``ehlfoam band``: bands of finer cells along a run's meniscus, printed as TOML for the next
case's ``mesh.refine`` (:mod:`ehlfoam.seed.band`).

Exit codes: 0 printed, 1 no meniscus line long enough, 2 bad input (an option out of range,
no such case or write).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ehlfoam.cli.common import EXIT_FAILURE, EXIT_OK, add_command, check_case


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``ehlfoam band``."""
    p = add_command(
        subparsers, "band", help="bands of finer cells along a run's meniscus (mesh.refine)",
        description="Read the meniscus (the alpha = 0.5 lines of the mid-gap oil fraction) "
                    "off a written time of a run case and print bands of finer cells along "
                    "it as a TOML array of inline tables, for --set 'mesh.refine=[...]' or a "
                    "spec's [mesh] refine = [...]. Sizes in units of the Hertz radius a.",
        examples=["ehlfoam band runs/nominal --size 0.06 --half-width 1.0",
                  "ehlfoam case examples/cases/nominal.toml --out runs/banded "
                  "--start-from runs/nominal --set \"mesh.refine=$(ehlfoam band runs/nominal "
                  "--size 0.06 --half-width 1)\""])
    p.add_argument("case", type=Path, help="a run case folder")
    p.add_argument("--size", type=float, required=True, help="cell size in the band [a]")
    p.add_argument("--half-width", type=float, required=True,
                   help="the band reaches this far either side of the meniscus [a]")
    p.add_argument("--time", default="last",
                   help="transits of the write to read, 'last', or 'start' (the initial field: "
                        "a case started from a thin-film state has its meniscus there)")
    p.add_argument("--spacing", type=float, default=None,
                   help="distance between the band's points [a] (default half-width / 4)")
    p.add_argument("--min-length", type=float, default=None,
                   help="leave out meniscus lines shorter than this [a] (default half-width)")
    p.set_defaults(func=cmd_band)
    return p


def check_args(args: argparse.Namespace) -> None:
    """Bad numbers (NaN and inf too) fail before the case is read, naming the option and its
    range: :class:`~ehlfoam.errors.SpecError`."""
    from ehlfoam.errors import SpecError

    for name, value, hi in (("--size", args.size, 10.0), ("--half-width", args.half_width, 20.0),
                            ("--spacing", args.spacing, 20.0)):
        if value is not None and not 0.0 < value <= hi:
            raise SpecError(f"{name} = {value:g} a is out of range (0 < {name} <= {hi:g} a)")
    if args.min_length is not None and not 0.0 <= args.min_length <= 1e3:
        raise SpecError(f"--min-length = {args.min_length:g} a is out of range "
                        "(0 <= --min-length <= 1000 a)")


def cmd_band(args: argparse.Namespace) -> int:
    """Print the bands along the case's meniscus (TOML on stdout, a summary on stderr). Bad
    input raises (exit 2, :mod:`ehlfoam.cli.failures`)."""
    check_args(args)
    check_case(args.case, "CASE")
    from ehlfoam.seed.band import bands_toml, meniscus_bands, meniscus_lines

    time, lines = meniscus_lines(args.case, args.time)
    bands = meniscus_bands(lines, args.size, args.half_width, args.spacing, args.min_length)
    if not bands:
        shortest = args.half_width if args.min_length is None else args.min_length
        print(f"ehlfoam band: {args.case} has no meniscus line of {shortest:g} a or longer "
              f"at t = {time:g} s", file=sys.stderr)
        return EXIT_FAILURE
    print(bands_toml(bands))
    print(f"# {len(bands)} band(s) along the meniscus of {args.case} at t = {time:g} s, "
          f"{sum(len(b.points) for b in bands)} points", file=sys.stderr)
    return EXIT_OK
