"""The initial and boundary fields of a case (``0.orig/``): the oil at t = 0, the supply
faces' oil and speed, the walls' velocities (rolling, sliding on the island, Navier slip off
the track) and, in the cavitating scene, the ambient pressure and temperature."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from foamlib import FoamFieldFile

from ehlfoam._io import atomic_write_text
from ehlfoam.case import face_oil
from ehlfoam.case.foam_lists import fill_placeholders, placeholder
from ehlfoam.case.geometry import CaseGeometry
from ehlfoam.case.stop import stop_entries, write_boundary_data
from ehlfoam.case.wall_angle import wall_angle_entry
from ehlfoam.case.wall_slip import navier_slip, rolling_velocity, wall_normals, write_slip_walls
from ehlfoam.mesh import PolyMesh, split_patch
from ehlfoam.spec.case import CaseSpec


def _overlap(lo, hi, a, b):
    """Length of [lo, hi] inside [a, b] (arrays)."""
    return np.clip(np.minimum(hi, b) - np.maximum(lo, a), 0.0, None)


def oil_fraction(spec: CaseSpec, z_lo, z_hi, gap_h, on_track) -> np.ndarray:
    """Oil fraction of cells or faces spanning z in [z_lo, z_hi] of a column of gap gap_h [m]:
    the supply layers on the disc and the ball ("layers") or the whole height ("flooded"),
    times ``on_track`` (bool, or the fraction of the face on the track)."""
    s = spec.supply
    if s.mode == "flooded":
        frac = np.ones_like(np.asarray(z_hi - z_lo, dtype=float))
    else:
        frac = wall_layers_fraction(z_lo, z_hi, gap_h, s.disc_layer, s.ball_layer)
    return frac * np.asarray(on_track, dtype=float)


def wall_layers_fraction(z_lo, z_hi, gap_h, disc_layer, ball_layer) -> np.ndarray:
    """Oil fraction (0-1) of cells or faces spanning z in [z_lo, z_hi] of a column of gap
    gap_h, holding an oil layer of ``disc_layer`` on the disc (z = 0) and one of
    ``ball_layer`` on the ball (z = gap_h); any one length unit, arrays broadcast."""
    span = np.maximum(z_hi - z_lo, 1e-300)
    disc = _overlap(z_lo, z_hi, 0.0, np.minimum(disc_layer, gap_h))
    ball = _overlap(z_lo, z_hi, np.maximum(gap_h - ball_layer, disc_layer), gap_h)
    return np.clip((disc + ball) / span, 0.0, 1.0)


def initial_alpha(spec: CaseSpec, mesh: PolyMesh, gap) -> np.ndarray:
    """alpha.oil at t = 0: the supply layers on the track, a puddle of radius
    initial_puddle a around the contact (whole gap height) and a gas seed of radius
    initial_bubble a on the island's downstream rim; all oil for single-phase, and all oil
    but the seed for a submerged supply."""
    if spec.scene == "single-phase":
        return np.ones(len(mesh.cell_volumes))
    x, y = mesh.cell_centres[:, 0], mesh.cell_centres[:, 1]
    h = gap(x, y)
    on_track = ((np.abs(y) < spec.supply.track_half_width)
                & (np.abs(y) >= spec.supply.track_inner_half_width))
    alpha = oil_fraction(spec, h * mesh.spans[:, 0], h * mesh.spans[:, 1], h, on_track)
    puddle = spec.fills_domain | (np.hypot(x, y) < spec.supply.initial_puddle * spec.a)
    alpha = np.where(puddle, 1.0, alpha)
    rim = spec.domain.island_radius * spec.a
    seed = np.hypot(x - rim, y) < spec.supply.initial_bubble * spec.a
    return np.where(seed, 0.0, alpha)


def supply_fraction(spec: CaseSpec, mesh: PolyMesh, patch: str = "inlet") -> np.ndarray:
    """Oil fraction of each face of ``patch`` in the supply: the share of its area, projected
    across the flow, inside the oil layers (or the whole height, flooded) on the track, so
    that the oil carried in is exact on any cells (:mod:`ehlfoam.case.face_oil`); 0 everywhere
    where oil fills the domain (single-phase, submerged: the open boundaries bring oil in)."""
    faces = mesh.faces[mesh.patch_slice(patch)]
    if spec.fills_domain:
        return np.zeros(len(faces))
    s = spec.supply
    fractions = np.empty(len(faces))
    for i, (face, node) in enumerate(zip(faces, mesh.base_node(faces))):
        tops = mesh.points[mesh.top_point(np.unique(node))][:, 1:]     # the ball, (y, z)
        fractions[i] = face_oil.oil_fraction(
            mesh.points[face][:, 1:], (tops[0], tops[-1]), s.disc_layer, s.ball_layer,
            (s.track_inner_half_width, s.track_half_width), flooded=s.mode == "flooded")
    return fractions


def with_supply_patch(spec: CaseSpec, mesh: PolyMesh) -> tuple[PolyMesh, np.ndarray]:
    """Split the inlet: faces that carry oil in become the ``supply`` patch (fixed inflow at
    the rolling speed), the rest stays an open boundary at ambient pressure. Returns the mesh
    and the oil fraction of each supply face, in the supply patch's face order."""
    frac = supply_fraction(spec, mesh)
    carries = frac > 1e-6
    return split_patch(mesh, "inlet", carries, "supply"), frac[carries]


