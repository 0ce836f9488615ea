"""``ehlfoam thin-film``: a case spec's flooded region in the thin-film model, as a start state.

Marches the spec's contact, oil, supply and wetting in the gap-averaged model
(:mod:`ehlfoam.thinfilm.from_spec`) and writes ``DIR/state.npz``, which ``ehlfoam case SPEC
--start-from DIR/state.npz`` starts a 3D case from, and ``DIR/summary.json`` (the region's
metrics, each transit's record, how it was made). Exit 2 on bad input, before anything is
solved or written.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

EXAMPLE = """example:
  ehlfoam thin-film examples/cases/nominal.toml --out runs/nominal_tf --balance
  ehlfoam case examples/cases/nominal.toml --out runs/nominal \\
      --start-from runs/nominal_tf/state.npz"""


def _ranged(kind: type, lo: float, hi: float | None = None, lo_open: bool = True,
            hi_open: bool = False):
    """An argparse type: ``kind`` within (lo, hi] (or the bounds the flags say), else an
    error that names the value and the valid range."""
    def parse(text: str) -> Any:
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a {kind.__name__}") from None
        above = value > lo if lo_open else value >= lo
        below = hi is None or (value < hi if hi_open else value <= hi)
        if not (above and below):
            rng = f"{'(' if lo_open else '['}{lo:g}, " + (
                "inf)" if hi is None else f"{hi:g}{')' if hi_open else ']'}")
            raise argparse.ArgumentTypeError(f"{value!r} is out of range: must be in {rng}")
        return value
    return parse


def _finite(text: str) -> float:
    """An argparse type: a finite number."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return value


def _receding(text: str) -> str | float:
    """--receding: 'static', 'bretherton' or a factor (the model checks its range)."""
    if text in ("static", "bretherton"):
        return text
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(
            f"{text!r}: must be 'static', 'bretherton' or a factor in [0.5, 2]")
    return value


