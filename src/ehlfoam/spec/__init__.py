"""The case spec: the validated description of an OpenFOAM case around the contact.

``load_case_spec(path)`` reads a TOML file, ``make_case_spec(data)`` validates nested data;
both return a frozen :class:`CaseSpec` or raise :class:`ehlfoam.errors.SpecError` naming the
parameter, its value and its valid range. Every field carries its description and unit
(``Field(description=..., json_schema_extra={"unit": ...})``).
"""

from ehlfoam.spec.case import SOLVERS, CaseSpec, load_case_spec, make_case_spec
from ehlfoam.spec.levels import (FOLLOW_BASE, FOLLOW_LEVELS, FOLLOW_POLAR_RADIUS,
                                 POLAR_RING_SHARE, RESOLUTIONS)
from ehlfoam.spec.mesh import Follow, Mesh, RefineBand, RefineBox, SideBox
from ehlfoam.spec.sections import Domain, DomainBox, Physics, Run, Supply

__all__ = [
    "FOLLOW_BASE",
    "FOLLOW_LEVELS",
    "FOLLOW_POLAR_RADIUS",
    "POLAR_RING_SHARE",
    "RESOLUTIONS",
    "SOLVERS",
    "CaseSpec",
    "Domain",
    "DomainBox",
    "Follow",
    "Mesh",
    "Physics",
    "RefineBand",
    "RefineBox",
    "Run",
    "SideBox",
    "Supply",
    "load_case_spec",
    "make_case_spec",
]