def slip_walls(spec: CaseSpec, mesh: PolyMesh, speed: float, off_track: bool = True
               ) -> dict[str, dict]:
    """U's entries for the disc, at (speed, 0, 0), and the ball, rolling on it at ``speed``
    [m/s], with the Navier slip length physics.wall_slip_length (:mod:`ehlfoam.case.wall_slip`)
    where the walls come in dry: off the supply track (|y| beyond supply.track_half_width or
    inside supply.track_inner_half_width), where the flooded region meets them in moving
    contact lines. On the track they come in wetted and keep no slip, so the flow that sets
    the inlet meniscus is the no-slip one. ``off_track`` False: slip on every face."""
    lam, radius = spec.physics.wall_slip_length, spec.contact.radius
    ball = rolling_velocity(mesh, "ball", np.array([0.0, 0.0, radius]),
                            np.array([0.0, -speed / radius, 0.0]))
    entries = {}
    for patch, velocity in (("disc", np.array([speed, 0.0, 0.0])), ("ball", ball)):
        y = np.abs(mesh.face_centres[mesh.patch_slice(patch), 1])
        dry = ((y > spec.supply.track_half_width) | (y < spec.supply.track_inner_half_width)
               if off_track else np.ones(len(y), bool))
        entries[patch] = navier_slip(mesh, patch, velocity, np.where(dry, lam, 0.0))
    return entries


def island_velocity(spec: CaseSpec, mesh: PolyMesh) -> np.ndarray:
    """Velocity of the island faces: (u, 0, 0) projected on the wall (no through-flow)."""
    n = wall_normals(mesh, "island")
    u = np.array([spec.wall_speed, 0.0, 0.0])
    return u - n * (n @ u)[:, None]


