"""A 2D strip of the gap: the least OpenFOAM case of the flooded region's menisci.

A strip one cell wide (empty sides) along y = 0 of a case's gap, x from x_in to x_out, with
the level's wall layers across the gap, holds a bridge of oil between the two rolling walls.
Two cases are written on it:

- **the film strip** (:func:`write_strip_case`): both walls roll at u away from the contact,
  the supply (x_in) feeds all-oil at a flux u * film, and the bridge's rear meniscus recedes
  from the walls laying films behind it. At balance it sits where Landau-Levich's films take
  away what comes in: the deposited films against that law measure what a level's cells make
  of the films that set the flooded region's size (:mod:`ehlfoam.metrics.strip`);
- **the contact-line strip** (:func:`reverse_walls` on a film strip): both walls roll at -u,
  come in dry at x_out and advance into the bridge, which an oil reservoir at ambient
  pressure feeds at x_in. Where the meniscus stands says the apparent angle of the moving
  contact line a gap's size from the wall (:mod:`ehlfoam.thinfilm.bridge`).

SI units: lengths in m, speeds in m/s, times in s.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np
from foamlib import FoamFieldFile

from ehlfoam.case.wall_angle import wall_angle_entry
from ehlfoam.case.wall_slip import write_slip_walls
from ehlfoam.case.dictionaries import edit_physics_dicts, edit_run_control
from ehlfoam.case.fields import slip_walls, wall_layers_fraction
from ehlfoam.case.timestep import capillary_time_step
from ehlfoam.case.writer import TEMPLATES, extrude_level
from ehlfoam.mesh import BaseMesh, PolyMesh, split_patch, write_polymesh
from ehlfoam.spec.case import CaseSpec

__all__ = ["reverse_walls", "strip_mesh", "supply_cell_size", "write_strip_case"]

Gap = Callable[[np.ndarray, np.ndarray], np.ndarray]


def supply_cell_size(gap: Gap, x_in: float) -> float:
    """The smallest in-plane cell [m] at the supply x_in [m]: twice the lean h h' / 2 of the
    columns there at the ball (the extrusion's normal columns lean upstream onto the supply's
    upright ones, and turn the first cells inside out where these are finer than the lean;
    0.075 a at 9 a on the nominal gap)."""
    eps = 1e-3 * x_in
    h = float(gap(np.array([x_in]), np.array([0.0]))[0])
    slope = float(np.diff(gap(np.array([x_in - eps, x_in + eps]), np.zeros(2)))[0]) / (2 * eps)
    return h * abs(slope)


def _cell_edges(x_in: float, x_out: float, dx: float, s_in: float) -> np.ndarray:
    """The cells' edges along x [m]: dx, grown to s_in at the supply x_in over 20 s_in where
    s_in is larger."""
    graded = [x_in]
    while s_in > dx and graded[-1] < x_in + 20.0 * s_in:
        graded.append(graded[-1] + max(dx, s_in * (1.0 - (graded[-1] - x_in) / (20.0 * s_in))))
    n_uniform = max(int(round((x_out - graded[-1]) / dx)), 1)
    return np.concatenate([graded[:-1], np.linspace(graded[-1], x_out, n_uniform + 1)])


def strip_mesh(spec: CaseSpec, gap: Gap, x_in: float, x_out: float, dx: float) -> PolyMesh:
    """The strip x in [x_in, x_out] [m], one cell of dx [m] wide in y, of cells dx along x
    (coarser near the supply where dx is finer than :func:`supply_cell_size`), extruded across
    the gap on y = 0 with the spec's level's wall layers; patches supply (x_in), outlet, disc,
    ball and side (both y faces, empty: a 2D case)."""
    x = _cell_edges(x_in, x_out, dx, supply_cell_size(gap, x_in))
    n = len(x) - 1
    points = np.concatenate([np.stack([x, np.zeros_like(x)], 1),
                             np.stack([x, np.full_like(x, dx)], 1)])
    i = np.arange(n)
    quads = np.stack([i, i + 1, n + 2 + i, n + 1 + i], 1)          # counter-clockwise
    edges = {"inlet": np.array([[n + 1, 0]]), "outlet": np.array([[n, 2 * n + 1]]),
             "side": np.concatenate([np.stack([i, i + 1], 1),
                                     np.stack([n + 2 + i, n + 1 + i], 1)])}
    mesh = extrude_level(spec, BaseMesh(points, quads, edges),
                         lambda xs, ys: gap(xs, np.zeros_like(xs)))
    mesh = split_patch(mesh, "inlet", np.ones(mesh.patch("inlet").size, bool), "supply")
    mesh.patches = [replace(p, type="empty") if p.name == "side" else p for p in mesh.patches]
    return mesh


def write_strip_case(spec: CaseSpec, case: Path, mesh: PolyMesh, x_bridge: float,
                     film: float, dx: float, end_time: float, write_interval: float) -> float:
    """The film strip: the interface template on the strip ``mesh``, oil for x < x_bridge [m],
    the all-oil supply carrying ``film`` * u [m2/s], both walls at u, the spec's fluids and
    interface numerics, and the level's capillary step for in-plane cells of dx [m]; run to
    ``end_time`` [s], written every ``write_interval`` [s]. Replaces ``case``. Returns the
    step limit [s]."""
    if case.exists():
        shutil.rmtree(case)
    for part in ("system", "constant", "0.orig"):
        shutil.copytree(TEMPLATES / "interface" / part, case / part)
    write_polymesh(mesh, case)
    side = mesh.patch("side").type
    u = spec.wall_speed
    h_in = mesh.points[mesh.faces[mesh.patch_slice("supply")], 2].max()   # the gap at x_in
    with FoamFieldFile(case / "0.orig" / "U") as f:
        f.boundary_field["disc"]["value"] = np.array([u, 0.0, 0.0])
        f.boundary_field["ball"]["origin"] = np.array([0.0, 0.0, spec.contact.radius])
        f.boundary_field["ball"]["omega"] = -u / spec.contact.radius
        f.boundary_field["supply"]["value"] = np.array([u * film / h_in, 0.0, 0.0])
        f.boundary_field["side"] = {"type": side}
    with FoamFieldFile(case / "0.orig" / "alpha.oil") as f:
        f.internal_field = (mesh.cell_centres[:, 0] < x_bridge).astype(float)
        f.boundary_field['"(disc|ball|island)"'] = wall_angle_entry(spec)
        f.boundary_field["supply"]["value"] = 1.0
        f.boundary_field["side"] = {"type": side}
    with FoamFieldFile(case / "0.orig" / "p_rgh") as f:
        f.boundary_field["side"] = {"type": side}
    edit_physics_dicts(spec, case)
    dt = capillary_time_step(spec, dx)
    edit_run_control(spec, case, end_time, write_interval, min(dt, write_interval))
    shutil.copytree(case / "0.orig", case / "0")
    return dt


def reverse_walls(spec: CaseSpec, case: Path, mesh: PolyMesh | None = None,
                  precursor: float = 0.0) -> None:
    """Turn a film strip (:func:`write_strip_case`) into the contact-line strip: both walls at
    -u, and the supply an oil reservoir at ambient pressure (oil in, anything out). With a
    ``precursor`` [m] (and the strip's ``mesh``) the walls come in wetted by a layer that
    thick each instead of dry; with a Navier slip (physics.wall_slip_length, needs ``mesh``)
    they slip on every face."""
    u = spec.wall_speed
    with FoamFieldFile(case / "0.orig" / "U") as f:
        f.boundary_field["disc"]["value"] = np.array([-u, 0.0, 0.0])
        f.boundary_field["ball"]["omega"] = u / spec.contact.radius
        f.boundary_field["supply"] = {"type": "pressureInletOutletVelocity",
                                      "value": np.zeros(3)}
    with FoamFieldFile(case / "0.orig" / "p_rgh") as f:
        f.boundary_field["supply"] = {"type": "totalPressure", "p0": 0.0, "value": 0.0}
    with FoamFieldFile(case / "0.orig" / "alpha.oil") as f:
        f.boundary_field["supply"] = {"type": "inletOutlet", "inletValue": 1.0, "value": 1.0}
        if precursor > 0:
            if mesh is None:
                raise ValueError(f"precursor = {precursor!r} m: needs the strip's mesh")
            z = mesh.points[mesh.faces[mesh.patch_slice("outlet")], 2]
            frac = wall_layers_fraction(z.min(1), z.max(1), z.max(), precursor, precursor)
            f.boundary_field["outlet"] = {"type": "inletOutlet", "inletValue": frac,
                                          "value": frac}
    if spec.physics.wall_slip_length > 0:
        if mesh is None:
            raise ValueError(f"physics.wall_slip_length = {spec.physics.wall_slip_length!r} "
                             "m: the slipping walls need the strip's mesh")
        write_slip_walls(case / "0.orig" / "U", slip_walls(spec, mesh, -u, off_track=False))
    shutil.rmtree(case / "0")
    shutil.copytree(case / "0.orig", case / "0")
