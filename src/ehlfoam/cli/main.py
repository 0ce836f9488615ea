"""The ``ehlfoam`` command line.

Subcommands:
  doctor   show the OpenFOAM runtime and check its build (pitzDaily test)
  precalc  the EHL pre-calculation, registered by ``ehlfoam.cli.precalc``
  case     write an OpenFOAM case from a TOML case spec
  run      run a case to steady state and write its metrics.json
  band     bands of finer cells along a run's meniscus (for mesh.refine)
  snapshot a run case's state in one small file, to start other cases from
  report   an HTML report (pictures, plots, metrics) of a case or a batch
  batch    generate, run and report a batch of cases (sweeps, speed ramps)

Exit codes: 0 ok, 1 failure, 2 bad input.
"""

from __future__ import annotations

import os

# One OpenBLAS thread (unless the user chose otherwise): the flow-pattern raster makes
# thousands of tiny LAPACK calls, which an OpenBLAS thread pool slows from 0.02 s to seconds
# on cores busy with OpenFOAM (ehlfoam.report.threads). Effective when numpy loads after this.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import shutil
import sys
from collections.abc import Sequence

from ehlfoam.cli import precalc as precalc_cli
from ehlfoam.cli import batch as batch_cli
from ehlfoam.cli import thin_film as thin_film_cli
from ehlfoam.seed import snapshot as case_snapshot
from ehlfoam.seed import band as meniscus_band
from ehlfoam.seed.mapping import oil_carried
from ehlfoam.report import add_parser as _report_add_parser
from ehlfoam.foam.runtime import FoamConfigError, FoamError, FoamRuntime, check_build

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


