"""The dictionaries of a case's ``constant/`` and ``system/`` folders: the fluids (transport
or thermophysical properties, the gas release), the interface numerics, the decomposition
and the run control."""

from __future__ import annotations

from pathlib import Path

from foamlib import FoamFile

from ehlfoam.spec.case import CaseSpec

#: The air of the cavitating scene, a perfect gas: molar mass [kg/mol] (the template's
#: molWeight) and specific gas constant [J/(kg K)].
AIR_MOLAR_MASS = 28.9e-3
AIR_GAS_CONSTANT = 8.314462618 / AIR_MOLAR_MASS
#: interIsoFoam's (isoAdvector's) controls, the values of its damBreak tutorial (read in a
#: later release's copy; v1912 ran with them): the tolerance on alpha where a cell is cut by
#: the isosurface, the band of alpha that makes a cell a surface cell, the bounding passes,
#: the snap to 0 and 1, and clipping to [0, 1]
ISOADVECTOR_CONTROLS = {"isoFaceTol": 1e-6, "surfCellTol": 1e-6, "nAlphaBounds": 3,
                        "snapTol": 1e-12, "clip": True}


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
        if spec.physics.interface_advection == "isoadvector":
            for key, value in ISOADVECTOR_CONTROLS.items():
                f["solvers"]['"alpha.oil.*"'][key] = value
    if spec.physics.interface_schemes == "balanced":
        _balance_interface_schemes(case)
    write_decomposition(case, spec.run.n_procs)


def write_decomposition(case: Path, n_procs: int) -> None:
    """system/decomposeParDict for ``n_procs`` ranks: slabs along x (method simple,
    ``n (n_procs 1 1)``). Written by the case writer and again by ``ehlfoam run`` before it
    decomposes, from the spec's run.n_procs (one source of truth)."""
    with FoamFile(case / "system" / "decomposeParDict") as f:
        f["numberOfSubdomains"] = n_procs
        f["method"] = "simple"
        f["coeffs"]["n"] = [n_procs, 1, 1]


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
    faces in a rolling case (docs/models/interface.md#numerics,
    docs/models/single-phase.md)."""
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
