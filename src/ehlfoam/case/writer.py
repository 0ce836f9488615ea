"""Write a complete OpenFOAM case from a :class:`~ehlfoam.spec.case.CaseSpec`.

    spec -> gap (ehl_precalc, cached) -> mesh (gmsh base, extruded on h) -> case

The case is the template folder ``templates/<scene>/`` copied and edited with foamlib (values
marked "set by the generator" in the templates), the mesh written directly as a polyMesh,
and ``ehlfoam/`` holding what the monitor and the metrics need (the spec, the geometry, the
mesh's 2D structure). The case also runs by hand: ``DIR/Allrun``, ``DIR/Allclean``.
"""

from __future__ import annotations

import math
import os
import shlex
import shutil
import tempfile
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from foamlib import FoamFieldFile, FoamFile

from ehlfoam._io import atomic_write_json, atomic_write_text
from ehlfoam.foam.runtime import FoamRuntime
from ehlfoam.notices import Notice

from ehlfoam.case import face_oil
from ehlfoam.spec.case import CaseSpec
from ehlfoam.case.foam_lists import fill_placeholders, placeholder
from ehlfoam.gap.source import load_gap
from ehlfoam.mesh.mesh import (BaseMesh, MeshParams, PolyMesh, build_base_mesh, extrude, gap_mismatch, split_patch, wall_steps, write_polymesh)
from ehlfoam.case.wall_slip import navier_slip, rolling_velocity, wall_normals, write_slip_walls

TEMPLATES = Path(__file__).resolve().parent / "templates"
META = "ehlfoam"  # the case's own folder of generator outputs

#: The air of the cavitating scene, a perfect gas: molar mass [kg/mol] (the template's
#: molWeight) and specific gas constant [J/(kg K)].
AIR_MOLAR_MASS = 28.9e-3
AIR_GAS_CONSTANT = 8.314462618 / AIR_MOLAR_MASS

#: Galusinski & Vigneaux (2008) constants of the capillary time-step limit.
GV_C1, GV_C2 = 0.01, 10.0


class CaseExists(FileExistsError):
    """The output folder exists and is not empty."""


@dataclass(frozen=True)
class CaseGeometry:
    """Numbers of a generated case that the run, the metrics and the reports need (SI)."""

    a: float
    radius: float
    speed: float
    x_min: float
    x_max: float
    y_max: float
    island_radius: float
    symmetric: bool
    n_layers: int
    cells: int
    transit_time: float
    end_time: float
    write_interval: float
    max_delta_t: float
    capillary_limit: str
    min_cell_size: float
    island_gap: float
    hc: float
    contact_flow: float
    gap_mismatch: float
    oil_viscosity: float
    oil_density: float
    solver: str = "interFoam"
    ambient_pressure: float = 1.013e5
    #: the gas-release scene's k [1/(Pa s)] (0: the scene releases nothing), its release
    #: pressure as the solver's gauge pSat [Pa], the oil's Bunsen coefficient for air, and
    #: the rate C [1/s] at which its gas dissolves back (0: never)
    gas_release_rate: float = 0.0
    gas_dissolution_rate: float = 0.0
    release_pressure_gauge: float = 0.0
    air_solubility: float = 0.09
    #: median over the base cells of the wall-cell heights the ball surface steps across a
    #: cell (ehlfoam.mesh.mesh.wall_steps); above BALL_WALL_STEPS_LIMIT a spurious film creeps
    #: along the ball (0: not computed, a case written before it existed)
    ball_wall_steps: float = 0.0
    #: the oil fraction of what flows in through the boundaries open to the outside: 0 (air)
    #: but where oil fills the domain (single-phase scene, submerged supply)
    open_inflow_oil: float = 0.0

    @property
    def mirror(self) -> float:
        """Factor from the meshed domain to the whole contact: 2 for a half domain, else 1."""
        return 2.0 if self.symmetric else 1.0

    @property
    def absolute_pressure(self) -> bool:
        """The solver's p is absolute (compressible scenes), else gauge (0 = ambient)."""
        return self.solver.startswith("compressible")

    @property
    def log_name(self) -> str:
        """The solver's log file in the case folder."""
        return f"log.{self.solver}"