def cmd_case(args: argparse.Namespace) -> int:
    """Validate the spec, then build the case (precalc, mesh, OpenFOAM files)."""
    from ehlfoam.errors import SpecError
    from ehlfoam.spec.case import load_case_spec, make_case_spec
    from ehlfoam.case.writer import CaseExists, mesh_warnings

    overrides = dict(kv.split("=", 1) for kv in args.set or [])
    try:
        overrides = {k: parse_value(v) for k, v in overrides.items()}
        spec = (load_case_spec(args.spec, **overrides) if args.spec
                else make_case_spec(None, **overrides))
    except (SpecError, ValueError) as err:
        print(f"ehlfoam case: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if spec.mesh.follow is not None and not args.start_from:
        print("ehlfoam case: mesh.follow needs --start-from (a run case, a case snapshot or a "
              "thin-film state): the mesh follows that state's meniscus", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.start_from:
        from ehlfoam.seed.start import RampError, check_start

        try:   # before anything is written
            check_start(args.start_from)
        except (RampError, OSError) as err:   # missing, or not a folder
            print(f"ehlfoam case: --start-from {args.start_from}: {err}", file=sys.stderr)
            return EXIT_BAD_INPUT
    from ehlfoam.seed.follow import write_started_case
    from ehlfoam.seed.start import RampError

    try:
        geom, seed = write_started_case(spec, args.out, args.start_from,
                                        overwrite=args.overwrite)
    except CaseExists as err:
        print(f"ehlfoam case: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except RampError as err:   # found only on the new mesh: leave no half-made case
        shutil.rmtree(args.out, ignore_errors=True)
        print(f"ehlfoam case: --start-from {args.start_from}: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except ValueError as err:   # mesh.follow: the source has no meniscus to follow
        if spec.mesh.follow is None:
            raise
        shutil.rmtree(args.out, ignore_errors=True)
        print(f"ehlfoam case: --start-from {args.start_from}: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if seed is not None:
        at = ("" if seed["previous_time_s"] is None
              else f" at t = {seed['previous_time_s']:.4g} s")
        print(f"starts from {args.start_from}{at} ({seed['method']}: "
              f"{', '.join(seed['fields'])})")
        if seed.get("oil"):
            print(oil_carried(seed["oil"]))
    print(f"case {args.out}: {geom.solver}, {geom.cells} cells, a = {geom.a * 1e3:.4f} mm, "
          f"transit {geom.transit_time:.3g} s, end time {geom.end_time:.3g} s, "
          f"maxDeltaT {geom.max_delta_t:.3g} s ({geom.capillary_limit}), "
          f"gap mismatch {geom.gap_mismatch:.2%}, ball wall steps {geom.ball_wall_steps:.1f}")
    for warning in mesh_warnings(geom):
        print(f"ehlfoam case: warning: {warning}", file=sys.stderr)
    return EXIT_OK


def parse_value(text: str):
    """A --set value: TOML scalar syntax (numbers, booleans, quoted or bare strings), or
    ``none`` for an optional key's "not set" (e.g. ``mesh.polar_radius=none``: free quads)."""
    import tomllib

    if text.strip().lower() == "none":
        return None
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not value > 0:
        raise argparse.ArgumentTypeError(f"{value} (valid range > 0)")
    return value


def cmd_run(args: argparse.Namespace) -> int:
    """Run a generated case and print its metrics."""
    import json

    from ehlfoam.run.monitor import CaseBusy, run_case

    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

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
            progress.console.print(_sample_line(sample, geom), highlight=False, soft_wrap=True)

    try:
        with progress:
            metrics = run_case(args.case, wall_limit=args.wall_limit, on_sample=on_sample,
                               extend_transits=args.extend)
    except (CaseBusy, FileNotFoundError) as err:
        print(f"ehlfoam run: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    keys = ("status", "end_reason", "state", "inlet_meniscus_distance_over_a",
            "inlet_meniscus_shape", "flooded_length_over_a", "flooded_width_over_a",
            "wake_gas_length_over_a", "bubble_length_over_a", "bubble_enclosed",
            "min_pressure_Pa", "oil_mass_balance_error", "simulated_time_s",
            "time_steps", "wall_s")
    print(json.dumps({k: metrics.get(k) for k in keys}))
    return EXIT_OK if metrics["status"] == "finished" else EXIT_FAILURE


def _sample_line(sample, geom) -> str:
    """One line per written time: time, transits, state, oil volume, menisci, bubble."""
    p = sample.pattern
    fmt = lambda v: "-" if v is None else f"{v:.2f}"  # noqa: E731
    return (f"t = {sample.time * 1e3:8.2f} ms ({sample.time / geom.transit_time:5.2f} transits)  "
            f"state {p.get('state')}  oil {sample.oil_volume * 1e12:9.4f} nl  "
            f"inlet meniscus {fmt(p.get('inlet_meniscus_distance_over_a'))} a  "
            f"flooded {fmt(p.get('flooded_length_over_a'))} x "
            f"{fmt(p.get('flooded_width_over_a'))} a  "
            f"bubble {fmt(p.get('bubble_length_over_a'))} a")


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

    case = sub.add_parser(
        "case", help="write an OpenFOAM case from a case spec (TOML)",
        description="Validate the case spec, solve (or reuse) its EHL precalc, mesh the gap "
                    "around the contact and write a complete OpenFOAM case that also runs by "
                    "hand (DIR/Allrun). Exit 2 on a bad spec, before anything is written.")
    case.add_argument("spec", nargs="?", help="case spec TOML (default: the reference case)")
    case.add_argument("--out", required=True, help="case folder to write")
    case.add_argument("--set", action="append", metavar="KEY=VALUE",
                      help="override a spec value, e.g. --set contact.speed=0.017 "
                           "--set mesh.resolution=coarse; none clears an optional key, e.g. "
                           "--set mesh.polar_radius=none (repeatable)")
    case.add_argument("--overwrite", action="store_true", help="replace an existing case")
    case.add_argument("--start-from", default=None, metavar="CASE|SNAPSHOT.npz|STATE.npz",
                      help="start from the final fields of another run case (a converged "
                           "neighbour: another speed, supply or level), copied on the same "
                           "mesh, else interpolated; from a case snapshot (`ehlfoam "
                           "snapshot`); or from the oil of a thin-film state "
                           "(`ehlfoam thin-film` writes them). With mesh.follow the "
                           "mesh follows its meniscus (needed then)")
    case.set_defaults(func=cmd_case)

    run = sub.add_parser(
        "run", help="run a case to steady state and write DIR/metrics.json",
        description="Run interFoam on a generated case, monitor oil volume and menisci from "
                    "outside, stop at steady state or a limit, write DIR/metrics.json and "
                    "DIR/history.csv. Exit 1 if the run failed.")
    run.add_argument("case", help="case folder written by `ehlfoam case`")
    run.add_argument("--wall-limit", type=float, default=None,
                     help="wall-clock limit [s] (default: the spec's run.wall_limit)")
    run.add_argument("--extend", type=_positive_float, default=None, metavar="TRANSITS",
                     help="go on for TRANSITS transit times past the latest written time (from 0 "
                          "in a case not run yet), whatever the steady-state tests say (does "
                          "a steady state last?)")
    run.add_argument("--quiet", action="store_true", help="no line per written time")
    run.set_defaults(func=cmd_run)

    meniscus_band.add_parser(sub)
    case_snapshot.add_parser(sub)
    _report_add_parser(sub)
    batch_cli.add_parser(sub)
    thin_film_cli.add_parser(sub)
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
