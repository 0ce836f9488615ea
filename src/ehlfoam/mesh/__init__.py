"""The thin-gap mesh: a 2D all-quad gmsh mesh extruded across the gap.

All lengths are SI metres. Coordinates: x is the rolling direction, y the lateral direction,
z across the gap; the origin is the contact centre. The disc is the plane z = 0, the ball the
surface z = h(x, y). Three steps, each usable on its own:

:func:`build_base_mesh` (:mod:`.base`)
    A 2D mesh of the domain around the island (:class:`MeshParams`, :mod:`.domain`), of the
    cell size a callable ``size(x, y)`` asks for (a case's: :func:`size_function`,
    :mod:`.sizing`), with an optional structured polar ring around the island.
:func:`extrude` (:mod:`.extrude`)
    The 2D mesh extruded into hexahedra whose ``n_layers`` layers follow the local gap
    (:mod:`.layers`: uniform or graded toward the walls).
:func:`write_polymesh` (:mod:`.polymesh`)
    The OpenFOAM ``constant/polyMesh`` files (ASCII), written directly by numpy.
"""

from ehlfoam.mesh.base import build_base_mesh
from ehlfoam.mesh.domain import PATCH_TYPES, BaseMesh, MeshParams
from ehlfoam.mesh.extrude import COLUMNS, extrude, gap_mismatch, wall_steps
from ehlfoam.mesh.layers import column_fractions, layer_fractions
from ehlfoam.mesh.polymesh import Patch, PolyMesh, split_patch, write_polymesh
from ehlfoam.mesh.sizing import REFINE_GROWTH, refinement_size, size_function, smallest_cell_size

__all__ = [
    "COLUMNS",
    "PATCH_TYPES",
    "REFINE_GROWTH",
    "BaseMesh",
    "MeshParams",
    "Patch",
    "PolyMesh",
    "build_base_mesh",
    "column_fractions",
    "extrude",
    "gap_mismatch",
    "layer_fractions",
    "refinement_size",
    "size_function",
    "smallest_cell_size",
    "split_patch",
    "wall_steps",
    "write_polymesh",
]
