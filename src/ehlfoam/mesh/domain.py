"""The thin-gap domain: its parameters, its patches and the 2D base mesh.

All lengths are SI metres. Coordinates: x is the rolling direction, y the lateral direction,
z across the gap; the origin is the contact centre. The disc is the plane z = 0, the ball the
surface z = h(x, y).

Patches (names and OpenFOAM types): ``disc`` (wall, z = 0), ``ball`` (wall, z = h),
``island`` (wall, the hole's rim), ``inlet`` (patch, x = x_min), ``outlet`` (patch,
x = x_max), ``side`` (patch, \\|y\\| = y_max) and, in the half domain only, ``symmetry``
(symmetryPlane, y = 0).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ehlfoam.spec.sections import DomainBox

#: Patch name -> OpenFOAM patch type, in the order the patches are written.
PATCH_TYPES: dict[str, str] = {
    "disc": "wall",
    "ball": "wall",
    "island": "wall",
    "inlet": "patch",
    "outlet": "patch",
    "side": "patch",
    "symmetry": "symmetryPlane",
}
#: The patches made from 2D boundary edges (the others are the disc and ball).
EDGE_PATCHES: tuple[str, ...] = ("island", "inlet", "outlet", "side", "symmetry")

#: Default upper bound on the number of 2D quads the size field may ask for.
DEFAULT_MAX_QUADS = 2_000_000

SizeFunction = Callable[[np.ndarray, np.ndarray], np.ndarray]
GapFunction = Callable[[np.ndarray, np.ndarray], np.ndarray]



def _require_finite(name: str, value: float) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite number in metres, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be a finite number in metres, got {value!r}")
    return v


def check_n_layers(n_layers: object) -> int:
    if isinstance(n_layers, bool) or not isinstance(n_layers, (int, np.integer)) or n_layers < 1:
        raise ValueError(f"n_layers must be an integer >= 1 (cells across the gap), "
                         f"got {n_layers!r}")
    return int(n_layers)


@dataclass(frozen=True, kw_only=True)
class MeshParams(DomainBox):
    """The thin-gap domain (:class:`~ehlfoam.spec.sections.DomainBox`, metres) and what the
    mesher needs beside it: ``n_layers``, the number of cells across the gap, and
    ``polar_radius`` [m] (None: no ring), the outer radius of a structured polar ring around
    the island (see :func:`build_base_mesh`), which must lie between the island and the
    nearest boundary."""

    n_layers: int
    polar_radius: float | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        check_n_layers(self.n_layers)
        if self.polar_radius is not None:
            rp = _require_finite("polar_radius", self.polar_radius)
            r = float(self.island_radius)
            nearest = min(-float(self.x_min), float(self.x_max), float(self.y_max))
            if not r < rp < nearest:
                raise ValueError(
                    f"polar_radius must lie between island_radius = {r:.6g} m and the nearest "
                    f"boundary ({nearest:.6g} m from the centre), got {self.polar_radius!r}")


@dataclass
class BaseMesh:
    """A 2D all-quad mesh (metres).

    ``points`` (n, 2); ``quads`` (m, 4) node ids, counter-clockwise seen
    from +z; ``edges`` patch name -> (k, 2) boundary edges (node ids),
    oriented so that their quad lies on the left (i.e. counter-clockwise
    along the quad).
    """

    points: np.ndarray
    quads: np.ndarray
    edges: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def n_points(self) -> int:
        return len(self.points)

    @property
    def n_quads(self) -> int:
        return len(self.quads)

    def quad_areas(self) -> np.ndarray:
        """Signed area of every quad (m^2; positive when counter-clockwise)."""
        p = self.points[self.quads]                     # (m, 4, 2)
        q = np.roll(p, -1, axis=1)
        return 0.5 * np.sum(p[..., 0] * q[..., 1] - q[..., 0] * p[..., 1], axis=1)
