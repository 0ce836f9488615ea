"""The time-step numbers of a case: the capillary limit on the smallest cell and the write
interval."""

from __future__ import annotations

import math

from ehlfoam.spec.case import CaseSpec

#: Galusinski & Vigneaux (2008) constants of the capillary time-step limit.
GV_C1, GV_C2 = 0.01, 10.0


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


def write_interval(spec: CaseSpec) -> float:
    """transit time / writes_per_transit, shortened so that the end time is a write time."""
    nominal = spec.transit_time / spec.run.writes_per_transit
    return spec.end_time / math.ceil(spec.end_time / nominal - 1e-9)