# --------------------------------------------------------------- numbers
def size_function(spec: CaseSpec):
    """In-plane cell size [m] at (x, y): size_rim at the island rim, growing in proportion to
    the distance from the contact centre (the gap grows like r^2, the meniscus sits a few a
    out), capped at size_far; smaller where a refinement box (mesh.refine) asks for it."""
    level, a, ri = spec.mesh.level(), spec.a, spec.domain.island_radius * spec.a
    rim, far = level["size_rim"] * a, level["size_far"] * a
    boxes = spec.mesh.refine

    def size(x, y):
        x, y = np.asarray(x, float), np.asarray(y, float)
        out = np.clip(rim * np.hypot(x, y) / ri, rim, far)
        for box in boxes:
            out = np.minimum(out, box.size_at(x / a, y / a) * a)
        return out

    return size


def smallest_cell_size(spec: CaseSpec) -> float:
    """The smallest in-plane cell [m] :func:`size_function` asks for: the level's size at the
    island rim, or a refinement's (mesh.refine) where it is finer. The capillary time step is
    set for it: before 2026-11-27 it was set for the rim alone, so a band of 0.035 a cells on
    the fine level (rim 0.055 a) ran at a step 1.6 times its own limit, and the 2D strip shows
    films that double at such steps (docs/cases.md, "The films' own time step")."""
    sizes = [spec.mesh.level()["size_rim"]] + [box.size for box in spec.mesh.refine]
    return min(sizes) * spec.a


def capillary_time_step(spec: CaseSpec, dx: float) -> float:
    """Surface-tension time-step limit [s] for in-plane cells of size dx [m].

    Galusinski-Vigneaux: dt <= 0.5 (c2 mu dx/sigma + sqrt((c2 mu dx/sigma)^2 + 4 c1 rho dx^3/sigma)),
    with the mean of the two viscosities and densities: its viscous term governs at Re << 1.
    Brackbill: dt <= sqrt(rho dx^3 / (2 pi sigma)). "none": no limit (inf).
    """
    p = spec.physics
    sigma = p.surface_tension
    rho = 0.5 * (spec.oil_density + p.air_density)
    mu = 0.5 * (spec.oil_viscosity + spec.air_viscosity)
    kind = spec.run.capillary_limit
    if kind == "brackbill":
        dt = math.sqrt(rho * dx**3 / (2.0 * math.pi * sigma))
    elif kind == "galusinski-vigneaux":
        v = GV_C2 * mu * dx / sigma
        dt = 0.5 * (v + math.sqrt(v * v + 4.0 * GV_C1 * rho * dx**3 / sigma))
    else:
        return math.inf
    return dt * spec.run.capillary_safety


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


def extrude_level(spec: CaseSpec, base: BaseMesh, gap) -> PolyMesh:
    """``base`` extruded across ``gap(x, y)`` [m] in the spec's layers: the level's count and
    wall grading, or one wall cell height everywhere (``mesh.wall_cell``)."""
    level = spec.mesh.level()
    return extrude(base, gap, level["n_layers"], level["wall_grading"] or 1.0,
                   spec.mesh.columns, wall_cell=level["wall_cell"])


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


# ----------------------------------------------------------------- writing
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


def _edit_fields(spec: CaseSpec, case: Path, mesh: PolyMesh, fraction: np.ndarray, gap,
                 geom: CaseGeometry) -> None:
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
        f.boundary_field['"(disc|ball|island)"']["theta0"] = spec.physics.contact_angle
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
    if not geom.symmetric:
        with FoamFieldFile(case / "0.orig" / "p_rgh") as f:
            del f.boundary_field["symmetry"]
    if spec.scene == "cavitating":
        _edit_thermo_fields(spec, case, geom)


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


def _edit_dicts(spec: CaseSpec, case: Path, geom: CaseGeometry) -> None:
    edit_physics_dicts(spec, case)
    edit_run_control(spec, case, geom.end_time, geom.write_interval, geom.max_delta_t)


def edit_physics_dicts(spec: CaseSpec, case: Path) -> None:
    """Write ``spec``'s fluids, interface numerics and decomposition into the template's
    constant/ and system/ dictionaries of ``case`` (everything but the run control)."""
    if spec.scene == "cavitating":
        _edit_thermo(spec, case)
    else:
        _edit_transport(spec, case)
    with FoamFile(case / "system" / "fvSolution") as f:
        f["solvers"]['"alpha.oil.*"']["cAlpha"] = spec.physics.interface_compression
        f["solvers"]['"alpha.oil.*"']["icAlpha"] = spec.physics.isotropic_compression
        f["PIMPLE"]["nCorrectors"] = spec.run.pressure_correctors
        if spec.run.alpha_subcycles is not None:
            f["solvers"]['"alpha.oil.*"']["nAlphaSubCycles"] = spec.run.alpha_subcycles
    if spec.physics.interface_schemes == "balanced":
        _balance_interface_schemes(case)
    with FoamFile(case / "system" / "decomposeParDict") as f:
        f["numberOfSubdomains"] = spec.run.n_procs
        f["coeffs"]["n"] = [spec.run.n_procs, 1, 1]


