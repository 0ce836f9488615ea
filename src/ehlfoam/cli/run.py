"""``ehlfoam run``: run a case to steady state and write its metrics.json.

Exit codes: 0 finished, 1 failed or stopped short (metrics.json says why), 2 bad input (no
such case, not a case, a corrupt case file, a path OpenFOAM cannot take, a read-only or full
disk, a case another process is running, a limit that is not a positive finite number,
run.n_procs above the usable cores without --oversubscribe, an extension beyond
run.max_steps; found before anything is written).
"""

from __future__ import annotations

import argparse
import json
import sys

from ehlfoam.cli.common import (EXIT_BAD_INPUT, EXIT_FAILURE, EXIT_OK, add_command,
                                check_case, positive_float, print_notices)

#: the metrics printed as the command's JSON line
KEYS = ("status", "end_reason", "reason", "state", "inlet_meniscus_distance_over_a",
        "inlet_meniscus_shape", "flooded_length_over_a", "flooded_width_over_a",
        "wake_gas_length_over_a", "bubble_length_over_a", "bubble_enclosed",
        "min_pressure_Pa", "oil_mass_balance_error", "simulated_time_s", "time_steps", "wall_s")


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``ehlfoam run``."""
    p = add_command(
        subparsers, "run", help="run a case to steady state and write DIR/metrics.json",
        description="Run interFoam on a generated case, monitor oil volume and menisci from "
                    "outside, stop at steady state or a limit, write DIR/metrics.json and "
                    "DIR/history.csv. Exit 1 if the run failed.",
        examples=["ehlfoam run runs/nominal", "ehlfoam run runs/nominal --extend 2 --quiet"])
    p.add_argument("case", help="case folder written by `ehlfoam case`")
    p.add_argument("--wall-limit", type=positive_float, default=None,
                   help="wall-clock limit [s] (default: the spec's run.wall_limit)")
    p.add_argument("--extend", type=positive_float, default=None, metavar="TRANSITS",
                   help="go on for TRANSITS transit times past the latest written time (from 0 "
                        "in a case not run yet), whatever the steady-state tests say (does "
                        "a steady state last?)")
    p.add_argument("--oversubscribe", action="store_true",
                   help="run even when run.n_procs is more than the CPU cores this process "
                        "may use (refused otherwise)")
    p.add_argument("--quiet", action="store_true", help="no line per written time")
    p.set_defaults(func=cmd_run)
    return p


def cmd_run(args: argparse.Namespace) -> int:
    """Check the case, run it, print its main metrics as one JSON line and its notices."""
    check_case(args.case, "CASE", writes=True)
    check_control_dict(args.case)
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    from ehlfoam.notices import from_text
    from ehlfoam.run.monitor import CaseBusy, run_case

    progress = Progress(TextColumn("{task.description}"), BarColumn(),
                        TextColumn("{task.fields[status]}"), TimeElapsedColumn(),
                        disable=args.quiet or not sys.stdout.isatty())
    task = progress.add_task(f"run {args.case}", total=1.0, status="starting")

    def on_sample(sample, geom) -> None:
        p = sample.pattern
        progress.update(task, completed=sample.time / geom.end_time,
                        status=f"t = {sample.time * 1e3:.1f} ms, state {p.get('state')}, "
                               f"oil {sample.oil_volume * 1e12:.2f} nl")
        if not args.quiet:
            progress.console.print(sample_line(sample, geom), highlight=False, soft_wrap=True)

    from ehlfoam.case.bounds import check_limit, check_wall_limit
    from ehlfoam.errors import SpecError

    try:
        if args.wall_limit is not None:   # the options by their names, before anything starts
            check_wall_limit(args.wall_limit, "--wall-limit")
        if args.extend is not None:
            check_limit("--extend", args.extend, "transits")
        with progress:
            metrics = run_case(args.case, wall_limit=args.wall_limit, on_sample=on_sample,
                               extend_transits=args.extend,
                               on_note=lambda line: print(f"ehlfoam run: {line}",
                                                          file=sys.stderr, flush=True),
                               oversubscribe=args.oversubscribe)
    except (CaseBusy, FileNotFoundError, SpecError) as err:
        print(f"ehlfoam run: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print(json.dumps({k: metrics.get(k) for k in KEYS}))
    print_notices("run", from_text(metrics.get("warnings")))
    return EXIT_OK if metrics["status"] == "finished" else EXIT_FAILURE


def check_control_dict(case) -> None:
    """The case's ``system/controlDict``, which the run edits (stopAt, endTime), must read as
    an OpenFOAM dictionary: :class:`~ehlfoam.errors.SpecError` naming it, before anything is
    written."""
    from pathlib import Path

    from foamlib import FoamFile

    from ehlfoam.cli.failures import foam_parse_text
    from ehlfoam.errors import SpecError

    path = Path(case) / "system" / "controlDict"
    if not path.is_file():
        raise SpecError(f"CASE {case}: it has no system/controlDict (not a complete case; "
                        f"write it again with ehlfoam case SPEC --out {case} --overwrite)")
    try:
        FoamFile(path).as_dict()
    except ValueError as err:   # foamlib's FoamFileDecodeError, a UnicodeDecodeError
        raise SpecError(f"CASE {case}: system/controlDict is not a valid OpenFOAM dictionary "
                        f"({foam_parse_text(err)}); write the case again with ehlfoam case SPEC --out {case} "
                        f"--overwrite") from None


def sample_line(sample, geom) -> str:
    """One line per written time: time, transits, state, oil volume, menisci, bubble."""
    p = sample.pattern

    def fmt(v: float | None) -> str:
        return "-" if v is None else f"{v:.2f}"

    return (f"t = {sample.time * 1e3:8.2f} ms ({sample.time / geom.transit_time:5.2f} transits)  "
            f"state {p.get('state')}  oil {sample.oil_volume * 1e12:9.4f} nl  "
            f"inlet meniscus {fmt(p.get('inlet_meniscus_distance_over_a'))} a  "
            f"flooded {fmt(p.get('flooded_length_over_a'))} x "
            f"{fmt(p.get('flooded_width_over_a'))} a  "
            f"bubble {fmt(p.get('bubble_length_over_a'))} a")
