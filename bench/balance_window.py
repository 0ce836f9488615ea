"""How well the oil balance of a finished run can be measured from written fields: re-run a
window of it with a write every few time steps and compare the balances that different write
densities and flux readings give.

    python bench/balance_window.py CASE --start-transits 1.5 --transits 1 --every 4
        [--c-alpha 0] [--work DIR] [--save NAME.json]

interPhaseChangeFoam (the gas-release scene) writes no alphaPhi, the oil flux it transported,
so its runs read the oil leaving through the open boundaries as phi x alpha at the writes
(``oil_flux_source`` in metrics.json). This script takes the written time folder nearest
``--start-transits`` from CASE, re-runs ``--transits`` transit times from it in a copy with a
write every ``--every`` steps, and prints, for every ``stride``-th write, the oil balance
residual (oil volume change minus the net inflow) with two readings of the outflow through the
faces open to the air: the written face alpha (what the monitor uses) and the alpha of the
cell behind the face (the upwind value; the face value where alpha is fixed). The gap between the two readings, and their drift
with the stride, bound what written fields can say about the balance. ``--c-alpha`` overrides
the interface compression of the re-run.
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

import numpy as np
from foamlib import FoamFieldFile, FoamFile

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.common import save  # noqa: E402
from ehlfoam.spec.case import SOLVERS
from ehlfoam.case.geometry import load_geometry, load_spec_of
from ehlfoam.run import fields as cf
from ehlfoam.foam.runtime import FoamRuntime

STRIDES = (1, 2, 5, 10, 25, 50)


def rerun_window(case: Path, work: Path, start_transits: float, transits: float, every: int,
                 c_alpha: float | None, solver: str | None = None) -> Path:
    """Copy ``case``'s mesh, set-up and the written time nearest ``start_transits`` into
    ``work`` and run ``transits`` transit times from there, writing every ``every`` steps,
    with the case's solver or ``solver``."""
    geom = load_geometry(case)
    folders = cf.time_folders(case)
    if not folders:
        raise FileNotFoundError(f"{case} has no written time folders to start from")
    t0, start = min(folders, key=lambda f: abs(f[0] - start_transits * geom.transit_time))
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    for name in ("constant", "system", "ehlfoam"):
        shutil.copytree(case / name, work / name)
    shutil.copytree(start, work / start.name)
    with FoamFile(work / "system" / "controlDict") as f:
        f["startFrom"], f["stopAt"] = "latestTime", "endTime"
        f["writeControl"], f["writeInterval"] = "timeStep", every
        f["endTime"] = t0 + transits * geom.transit_time
    if c_alpha is not None:
        with FoamFile(work / "system" / "fvSolution") as f:
            f["solvers"]['"alpha.oil.*"']["cAlpha"] = c_alpha
    solver = solver or SOLVERS[load_spec_of(case).scene]
    FoamRuntime.from_environment().run(solver, cwd=work, log_path=work / f"log.{solver}")
    return work


def outflow_readings(case: Path) -> dict[str, np.ndarray]:
    """Per write: time, oil volume, supply inflow and the outflow through the faces open to
    the air read with the face alpha and with the cell alpha (m3, m3/s, whole contact); and,
    where the solver wrote it (interFoam), the net outward oil flux it transported
    (alphaPhi0.oil, over all open boundaries; ``exact``, else NaN)."""
    st, geom = cf.Structure.load(case), load_geometry(case)
    owner = np.asarray(FoamFile(case / "constant" / "polyMesh" / "owner")[None])
    n_boundary = sum(size for _, size in st.patches.values())
    boundary_owner = owner[len(owner) - n_boundary:]
    rows = []
    for t, folder in cf.time_folders(case):
        alpha_file = FoamFieldFile(folder / "alpha.oil")
        alpha = np.asarray(cf._uniform_or_list(alpha_file.internal_field, len(st.cell_volumes)))
        phi = FoamFieldFile(folder / "phi").boundary_field
        q_in = q_face = q_cell = 0.0
        exact_file = folder / "alphaPhi0.oil"
        exact = FoamFieldFile(exact_file).boundary_field if exact_file.exists() else None
        q_exact = 0.0 if exact is not None else float("nan")
        for name in cf.OPEN_PATCHES:
            if name not in st.patches:
                continue
            start, size = st.patches[name]
            flux = np.asarray(cf._uniform_or_list(phi[name]["value"], size))
            if exact is not None:
                q_exact += float(np.sum(cf._uniform_or_list(exact[name]["value"], size)))
            face = np.clip(cf._uniform_or_list(alpha_file.boundary_field[name]["value"], size),
                           0.0, 1.0)
            if name == cf.SUPPLY_PATCH:
                q_in -= float(np.sum(flux * face))
                continue
            cell = (face if alpha_file.boundary_field[name]["type"] == "fixedValue"
                    else np.clip(alpha[boundary_owner[start:start + size]], 0.0, 1.0))
            out = np.maximum(flux, 0.0)
            q_face += float(np.sum(out * face))
            q_cell += float(np.sum(out * cell))
        rows.append((t, cf._oil_volume(alpha, st, geom), geom.mirror * q_in,
                     geom.mirror * q_face, geom.mirror * q_cell, geom.mirror * q_exact))
    t, volume, q_in, q_face, q_cell, q_exact = map(np.array, zip(*rows))
    return {"t": t, "volume": volume, "in": q_in, "out_face": q_face, "out_cell": q_cell,
            "net_out_exact": q_exact}