def edit_run_control(spec: CaseSpec, case: Path, end_time: float, write_interval: float,
                     max_delta_t: float) -> None:
    """system/controlDict: the solver, the time limit and write interval [s], the Courant
    limits and the largest step [s] (the capillary limit, :func:`capillary_time_step`)."""
    with FoamFile(case / "system" / "controlDict") as f:
        f["application"] = spec.solver
        f["endTime"] = end_time
        f["writeInterval"] = write_interval
        f["maxCo"] = spec.run.max_courant
        f["maxAlphaCo"] = spec.run.max_alpha_courant
        f["maxDeltaT"] = max_delta_t


def _balance_interface_schemes(case: Path) -> None:
    """``physics.interface_schemes = "balanced"``: the pressure and the surface tension take
    their face gradients the same, uncorrected way (so that a resting meniscus can be in
    exact discrete balance on non-orthogonal faces), the interface normal comes from a
    smoother point-cells least-squares gradient, and the compression flux is limited to the
    interface. Calmer at rest, but the uncorrected gradients are an error on non-orthogonal
    faces in a rolling case (docs/cases.md)."""
    with FoamFile(case / "system" / "fvSchemes") as f:
        f["snGradSchemes"]["default"] = "uncorrected"
        f["laplacianSchemes"]["default"] = ("Gauss", "linear", "uncorrected")
        f["gradSchemes"]["nHat"] = "pointCellsLeastSquares"
        f["divSchemes"]["div(phirb,alpha)"] = ("Gauss", "interfaceCompression")


def _edit_transport(spec: CaseSpec, case: Path) -> None:
    """interFoam's two incompressible phases and the surface tension; in the gas-release
    scene also interPhaseChangeFoam's mass transfer (:func:`gas_release_entries`)."""
    p = spec.physics
    with FoamFile(case / "constant" / "transportProperties") as f:
        f["oil"]["nu"] = spec.oil_viscosity / spec.oil_density
        f["oil"]["rho"] = spec.oil_density
        f["air"]["nu"] = spec.air_viscosity / p.air_density
        f["air"]["rho"] = p.air_density
        f["sigma"] = p.surface_tension
        if spec.scene == "gas-release":
            for key, value in gas_release_entries(spec).items():
                f[key] = value


def release_pressure_gauge(spec: CaseSpec) -> float:
    """The gas-release scene's release pressure as its solver sees it: gauge [Pa]."""
    return spec.physics.cavitation_pressure - spec.physics.ambient_pressure


def release_geometry(spec: CaseSpec) -> dict:
    """The :class:`CaseGeometry` fields of the gas release that the run's budget check reads:
    k (0 unless the scene releases gas), the release pressure as pSat and the Bunsen
    coefficient."""
    p = spec.physics
    releases = spec.scene == "gas-release"
    return {"gas_release_rate": p.gas_release_rate if releases else 0.0,
            "release_pressure_gauge": release_pressure_gauge(spec),
            "air_solubility": p.air_solubility,
            "gas_dissolution_rate": p.gas_dissolution_rate if releases else 0.0}


def gas_release_entries(spec: CaseSpec) -> dict:
    """interPhaseChangeFoam's Kunz model as a gas release: below pSat (the cavitation
    pressure, gauge like the solver's p) oil turns into gas at
    mdot = Cv rho_gas / (0.5 rho_oil UInf^2 tInf) (pSat - p) alpha_oil [kg/(m3 s)], i.e.
    k (pSat - p) volumes of gas per volume of oil per second with UInf = tInf = 1 and
    Cv = 0.5 rho_oil k. Above pSat gas goes back into the oil at
    mdot = Cc rho_gas / tInf alpha_oil^2 (1 - alpha_oil): Cc = physics.gas_dissolution_rate,
    0 by default (the gas is never dissolved back)."""
    p = spec.physics
    return {"phaseChangeTwoPhaseMixture": "Kunz",
            "pSat": release_pressure_gauge(spec),
            "KunzCoeffs": {"UInf": 1.0, "tInf": 1.0, "Cc": p.gas_dissolution_rate,
                           "Cv": 0.5 * spec.oil_density * p.gas_release_rate}}


