"""``ehlfoam precalc``: solve the EHL contact and write summary.json, solution.npz, precalc.png.

Exit codes: 0 converged, 3 not converged (outputs written, ``converged: false``), 2 bad
input: a bad value (NaN and inf too) or a --out that cannot be written, found before solving
(nothing written).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import TYPE_CHECKING

from ehlfoam.cli.common import EXIT_NOT_CONVERGED, EXIT_OK, add_command, removed_on_failure

if TYPE_CHECKING:
    from ehlfoam.contact.spec import PrecalcSpec

_OPTIONS = {
    # flag: (spec key, type, help with units)
    "--load": ("load", float, "normal load F [N] (default 20)"),
    "--speed": ("speed", float, "rolling speed u [m/s] (default 0.01)"),
    "--temperature": ("temperature", float, "oil temperature [C] (default 40)"),
    "--lubricant": ("lubricant", str, "tabulated oil (HVI60) or 'custom'"),
    "--eta0": ("eta0", float, "custom oil: ambient viscosity [Pa s]"),
    "--alpha": ("alpha", float, "custom oil: pressure-viscosity coefficient [1/Pa]"),
    "--rho0": ("rho0", float, "custom oil: density [kg/m3]"),
    "--radius": ("radius", float, "ball radius [m] (default 9.525e-3)"),
    "--modulus": ("modulus", float, "reduced modulus E' [Pa] (default 1.11e11)"),
    "--viscosity": ("viscosity", str, "roelands (default) or barus"),
    "--density": ("density", str, "dowson-higginson (default) or incompressible"),
    "--cavitation": ("cavitation", str, "complementarity (default, p >= 0) or twophase"),
    "--twophase-coupling": ("twophase_coupling", str, "twophase only: coupled (default, the "
                            "sub-ambient pressures' deformation and load included) or one-way"),
    "--inlet-layer": ("inlet_layer", float, "starved inlet: oil layer carried in, both "
                      "surfaces together [m] (default: fully flooded)"),
    "--inlet-meniscus": ("inlet_meniscus", float, "starved inlet: meniscus distance upstream "
                         "of x = -a [a] (default: fully flooded)"),
    "--grid": ("grid", int, "grid points per side, 2^k+1 or 3*2^k+1 (default: chosen from M)"),
    "--max-cycles": ("max_cycles", int, "multigrid cycle limit (default 100)"),
}


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``precalc`` subcommand."""
    p = add_command(
        subparsers, "precalc", help="solve the EHL contact (gap and film) of one operating point",
        description="Solve the isothermal EHL point contact (Reynolds + elastic deformation + "
                    "load balance) and write DIR/summary.json (SI units), DIR/solution.npz and "
                    "DIR/precalc.png. Exit 3 if not converged (outputs written), 2 on bad "
                    "input (nothing solved, nothing written).",
        examples=["ehlfoam precalc --load 20 --speed 0.008 --temperature 40 --out precalc/u8",
                  "ehlfoam precalc --speed 0.5 --grid 129 --out precalc/fast"])
    p.add_argument("spec_file", nargs="?", help="TOML spec (keys as the options, without --)")
    for flag, (_, _, help_) in _OPTIONS.items():
        p.add_argument(flag, default=None, help=help_)   # converted by spec_from_args
    p.add_argument("--out", required=True, help="output folder")
    p.set_defaults(func=run)
    return p


def _convert(flag: str, raw: str | None):
    from ehlfoam.contact.spec import valid_range
    from ehlfoam.errors import SpecError

    if raw is None:
        return None
    key, typ, _ = _OPTIONS[flag]
    kind = "an integer" if typ is int else "a number"
    try:
        value = typ(raw)
    except ValueError:
        value = None
    if value is None or (typ is float and not math.isfinite(value)):
        rng = valid_range(key)
        finite = "a finite number" if value is not None else kind
        raise SpecError(f"invalid input: {flag} {raw}: not {finite}"
                        + (f" ({rng})" if rng else "")) from None
    return value


def spec_from_args(args: argparse.Namespace) -> PrecalcSpec:
    """The contact spec of the options (over the TOML spec file, if given)."""
    from ehlfoam.contact.spec import load_spec, make_spec

    values = {_OPTIONS[f][0]: _convert(f, getattr(args, f[2:].replace("-", "_")))
              for f in _OPTIONS}
    if args.spec_file:
        return load_spec(args.spec_file, **values)
    return make_spec(**values)


def run(args: argparse.Namespace) -> int:
    """Check the spec and the output folder, solve, write the outputs, print the summary's
    main numbers as one JSON line. Bad input raises (exit 2, nothing solved or written)."""
    from ehlfoam.paths import check_output

    spec = spec_from_args(args)
    check_output(args.out, "--out")            # before solving: a precalc that cannot write
    from ehlfoam.contact.outputs import write_all   # does not solve first
    from ehlfoam.contact.solver import GRID_ERROR_WARN, solve

    result = solve(spec)
    with removed_on_failure(args.out):
        summary = write_all(result, args.out)
    keys = ("M", "L", "hc_m", "hmin_m", "p_max_Pa", "converged", "residual", "load_error",
            "grid", "wall_s")
    print(json.dumps({k: summary[k] for k in keys}))
    error = summary["hc_grid_error"]
    if error is not None and error > GRID_ERROR_WARN:
        print(f"ehlfoam precalc: warning: hc is some {error:.1%} or more off its "
              f"grid-converged value on {summary['grid'][1]} points a side (the estimate's "
              f"limit: {GRID_ERROR_WARN:.0%}): a finer --grid gives about a quarter of that "
              f"per doubling (docs/models/contact.md)", file=sys.stderr)
    if not result.converged:
        print(f"ehlfoam precalc: NOT converged: {result.mg.failure}", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    return EXIT_OK
