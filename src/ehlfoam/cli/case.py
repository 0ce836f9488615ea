"""``ehlfoam case``: write an OpenFOAM case from a TOML case spec.

Exit codes: 0 written, 2 bad input (a bad spec or --set, an existing folder, a --out that
cannot be written or that OpenFOAM cannot take, a --start-from that does not fit, a mesh too
big; nothing left written).
"""

from __future__ import annotations

import argparse
from collections.abc import Iterable
from typing import Any

from ehlfoam.cli.common import EXIT_OK, add_command, print_notices, removed_on_failure

#: what --set's help says of its values (``ehlfoam thin-film --set`` too)
SET_HELP = ("override a spec value by its dotted key, e.g. --set contact.speed=0.017 --set "
            "mesh.resolution=coarse. The value is TOML: a number, true/false, a quoted or bare "
            "word (a string: \"0.02\" is not a number), a [list] or an {inline table}, whose "
            "keys are merged into the spec's table (--set 'mesh={n_layers=4}' keeps the "
            "file's other mesh keys); none clears an optional key (mesh.polar_radius=none). "
            "Types are strict: no true for a number, no string for a number (repeatable)")


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``ehlfoam case``."""
    p = add_command(
        subparsers, "case", help="write an OpenFOAM case from a case spec (TOML)",
        description="Validate the case spec, solve (or reuse) its EHL precalc, mesh the gap "
                    "around the contact and write a complete OpenFOAM case that also runs by "
                    "hand (DIR/Allrun). Exit 2 on bad input (the spec, --set, an --out that "
                    "cannot be written or whose path OpenFOAM cannot take), before anything "
                    "is written (docs/cli.md).",
        examples=["ehlfoam case examples/cases/nominal.toml --out runs/nominal "
                  "--set mesh.resolution=coarse",
                  "ehlfoam case examples/cases/nominal.toml --out runs/u17 "
                  "--set contact.speed=0.017 --start-from runs/nominal",
                  "ehlfoam case examples/cases/nominal.toml --out runs/nominal_tf "
                  "--rung thin-film-medium"])
    p.add_argument("spec", nargs="?", help="case spec TOML (default: the reference case)")
    p.add_argument("--out", required=True,
                   help="case folder to write; its path may not hold whitespace, quotes, a "
                        "backslash or any of *?[]{}$;<>|&` (OpenFOAM cannot take them)")
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help=SET_HELP)
    p.add_argument("--rung", default=None, metavar="RUNG",
                   help="the rung of the model ladder (the spec's `rung`, docs/ladder.md): "
                        "thin-film-LEVEL, LEVEL (3D) or resolved-LEVEL, LEVEL one of coarse, "
                        "medium, fine")
    p.add_argument("--overwrite", action="store_true", help="replace an existing case")
    p.add_argument("--start-from", default=None, metavar="CASE|SNAPSHOT.npz|STATE.npz",
                   help="start from the final fields of another run case (a converged "
                        "neighbour: another speed, supply or level), copied on the same "
                        "mesh, else interpolated; from a case snapshot (`ehlfoam "
                        "snapshot`); or from the oil of a thin-film state "
                        "(`ehlfoam thin-film` writes one). With mesh.follow the mesh follows its "
                        "meniscus (without it, the case starts from the thin-film balance of its "
                        "point: run.start = \"thin-film\", the resolved rungs)")
    p.set_defaults(func=cmd_case)
    return p


def parse_value(text: str, key: str = "KEY") -> Any:
    """A --set value: a TOML value (a number, a boolean, a quoted string, a [list], an
    {inline table}), a bare word that is not TOML (a string: ``mesh.resolution=coarse``), or
    ``none`` for an optional key's "not set" (e.g. ``mesh.polar_radius=none``: free quads).
    A value that starts as a quoted string, a list or a table but is not valid TOML raises
    :class:`~ehlfoam.errors.SpecError` naming ``key``."""
    import tomllib

    if text.strip().lower() == "none":
        return None
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError as err:
        if text.strip()[:1] in ("[", "{", '"', "'"):
            from ehlfoam.errors import SpecError

            raise SpecError(f"--set {key}={text}: not a valid TOML value ({err})") from None
        return text


def parse_overrides(items: Iterable[str] | None) -> dict[str, Any]:
    """``KEY=VALUE`` options as the spec's dotted-key overrides (values by
    :func:`parse_value`). Raises :class:`~ehlfoam.errors.SpecError` for an item without '='
    or without a key."""
    from ehlfoam.errors import SpecError

    out = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise SpecError(f"--set {item!r}: expected KEY=VALUE, e.g. contact.speed=0.017")
        out[key] = parse_value(value, key)
    return out


def cmd_case(args: argparse.Namespace) -> int:
    """Validate the spec and the output folder, then build the case (precalc, mesh, OpenFOAM
    files). Bad input raises :class:`~ehlfoam.errors.SpecError` (exit 2, see
    :mod:`ehlfoam.cli.failures`) before anything is written."""
    from ehlfoam.errors import SpecError
    from ehlfoam.paths import check_case_out
    from ehlfoam.spec.case import load_case_spec, make_case_spec

    from ehlfoam.case.bounds import check_work

    overrides = parse_overrides(args.set)
    if args.rung is not None:
        overrides["rung"] = args.rung
    spec = (load_case_spec(args.spec, **overrides) if args.spec
            else make_case_spec(None, **overrides))
    check_case_out(args.out, "--out")
    check_work(spec)   # mesh.max_cells, run.max_steps: before the precalc and the mesher
    if spec.mesh.follow is not None and not args.start_from and spec.run.start != "thin-film":
        raise SpecError("mesh.follow needs --start-from (a run case, a case snapshot or a "
                        "thin-film state) or run.start = \"thin-film\": the mesh follows "
                        "that state's meniscus")
    if args.start_from:
        from ehlfoam.seed.start import RampError, check_start

        try:   # before anything is written
            check_start(args.start_from, spec.scene)
        except (RampError, OSError) as err:   # missing, or not a folder
            raise SpecError(f"--start-from {args.start_from}: {err}") from None
    with removed_on_failure(args.out):
        return _write(spec, args)


def _write(spec, args: argparse.Namespace) -> int:
    from ehlfoam.case.geometry import mesh_warnings
    from ehlfoam.errors import SpecError
    from ehlfoam.seed.follow import write_started_case
    from ehlfoam.seed.mapping import oil_carried
    from ehlfoam.seed.start import RampError

    try:
        geom, seed = write_started_case(spec, args.out, args.start_from,
                                        overwrite=args.overwrite)
    except RampError as err:   # found only on the new mesh: no case was written
        raise SpecError(f"--start-from {args.start_from}: {err}") from None
    except ValueError as err:   # mesh.follow: the source has no meniscus to follow
        if spec.mesh.follow is None or isinstance(err, SpecError):
            raise               # a mesh too big, ...: bad input all the same (exit 2)
        raise SpecError(f"--start-from {args.start_from}: {err}") from None
    if seed is not None:
        at = ("" if seed["previous_time_s"] is None
              else f" at t = {seed['previous_time_s']:.4g} s")
        print(f"starts from {args.start_from}{at} ({seed['method']}: "
              f"{', '.join(seed['fields'])})")
        if seed.get("oil"):
            print(oil_carried(seed["oil"]))
    if spec.scene == "thin-film":   # no OpenFOAM: the model's grid (issue 74)
        until = (f"a cycle of at most {spec.cycle.passes_max} passes on a "
                 f"{spec.supply.track_radius * 1e3:g} mm track" if spec.supply.mode == "rig"
                 else f"end time {geom.end_time:.3g} s")
        print(f"case {args.out}: thin-film model, {geom.cells} cells of "
              f"{geom.min_cell_size / geom.a:g} a, a = {geom.a * 1e3:.4f} mm, transit "
              f"{geom.transit_time:.3g} s, {until}, step {geom.max_delta_t:.3g} s, "
              f"cavitation pressure {spec.physics.cavitation_pressure:g} Pa")
        return EXIT_OK
    print(f"case {args.out}: {geom.solver}, {geom.cells} cells, a = {geom.a * 1e3:.4f} mm, "
          f"transit {geom.transit_time:.3g} s, end time {geom.end_time:.3g} s, "
          f"maxDeltaT {geom.max_delta_t:.3g} s ({geom.capillary_limit}), "
          f"gap mismatch {geom.gap_mismatch:.2%}, ball wall steps {geom.ball_wall_steps:.1f}")
    print_notices("case", mesh_warnings(geom))
    return EXIT_OK
