"""How far behind the contact the oil stays below a pressure, on the centre line, at a case's
last write: the gap-averaged pressure of the columns, interpolated linearly onto y = 0 from
x = a to the outlet, and the largest x - a at which it is more than 1 kPa below ambient (the
open boundaries hold the total pressure at ambient, so the static pressure of the oil leaving
is a fraction of a pascal below it everywhere downstream) and below the gas-release pressure.

The Reynolds model of the reference calls its sub-ambient region the bubble (0.9 a at 20 mm/s,
25 C, 20 N); this gives the same reading of a finished case, e.g. one with (almost) nothing
released, to set beside the bubble the case makes (docs/cavitation.md, "A submerged contact").

    python bench/centreline_pressure.py CASE [CASE ...] [--below KPA ...]

``--below`` adds the reach below other absolute pressures [kPa], e.g. the release pressures
of other runs, to read them off a run that released nothing.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy.interpolate import LinearNDInterpolator

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from foamlib import FoamFieldFile  # noqa: E402

from ehlfoam.case.geometry import load_geometry
from ehlfoam.run import fields as case_fields

#: spacing of the samples along the centre line [a]
STEP = 0.02
#: "sub-ambient" means this far below ambient [Pa]
MARGIN = 1e3


def below_extents(case: str | Path, others: tuple[float, ...] = ()) -> dict:
    """The centre line's lowest gap-averaged pressure [Pa, absolute] behind the contact and
    the largest x - a [units of a] at which it is more than :data:`MARGIN` below ambient and
    below the release pressure, and ``below`` {pressure [Pa]: x - a} for ``others`` [Pa]."""
    case = Path(case)
    geom = load_geometry(case)
    structure = case_fields.Structure.load(case)
    _, last = case_fields.time_folders(case)[-1]
    p = np.asarray(FoamFieldFile(last / "p").internal_field, dtype=float)
    offset = 0.0 if geom.absolute_pressure else geom.ambient_pressure
    column_p = structure.gap_mean(p) + offset
    x, y = structure.base_x / geom.a, structure.base_y / geom.a
    if geom.symmetric:   # mirror the half domain so that y = 0 lies inside the triangulation
        x, y, column_p = (np.concatenate([x, x]), np.concatenate([y, -y]),
                          np.concatenate([column_p, column_p]))
    xs = np.arange(geom.island_radius / geom.a, geom.x_max / geom.a, STEP)
    ps = LinearNDInterpolator(np.column_stack([x, y]), column_p)(xs, np.zeros_like(xs))
    xs, ps = xs[np.isfinite(ps)], ps[np.isfinite(ps)]

    def reach(threshold: float) -> float:
        below = xs[ps < threshold]
        return float(below.max() - 1.0) if below.size else 0.0

    release = geom.release_pressure_gauge + geom.ambient_pressure
    return {"case": case.name, "time_s": float(last.name), "min_pressure_Pa": float(ps.min()),
            "sub_ambient_over_a": reach(geom.ambient_pressure - MARGIN),
            "below_release_over_a": reach(release), "release_pressure_Pa": release,
            "below": {q: reach(q) for q in others}}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="+")
    ap.add_argument("--below", nargs="+", type=float, default=[], metavar="KPA")
    args = ap.parse_args(argv)
    for case in args.cases:
        r = below_extents(case, tuple(1e3 * q for q in args.below))
        others = "".join(f", below {q / 1e3:g} kPa to {x:.2f} a" for q, x in r["below"].items())
        print(f"{r['case']} at {r['time_s']:.4g} s: lowest {r['min_pressure_Pa'] / 1e3:.0f} kPa "
              f"(abs); {MARGIN / 1e3:g} kPa below ambient to x - a = "
              f"{r['sub_ambient_over_a']:.2f} a, below {r['release_pressure_Pa'] / 1e3:g} kPa "
              f"to {r['below_release_over_a']:.2f} a{others}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
