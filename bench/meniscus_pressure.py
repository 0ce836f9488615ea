"""The oil's pressure at the flooded region's side menisci, and the contact angle it implies.

Across a thin gap h a meniscus between the oil and the air holds a pressure jump
p_oil - p_air = -2 sigma cos(theta) / h + sigma kappa, theta the meniscus's apparent contact
angle (the same on both walls), kappa the curvature of the region's outline in the plane
(positive where the region bulges out). Where the walls move along the meniscus, as on the
region's sides near its widest point, no contact line is driven and theta should be the
wall's static angle; in a volume-of-fluid run it is whatever the cells and the interface
compression make of it. This reads, at stations x / a on one side of the region (y > 0):

- the meniscus's position y_m at mid-gap (half the region's width there, as the run's metrics
  read it), the gap h there and the outline's curvature kappa (a parabola through its
  half-widths 1 a either side);
- the oil's mid-gap pressure p_rgh extrapolated to y_m by a straight line through the base
  cells 0.25-1 a inside it (the region's own pressure gradient taken out), and the air's, the
  median 0.25-1 a outside;
- theta = arccos((p_air - p_oil + sigma kappa) h / (2 sigma)).

    python bench/meniscus_pressure.py CASE[@T] [CASE[@T] ...] [--stations 0 2 4 6 8]
        [--save NAME.json]

(half domains only, as the nominal cases are.)
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from foamlib import FoamFieldFile

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.common import save  # noqa: E402
from bench.plot_midgap import _pick  # noqa: E402
from generator.case_writer import load_geometry, load_spec_of  # noqa: E402
from runs import case_fields, metrics  # noqa: E402

#: the pressure is read this far inside and outside the meniscus [a]
NEAR, FAR = 0.25, 1.0
#: the outline's curvature: a parabola through its half-widths at these offsets [a]
CURVATURE_OFFSETS = np.linspace(-1.0, 1.0, 9)
#: half-widths [a] of the strip along y the pressures are read in, tried in turn until the
#: strip holds cells inside and outside the meniscus
STRIP_HALF_WIDTHS = (0.1, 0.2, 0.35)


def apparent_angle(p_oil: float, p_air: float, gap: float, sigma: float,
                   outline_curvature: float = 0.0) -> float:
    """The contact angle [deg] a meniscus across a gap ``gap`` [m] holds between the oil's
    pressure ``p_oil`` and the air's ``p_air`` [Pa], with surface tension ``sigma`` [N/m] and
    the outline's in-plane curvature [1/m]; NaN where the jump is beyond any angle."""
    c = (p_air - p_oil + sigma * outline_curvature) * gap / (2.0 * sigma)
    return float(np.degrees(np.arccos(c))) if -1.0 <= c <= 1.0 else float("nan")


def side_menisci(case: Path, at: float | None, stations_over_a: list[float]) -> dict:
    """Per station: the side meniscus's position [a], gap [m], outline curvature [1/m], the
    oil's and the air's pressure at it [Pa] and the apparent angle [deg] (see the module)."""
    g, spec = load_geometry(case), load_spec_of(case)
    if not g.symmetric:
        raise SystemExit(f"meniscus_pressure: {case} is a full domain (half domains only)")
    st = case_fields.Structure.load(case)
    t, folder = case_fields.write_near(case, "last" if at is None else str(at), g.transit_time)
    oil = case_fields.mid_gap_alpha(folder, st, g)
    raster = case_fields.column_raster(oil, st, g)
    p = st.mid_gap(np.asarray(FoamFieldFile(folder / "p_rgh").internal_field, float),
                   g.n_layers)
    gaps = st.column_gaps()
    bx, by = st.base_x / g.a, st.base_y / g.a
    sigma = spec.physics.surface_tension
    rows = []
    for x in stations_over_a:
        w = metrics.flooded_widths_at(raster, (x + CURVATURE_OFFSETS) * g.a)
        if any(v is None for v in w):
            rows.append({"x_over_a": x, "y_over_a": None})
            continue
        c2, c1, _ = np.polyfit(CURVATURE_OFFSETS * g.a, np.array(w) / 2.0, 2)
        kappa = -2.0 * c2 / (1.0 + c1 ** 2) ** 1.5
        ym = w[len(w) // 2] / 2.0 / g.a
        for half in STRIP_HALF_WIDTHS:
            strip = np.abs(bx - x) < half
            inside = strip & (by > ym - FAR) & (by < ym - NEAR)
            outside = strip & (by > ym + NEAR) & (by < ym + FAR)
            at_line = strip & (np.abs(by - ym) < half)
            if inside.sum() >= 3 and outside.any() and at_line.any():
                break
        else:
            rows.append({"x_over_a": x, "y_over_a": ym})
            continue
        slope, icpt = np.polyfit(by[inside], p[inside], 1)
        p_oil, p_air = float(slope * ym + icpt), float(np.median(p[outside]))
        h = float(np.median(gaps[at_line]))
        rows.append({"x_over_a": x, "y_over_a": ym, "gap_m": h, "outline_curvature_1_m": kappa,
                     "p_oil_Pa": p_oil, "p_air_Pa": p_air,
                     "angle_deg": apparent_angle(p_oil, p_air, h, sigma, kappa)})
    return {"case": str(case), "transits": t / g.transit_time, "wall_angle_deg":
            spec.physics.contact_angle, "surface_tension": sigma, "stations": rows}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("cases", nargs="+", help="CASE or CASE@TRANSITS")
    ap.add_argument("--stations", nargs="+", type=float, default=[0.0, 2.0, 4.0, 6.0, 8.0],
                    help="x / a")
    ap.add_argument("--save", help="write bench/results/NAME.json")
    args = ap.parse_args(argv)
    results = [side_menisci(*_pick(c), args.stations) for c in args.cases]
    for r in results:
        print(f"{r['case']} at {r['transits']:.3f} transits (wall angle "
              f"{r['wall_angle_deg']:g} deg)")
        print("   x/a   y_m/a   h, um   R_plane, a   p_oil, Pa   p_air, Pa   angle, deg")
        for s in r["stations"]:
            if "angle_deg" not in s:
                print(f"  {s['x_over_a']:4.1f}   (no meniscus read)")
                continue
            k = s["outline_curvature_1_m"]
            radius = f"{1.0 / k / load_geometry(Path(r['case'])).a:10.1f}" if k else "       inf"
            print(f"  {s['x_over_a']:4.1f}  {s['y_over_a']:6.3f}  {s['gap_m'] * 1e6:6.1f}  "
                  f"{radius}   {s['p_oil_Pa']:9.1f}   {s['p_air_Pa']:9.1f}   "
                  f"{s['angle_deg']:6.1f}")
    if args.save:
        save(args.save, {"command": " ".join(sys.argv), "results": results})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
