"""The mesh levels a case spec names (``mesh.resolution``), and the polar ring's default size.

In-plane sizes are in units of the Hertzian radius a, wall cells in metres.
"""

from __future__ import annotations

#: In-plane cell size at the island rim and far away (a), cells across the gap and their
#: grading toward the walls, per level. The wall cell is 2.4 / 1.7 / 1.2 % of the local gap,
#: fine enough to hold the oil films left behind the flooded region (a few per cent of the
#: gap).
RESOLUTIONS: dict[str, dict[str, float]] = {
    "coarse": {"size_rim": 0.12, "size_far": 0.8, "n_layers": 10, "wall_grading": 8.0},
    "medium": {"size_rim": 0.08, "size_far": 0.55, "n_layers": 12, "wall_grading": 10.0},
    "fine": {"size_rim": 0.055, "size_far": 0.38, "n_layers": 14, "wall_grading": 12.0},
}

#: The levels whose mesh follows the start state's meniscus (``mesh.follow``): a band of
#: in-plane cells of ``band`` (a) along the meniscus, twice as fine on the region's sides
#: (``mesh.follow.sides``), and one wall cell of ``wall_cell`` [m] everywhere, on the base
#: cells and layers of :data:`FOLLOW_BASE`. The wall cell halves with the side cells, as the
#: contact-line model needs (``physics.wall_slip_length``: the slip resolved along the wall
#: as well as across it). The levels of :data:`RESOLUTIONS` leave the meniscus in their
#: base cells.
FOLLOW_LEVELS: dict[str, dict[str, float]] = {
    "coarse": {"band": 0.24, "wall_cell": 1.6e-6},
    "medium": {"band": 0.12, "wall_cell": 0.8e-6},
    "fine": {"band": 0.06, "wall_cell": 0.4e-6},
}

#: Base cells of the following levels: the coarse level's in-plane sizes (the bands carry the
#: resolution where the meniscus is) and 20 layers across the gap.
FOLLOW_BASE: dict[str, float] = {"size_rim": RESOLUTIONS["coarse"]["size_rim"],
                                 "size_far": RESOLUTIONS["coarse"]["size_far"],
                                 "n_layers": 20}

#: mesh.polar_radius = "auto" with mesh.follow: the polar ring ends at this radius (a), twice
#: the default island's, so that the bands (which refine free quads only) reach the meniscus.
FOLLOW_POLAR_RADIUS = 3.0

#: mesh.polar_radius = "auto": the polar ring's outer radius over the nearest boundary's
#: distance (6.8 a in the default 8 a wide half domain).
POLAR_RING_SHARE = 0.85