def _edit_thermo(spec: CaseSpec, case: Path) -> None:
    """compressibleInterFoam's phases: the oil incompressible (rhoConst), or a perfect fluid
    when a bulk modulus K is given (rho = rho0 + p/(R T), R = K/(rho0 T)); the air a perfect
    gas; surface tension and the pressure floor (the cavitation pressure)."""
    p, const = spec.physics, case / "constant"
    with FoamFile(const / "thermophysicalProperties") as f:
        f["sigma"] = p.surface_tension
        f["pMin"] = p.cavitation_pressure
    with FoamFile(const / "thermophysicalProperties.oil") as f:
        if p.oil_bulk_modulus is None:
            f["mixture"]["equationOfState"] = {"rho": spec.oil_density}
        else:
            f["thermoType"]["equationOfState"] = "perfectFluid"
            f["mixture"]["equationOfState"] = {
                "R": p.oil_bulk_modulus / (spec.oil_density * spec.temperature_k),
                "rho0": spec.oil_density}
        f["mixture"]["transport"]["mu"] = spec.oil_viscosity
    with FoamFile(const / "thermophysicalProperties.air") as f:
        f["mixture"]["transport"]["mu"] = spec.air_viscosity
        f["mixture"]["specie"]["molWeight"] = AIR_MOLAR_MASS * 1e3


def _write_scripts(case: Path, runtime: FoamRuntime, n_procs: int, solver: str) -> None:
    """Fill the runtime into the hand-runnable Allrun (launch words, application folder)."""
    argv = runtime.command("APP")
    app_path = Path(argv[-1])
    values = {"@FOAM_LAUNCH@": shlex.join(argv[:-1]),
              "@FOAM_BIN@": str(app_path.parent) if app_path.is_absolute() else "",
              "@WM_PROJECT_DIR@": runtime.env({}).get("WM_PROJECT_DIR", ""),
              "@NPROCS@": str(n_procs),
              "@SOLVER@": solver,
              "@PARALLEL_SOLVER@": shlex.join(runtime.mpi_command(solver, n_procs, "."))
              if n_procs > 1 else "false"}  # the serial branch runs instead
    text = (case / "Allrun").read_text()
    for key, value in values.items():
        text = text.replace(key, value)
    (case / "Allrun").write_text(text)


#: the median ball wall steps (ehlfoam.mesh.mesh.wall_steps) above which a case is flagged: the
#: three levels give 7-9; at 15-90 (thinner wall cells under the same in-plane cells) a
#: spurious oil film creeps along the ball beside the flooded region and 10-54 % of the
#: outflow leaves through the side (docs/cases.md, "Thinner wall cells: the ball's stair-steps")
BALL_WALL_STEPS_LIMIT = 10.0


def mesh_warnings(geom: CaseGeometry) -> list[Notice]:
    """What is wrong with a written case's mesh though it runs: the ball's wall cells
    stair-stepping above :data:`BALL_WALL_STEPS_LIMIT`. `ehlfoam case` prints these, and every
    run records them in metrics.json (``warnings``), which a batch shows."""
    if geom.ball_wall_steps <= BALL_WALL_STEPS_LIMIT:
        return []
    return [Notice("ball-wall-steps",
                   f"the ball's wall cells step {geom.ball_wall_steps:.1f} heights per cell "
                   f"(above {BALL_WALL_STEPS_LIMIT:g}): a spurious oil film creeps along the "
                   f"ball, thin mesh.n_layers need finer in-plane cells",
                   "docs/models/mesh.md#wall-cells")]


def case_mesh(spec: CaseSpec, gap) -> tuple[MeshParams, BaseMesh, PolyMesh, np.ndarray]:
    """The mesh :func:`write_case` writes for ``spec`` on the gap h(x, y) [m]: its parameters,
    the 2D base mesh, the extruded mesh with its supply patch, and the supply faces' oil
    fractions."""
    a, d = spec.a, spec.domain
    params = MeshParams(x_min=-d.upstream * a, x_max=d.downstream * a, y_max=d.side * a,
                        island_radius=d.island_radius * a, n_layers=spec.mesh.level()["n_layers"],
                        symmetric=d.symmetry == "half",
                        polar_radius=None if spec.polar_radius is None
                        else spec.polar_radius * a)
    base = build_base_mesh(params, size_function(spec))
    mesh, supply = with_supply_patch(spec, extrude_level(spec, base, gap))
    return params, base, mesh, supply