def supply_faces(spec: CaseSpec, fraction: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """alpha.oil and U [m/s] on the supply faces whose oil fractions are ``fraction``.

    Each face carries its oil fraction f of oil and the rest air, both at the rolling speed u,
    except in the gas-release scene: interPhaseChangeFoam (unlike interFoam and
    compressibleInterFoam) compresses the interface across boundary faces too, which on a
    face that is part oil moves oil through the patch outside its flux (5.6 % of the oil
    carried in on the tiny test case, 0.02 % without). There each face is all oil at f u:
    the same oil flux, the air entering beside it through the open inlet."""
    u = np.array([spec.wall_speed, 0.0, 0.0])
    if spec.scene == "gas-release":
        return np.ones_like(fraction), np.outer(fraction, u)
    return fraction, u


def edit_fields(spec: CaseSpec, case: Path, mesh: PolyMesh, fraction: np.ndarray, gap,
                 geom: CaseGeometry) -> None:
    """Write ``spec``'s initial and boundary values into the template's ``0.orig/`` fields of
    ``case``: the walls' and the supply's velocities, the oil at t = 0 and on the supply faces
    (whose oil fractions are ``fraction``), the contact angle, the Navier slip and, in the
    cavitating scene, the thermodynamic fields."""
    u = spec.wall_speed
    supply, supply_u = supply_faces(spec, fraction)
    with FoamFieldFile(case / "0.orig" / "U") as f:
        f.boundary_field["disc"]["value"] = np.array([u, 0.0, 0.0])
        f.boundary_field["ball"]["origin"] = np.array([0.0, 0.0, spec.contact.radius])
        f.boundary_field["ball"]["omega"] = -u / spec.contact.radius
        f.boundary_field["island"]["value"] = island_velocity(spec, mesh)
        f.boundary_field["supply"]["value"] = supply_u
        if not geom.symmetric:
            del f.boundary_field["symmetry"]
    with FoamFieldFile(case / "0.orig" / "alpha.oil") as f:
        f.internal_field = initial_alpha(spec, mesh, gap)
        f.boundary_field['"(disc|ball|island)"'] = wall_angle_entry(spec)
        if len(supply):
            f.boundary_field["supply"]["value"] = (supply if len(supply) not in (3, 6, 9)
                                                   else placeholder("supply", "value"))
        if spec.fills_domain:   # oil everywhere: oil is what flows in
            f.boundary_field['"(outlet|side)"']["inletValue"] = 1.0
            f.boundary_field["inlet"]["value"] = 1.0
        if not geom.symmetric:
            del f.boundary_field["symmetry"]
    if len(supply) in (3, 6, 9):
        fill_placeholders(case / "0.orig" / "alpha.oil", {placeholder("supply", "value"): supply})
    if spec.physics.wall_slip_length > 0:
        write_slip_walls(case / "0.orig" / "U", slip_walls(spec, mesh, u))
    if spec.stop.at is not None:
        _stop_walls(spec, case, mesh, supply_u)
    if not geom.symmetric:
        with FoamFieldFile(case / "0.orig" / "p_rgh") as f:
            del f.boundary_field["symmetry"]
    if spec.scene == "cavitating":
        _edit_thermo_fields(spec, case, geom)


def _stop_walls(spec: CaseSpec, case: Path, mesh: PolyMesh, supply_u: np.ndarray) -> None:
    """The walls' velocities as the stop has them over time (:mod:`ehlfoam.case.stop`): the
    disc's and a uniform supply's as tables, the ball's omega as one, the island's and a
    supply's of differing faces mapped from boundaryData."""
    tables = stop_entries(spec)
    mapped = {"island": island_velocity(spec, mesh)}
    words = {"disc": tables["disc"]}
    if np.ndim(supply_u) == 1:
        words["supply"] = tables["disc"]
    elif len(supply_u):
        mapped["supply"] = supply_u
    with FoamFieldFile(case / "0.orig" / "U") as f:
        for patch in words:
            f.boundary_field[patch]["type"] = "uniformFixedValue"
            f.boundary_field[patch]["uniformValue"] = placeholder(patch, "uniformValue")
        f.boundary_field["ball"]["omega"] = placeholder("ball", "omega")
        for patch in mapped:
            f.boundary_field[patch]["type"] = "timeVaryingMappedFixedValue"
            f.boundary_field[patch]["mapMethod"] = "nearest"
            f.boundary_field[patch]["setAverage"] = False
    text = (case / "0.orig" / "U").read_text()
    for word, table in [(placeholder(p, "uniformValue"), t) for p, t in words.items()] + [
            (placeholder("ball", "omega"), tables["ball"])]:
        text = text.replace(word, table)
    atomic_write_text(case / "0.orig" / "U", text)
    for patch, values in mapped.items():
        write_boundary_data(spec, case, patch, mesh.face_centres[mesh.patch_slice(patch)],
                            values)


def _edit_thermo_fields(spec: CaseSpec, case: Path, geom: CaseGeometry) -> None:
    """The cavitating scene's absolute pressure (ambient at the open boundaries) and T."""
    p_amb, temp = spec.physics.ambient_pressure, spec.temperature_k
    # boundary values are written out (not $internalField): a ramp step replaces the internal
    # field by a list, and v1912 cannot expand a list macro twice
    with FoamFieldFile(case / "0.orig" / "p_rgh") as f:
        f.internal_field = p_amb
        f.boundary_field['"(disc|ball|island|supply)"']["value"] = p_amb
        f.boundary_field['"(inlet|outlet|side)"']["p0"] = p_amb
        f.boundary_field['"(inlet|outlet|side)"']["value"] = p_amb
    with FoamFieldFile(case / "0.orig" / "p") as f:
        f.internal_field = p_amb
        f.boundary_field['".*"']["value"] = p_amb
        if not geom.symmetric:
            del f.boundary_field["symmetry"]
    with FoamFieldFile(case / "0.orig" / "T") as f:
        f.internal_field = temp
        f.boundary_field["supply"]["value"] = temp
        f.boundary_field['"(inlet|outlet|side)"']["inletValue"] = temp
        f.boundary_field['"(inlet|outlet|side)"']["value"] = temp
        if not geom.symmetric:
            del f.boundary_field["symmetry"]