def add_parser(subparsers: Any) -> None:
    """Register ``ehlfoam thin-film`` on the command line's subparsers."""
    p = subparsers.add_parser(
        "thin-film", help="a spec's flooded region in the thin-film model: a start state",
        description="March the case spec's contact, oil, supply and wetting in the "
                    "gap-averaged thin-film model from its initial puddle (or --start) for "
                    "--transits transits, or until the outflow balances the supply "
                    "(--balance); write DIR/state.npz (`ehlfoam case SPEC --start-from "
                    "DIR/state.npz` starts a 3D case from it) and DIR/summary.json. Exit 2 "
                    "on bad input, before anything is solved.",
        epilog=EXAMPLE, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("spec", nargs="?", help="case spec TOML (default: the reference case)")
    p.add_argument("--out", required=True, type=Path, metavar="DIR",
                   help="folder to write state.npz and summary.json into")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a spec value, as `ehlfoam case --set` (TOML values, strict "
                        "types; an {inline table} merges into the spec's table; repeatable)")
    p.add_argument("--transits", type=_ranged(float, 0.0, 1e4), default=None,
                   help="transits to march (default: 10); with --balance, the most to march "
                        "(default: 200)")
    p.add_argument("--balance", action="store_true",
                   help="stop when the outflow balances the supply and the oil stands")
    p.add_argument("--tolerance", type=_ranged(float, 0.0, 1.0, hi_open=True), default=0.01,
                   help="of --balance: the mean outflow / supply within it of 1 and the oil "
                        "changed by less than it over --window transits (default: 0.01)")
    p.add_argument("--window", type=_ranged(int, 1, 1000, lo_open=False), default=5,
                   help="of --balance, transits (default: 5)")
    p.add_argument("--cell", type=_ranged(float, 0.0, 10.0), default=0.2, metavar="SIZE",
                   help="cell size, units of a (default: 0.2)")
    p.add_argument("--domain", nargs=3, type=_finite, default=[-11.0, 19.0, 11.0],
                   metavar=("X_MIN", "X_MAX", "Y_MAX"),
                   help="the half domain, units of a (default: -11 19 11)")
    p.add_argument("--courant", type=_ranged(float, 0.0, 1.0), default=0.25,
                   help="the step over a cell's transit at u (default: 0.25)")
    p.add_argument("--receding", type=_receding, default="static",
                   help="the receding meniscus's pressure: static, bretherton or a factor "
                        "in [0.5, 2] on the static one (default: static)")
    p.add_argument("--advancing", type=_ranged(float, 0.0, 180.0, lo_open=False), default=None,
                   metavar="DEG",
                   help="apparent angle of menisci advancing onto dry walls, from the "
                        "spec's contact angle to 90 deg (default: the contact angle)")
    p.add_argument("--start", type=Path, default=None, metavar="STATE.npz",
                   help="start from a state written before (any grid) instead of the "
                        "spec's puddle")
    p.add_argument("--quiet", action="store_true", help="no line per transit")
    p.set_defaults(func=cmd_thin_film)


def cmd_thin_film(args: argparse.Namespace) -> int:
    """Validate, march, write the state and its summary, print the region's metrics."""
    from ehlfoam.cli.case import parse_overrides   # the one reading of --set
    from ehlfoam.cli.common import removed_on_failure
    from ehlfoam.errors import SpecError
    from ehlfoam.gap.source import load_gap
    from ehlfoam.paths import check_output
    from ehlfoam.spec.case import load_case_spec, make_case_spec
    from ehlfoam.thinfilm.from_spec import (STATE_FILE, SUMMARY_FILE, RegionOptions, march,
                                            problem_from_spec, write_region)
    from ehlfoam.thinfilm.state import load_state

    overrides = parse_overrides(args.set)
    spec = (load_case_spec(args.spec, **overrides) if args.spec
            else make_case_spec(None, **overrides))
    check_output(args.out, "--out")        # before anything is solved
    if spec.stop.at is not None:           # a start state is the balance at speed
        print(f"note: stop.at = {spec.stop.at:g} s is not applied: ehlfoam thin-film marches "
              "at contact.speed to a start state (a case's run applies the stop: ehlfoam "
              "case, ehlfoam run)", file=sys.stderr)
    start = None
    if args.start is not None:
        try:
            start = load_state(args.start)
        except (OSError, KeyError, ValueError) as err:
            raise SpecError(f"--start {args.start}: not a thin-film state ({err})") from None
    options = RegionOptions(cell=args.cell, domain=tuple(args.domain), receding=args.receding,
                            advancing_angle=args.advancing)
    gap, _ = load_gap(spec.contact)
    prob = problem_from_spec(spec, gap, options)   # a ValueError: bad input (exit 2)
    transits = args.transits or (200.0 if args.balance else 10.0)
    t0 = time.perf_counter()
    sol = march(spec, prob, transits=transits, balance=args.balance,
                tolerance=args.tolerance, window=args.window, courant=args.courant,
                start=start, progress=None if args.quiet else _progress(spec))
    record = {"spec": args.spec, "set": overrides, "options": asdict(options),
              "transits_max": transits, "balance": args.balance,
              "tolerance": args.tolerance if args.balance else None,
              "window": args.window if args.balance else None, "courant": args.courant,
              "start": None if args.start is None else str(args.start),
              "wall_s": time.perf_counter() - t0}
    with removed_on_failure(args.out):
        summary = write_region(sol, spec, args.out, record)
    print(_metrics_text(summary), flush=True)
    print(f"wrote {args.out / STATE_FILE} and {args.out / SUMMARY_FILE}")
    return 0


def _progress(spec: Any):
    """A line on stderr per transit: its oil, outflow over supply, width and the cells that
    ran dry within a step."""
    a, transit = spec.a, spec.transit_time

    def show(rec: dict) -> None:
        print(f"  transit {rec['time_s'] / transit:6.1f}: oil {rec['oil_m3'] * 2e12:7.1f} nl, "
              f"out / in {rec['outflow_over_supply']:5.3f}, width {rec['width_m'] / a:6.2f} a, "
              f"{rec['cells_opened_dry']} cells ran dry", file=sys.stderr, flush=True)
    return show


def _metrics_text(summary: dict[str, Any]) -> str:
    """The region's metrics in a few lines (lengths in a, oil in nl)."""
    m = summary["metrics"]
    fmt = lambda v: "-" if v is None else f"{v:.2f}"  # noqa: E731
    out = m["outflow_over_supply"]
    return (f"{summary['transits']:.1f} transits on {m['cell_over_a']:g} a cells, "
            f"{'balanced' if m['steady'] else 'not balanced'} "
            f"(outflow / supply {fmt(out)}), {summary['wall_s']:.0f} s\n"
            f"state {m['state']}, inlet meniscus {fmt(m['inlet_meniscus_distance_over_a'])} a, "
            f"flooded {fmt(m['flooded_length_over_a'])} x {fmt(m['flooded_width_over_a'])} a, "
            f"rear meniscus {fmt(m['rear_meniscus_x_over_a'])} a, "
            f"oil {m['oil_volume_m3'] * 1e12:.1f} nl, "
            f"mass balance error {m['oil_mass_balance_error']:.1e}")
