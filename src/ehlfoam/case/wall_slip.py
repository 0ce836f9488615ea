"""Navier slip on a moving wall, as v1912's ``directionMixed`` velocity condition.

With no slip and a static contact angle the viscous stress at a moving contact line is singular
and a volume-of-fluid method cuts it off at its cells: where the walls drive into the oil (the
flooded region's front and sides) the line's apparent angle then depends on the cells
(docs/models/interface.md#the-contact-line-model-and-what-converges). A slip length lambda that
the cells resolve removes the singularity at a length of the model's, not the mesh's: the
wall's fluid moves with it but for lambda times the shear, u_s - U_w = lambda du/dn.

v1912 has no Navier slip condition and nothing can be compiled here, but ``directionMixed``
holds it on a fixed mesh: the normal part of the velocity fixed to the wall's (no flow
through it), the tangential part a mix of the wall's velocity and the wall cell's,

    U_f = U_w + (1 - f) (I - n n) (U_c - U_w),    f = delta / (delta + lambda),

which is the discrete u_s - U_w = lambda (U_c - u_s) / delta across the wall cell's
centre-to-face distance delta (OpenFOAM's 1 / deltaCoeffs on a wall). lambda = 0 gives f = 1,
no slip.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from foamlib import FoamFieldFile

from ehlfoam.case.foam_lists import fill_placeholders, placeholder
from ehlfoam.mesh import PolyMesh


def wall_normals(mesh: PolyMesh, patch: str) -> np.ndarray:
    """Unit normals (F, 3) of a patch's faces, out of the domain."""
    sf = mesh.face_areas[mesh.patch_slice(patch)]
    return sf / np.linalg.norm(sf, axis=1, keepdims=True)


def rolling_velocity(mesh: PolyMesh, patch: str, origin: np.ndarray, omega: np.ndarray
                     ) -> np.ndarray:
    """The velocity [m/s] (F, 3) of a patch's faces on a rigid body turning at ``omega``
    [rad/s, vector] about ``origin`` [m], its normal part removed (as v1912's
    ``rotatingWallVelocity`` does, for a surface that is not exactly the body's)."""
    n = wall_normals(mesh, patch)
    u = np.cross(np.asarray(omega, float), mesh.face_centres[mesh.patch_slice(patch)]
                 - np.asarray(origin, float))
    return u - n * np.einsum("fd,fd->f", n, u)[:, None]


def slip_fraction(mesh: PolyMesh, patch: str, slip_length: float | np.ndarray) -> np.ndarray:
    """f = delta / (delta + lambda) on each face of a patch: the share of the wall cell's
    tangential velocity relative to the wall that the wall holds (1: no slip). delta [m] is
    the owner cell centre's distance from the face along its normal, ``slip_length`` [m] one
    for the patch or one per face."""
    if not np.all(np.asarray(slip_length) >= 0.0):
        raise ValueError(f"slip_length: {np.min(slip_length)} (valid range >= 0 m)")
    sl = mesh.patch_slice(patch)
    n = wall_normals(mesh, patch)
    delta = np.abs(np.einsum("fd,fd->f", n, mesh.face_centres[sl]
                             - mesh.cell_centres[mesh.owner[sl]]))
    return delta / (delta + slip_length)


def navier_slip(mesh: PolyMesh, patch: str, wall_velocity: np.ndarray,
                slip_length: float | np.ndarray) -> dict:
    """The ``directionMixed`` entry of U on a wall moving at ``wall_velocity`` [m/s] ((3,) or
    one per face (F, 3), tangent to the wall) with a Navier slip length [m] (one, or one per
    face): valueFraction
    n n + f (I - n n) per face (symmTensor xx xy xz yy yz zz), f from :func:`slip_fraction`."""
    n = wall_normals(mesh, patch)
    f = slip_fraction(mesh, patch, slip_length)
    u = np.broadcast_to(np.asarray(wall_velocity, float), n.shape).copy()
    nn = n[:, :, None] * n[:, None, :]
    vf = nn + f[:, None, None] * (np.eye(3) - nn)
    sym = vf[:, [0, 0, 0, 1, 1, 2], [0, 1, 2, 1, 2, 2]]
    return {"type": "directionMixed", "refValue": u, "refGradient": np.zeros_like(u),
            "valueFraction": sym, "value": u}


def write_slip_walls(u_file: Path, entries: dict[str, dict]) -> None:
    """Put patches' :func:`navier_slip` entries into the U file ``u_file``. foamlib writes the
    entries with a placeholder word for each list, and the lists are written here: it takes
    ``valueFraction`` for a uniform value, and a patch of 3, 6 or 9 faces' list for a tensor."""
    lists: dict[str, np.ndarray] = {}
    with FoamFieldFile(u_file) as f:
        for patch, entry in entries.items():
            words = {}
            for key, value in entry.items():
                if isinstance(value, np.ndarray):
                    words[key] = placeholder(patch, key)
                    lists[words[key]] = value
            f.boundary_field[patch] = {**entry, **words}
    fill_placeholders(u_file, lists)