def write_case(spec: CaseSpec, out: str | os.PathLike, runtime: FoamRuntime | None = None,
               overwrite: bool = False) -> CaseGeometry:
    """Build the case of ``spec`` in ``out`` (atomically: built in a temporary sibling folder
    and renamed into place). Returns the case's :class:`CaseGeometry`."""
    out = Path(out)
    if spec.mesh.follow is not None:
        raise ValueError("mesh.follow needs the state the case starts from, whose meniscus "
                         "the mesh follows: ehlfoam case SPEC --out DIR --start-from SOURCE "
                         "(ehlfoam.seed.follow.write_started_case)")
    if out.exists() and any(out.iterdir()):
        if not overwrite:
            raise CaseExists(f"output folder {out} exists and is not empty (use --overwrite)")
    runtime = runtime or FoamRuntime.from_environment()
    gap, precalc = load_gap(spec.contact)
    level, a = spec.mesh.level(), spec.a
    params, base, mesh, supply = case_mesh(spec, gap)
    steps = float(np.median(wall_steps(base, mesh)))
    dx = smallest_cell_size(spec)
    dt = capillary_time_step(spec, dx)
    write_interval = _write_interval(spec)
    summary = _read_json(precalc / "summary.json")
    hc = float(summary["hc_m"])
    geom = CaseGeometry(
        a=a, radius=spec.contact.radius, speed=spec.speed, x_min=params.x_min,
        x_max=params.x_max, y_max=params.y_max, island_radius=params.island_radius,
        symmetric=params.symmetric, n_layers=params.n_layers, cells=len(mesh.cell_volumes),
        transit_time=spec.transit_time, end_time=spec.end_time,
        write_interval=write_interval,
        max_delta_t=min(dt, write_interval),
        capillary_limit=spec.run.capillary_limit, min_cell_size=dx,
        island_gap=float(gap(np.array([params.island_radius]), np.array([0.0]))[0]),
        hc=hc, contact_flow=spec.speed * hc * 2.0 * a,
        gap_mismatch=gap_mismatch(mesh, gap),
        oil_viscosity=spec.oil_viscosity, oil_density=spec.oil_density,
        solver=spec.solver, ambient_pressure=spec.physics.ambient_pressure,
        **release_geometry(spec), ball_wall_steps=steps,
        open_inflow_oil=1.0 if spec.fills_domain else 0.0)

    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}."))
    try:
        shutil.copytree(TEMPLATES / _template_for(spec), tmp, dirs_exist_ok=True)
        write_polymesh(mesh, tmp)
        _edit_fields(spec, tmp, mesh, supply, gap, geom)
        _edit_dicts(spec, tmp, geom)
        _write_scripts(tmp, runtime, spec.run.n_procs, spec.solver)
        meta = tmp / META
        meta.mkdir()
        atomic_write_text(meta / "spec.json", spec.model_dump_json(indent=2) + "\n")
        atomic_write_json(meta / "geometry.json", asdict(geom))
        _save_structure(meta / "mesh.npz", mesh)
        shutil.copytree(precalc, tmp / "precalc")
        if out.exists():
            shutil.rmtree(out)
        os.replace(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return geom


def _write_interval(spec: CaseSpec) -> float:
    """transit time / writes_per_transit, shortened so that the end time is a write time."""
    nominal = spec.transit_time / spec.run.writes_per_transit
    return spec.end_time / math.ceil(spec.end_time / nominal - 1e-9)


def _template_for(spec: CaseSpec) -> str:
    return {"interface": "interface", "single-phase": "interface",
            "cavitating": "cavitating", "gas-release": "interface"}[spec.scene]


def _read_json(path: Path) -> dict:
    import json

    return json.loads(path.read_text())


def _save_structure(path: Path, mesh: PolyMesh) -> None:
    """What the monitor needs to read fields without parsing the polyMesh: per cell its
    centre, volume, 2D base cell and layer; the boundary patches' face ranges."""
    names = np.array([p.name for p in mesh.patches])
    starts = np.array([p.start for p in mesh.patches])
    sizes = np.array([p.size for p in mesh.patches])
    n_internal = len(mesh.neighbour)
    with open(path, "wb") as fh:
        np.savez_compressed(fh, cell_centres=mesh.cell_centres, cell_volumes=mesh.cell_volumes,
                            base_cell=mesh.base_cell, layer=mesh.layer, patch_names=names,
                            patch_starts=starts - n_internal, patch_sizes=sizes,
                            face_centres_boundary=mesh.face_centres[n_internal:])


def load_geometry(case: str | os.PathLike) -> CaseGeometry:
    """The :class:`CaseGeometry` a generated case was written with."""
    return CaseGeometry(**_read_json(Path(case) / META / "geometry.json"))


def load_spec_of(case: str | os.PathLike) -> CaseSpec:
    """The spec a generated case was written from."""
    return CaseSpec.model_validate_json((Path(case) / META / "spec.json").read_text())