def balance_by_stride(r: dict[str, np.ndarray]) -> list[dict]:
    """The residual (volume change minus net inflow, trapezoid over every stride-th write and
    the last) for each stride and reading, also as a fraction of the outflow."""
    n, rows = len(r["t"]), []
    for stride in STRIDES:
        idx = np.arange(0, n, stride)
        if idx[-1] != n - 1:
            idx = np.append(idx, n - 1)
        if len(idx) < 2:
            continue
        t = r["t"][idx]
        carried_in = float(np.trapezoid(r["in"][idx], t))
        row = {"stride": stride, "writes": len(idx), "oil_in_m3": carried_in,
               "volume_change_m3": float(r["volume"][-1] - r["volume"][0])}
        for reading in ("face", "cell"):
            out = float(np.trapezoid(r[f"out_{reading}"][idx], t))
            residual = row["volume_change_m3"] - (carried_in - out)
            row[f"oil_out_{reading}_m3"] = out
            row[f"residual_{reading}_m3"] = residual
            row[f"residual_{reading}_over_out"] = residual / out if out > 0 else None
        if np.isfinite(r["net_out_exact"][1:]).all():   # the start folder was copied
            # alphaPhi0 written at a time is the flux of the step that ended there
            net_out = float(np.sum(r["net_out_exact"][idx[1:]] * np.diff(t)))
            row["residual_exact_m3"] = row["volume_change_m3"] + net_out
            row["residual_exact_over_out"] = (row["residual_exact_m3"]
                                              / (net_out + carried_in))
        rows.append(row)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("case", type=Path)
    ap.add_argument("--start-transits", type=float, required=True)
    ap.add_argument("--transits", type=float, default=1.0)
    ap.add_argument("--every", type=int, default=4, help="time steps between writes")
    ap.add_argument("--c-alpha", type=float, default=None)
    ap.add_argument("--solver", default=None,
                    help="re-run with this solver instead of the case's (interFoam writes "
                         "alphaPhi0.oil, the exact oil flux)")
    ap.add_argument("--work", type=Path, default=None,
                    help="where the re-run goes (default: CASE.balance_window)")
    ap.add_argument("--save", default=None, help="bench/results/NAME.json")
    args = ap.parse_args()
    if args.every < 1 or not args.transits > 0:
        ap.error(f"--every must be >= 1 and --transits > 0 (got {args.every}, {args.transits})")
    case = args.case.absolute()
    work = rerun_window(case, args.work or case.with_name(case.name + ".balance_window"),
                        args.start_transits, args.transits, args.every, args.c_alpha,
                        args.solver)
    r = outflow_readings(work)
    rows = balance_by_stride(r)
    print(f"{case}: {len(r['t'])} writes every {args.every} steps over {args.transits} transits "
          f"from {args.start_transits} transits")
    print("stride | writes | oil in [nl] | out, face alpha | residual / out | "
          "out, cell alpha | residual / out")
    for row in rows:
        print(f"{row['stride']:6d} | {row['writes']:6d} | {row['oil_in_m3'] * 1e12:11.3f} | "
              f"{row['oil_out_face_m3'] * 1e12:15.3f} | {100 * row['residual_face_over_out']:+13.2f} % | "
              f"{row['oil_out_cell_m3'] * 1e12:15.3f} | {100 * row['residual_cell_over_out']:+13.2f} %"
              + (f" | exact (alphaPhi0): {100 * row['residual_exact_over_out']:+.3f} %"
                 if "residual_exact_over_out" in row else ""))
    if args.save:
        print("wrote", save(args.save, {"args": {k: str(v) for k, v in vars(args).items()},
                                        "writes": len(r["t"]), "rows": rows}))


if __name__ == "__main__":
    main()
