"""The ``[mesh]`` table of a case spec: the resolution level, its overrides, refinements of
the in-plane cells and the meshes that follow a start state's meniscus.

In-plane lengths are in units of the Hertzian radius a, wall cells in metres. The mesh
layer turns these into cell sizes (:mod:`ehlfoam.mesh.sizing`).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, Union

import numpy as np
from pydantic import (BaseModel, BeforeValidator, Discriminator, Field, Tag, field_validator,
                      model_validator)

from ehlfoam.spec.levels import FOLLOW_BASE, FOLLOW_LEVELS, POLAR_RING_SHARE, RESOLUTIONS
from ehlfoam.spec.sections import STRICT, as_tuples


class RefineBox(BaseModel):
    """A box of finer in-plane cells (``mesh.refine``), x in [x_min, x_max] and |y| in
    [y_min, y_max]: cells of ``size`` inside, growing back to the level's size outside. It
    refines the free quads only: the polar ring keeps its cells."""

    model_config = STRICT
    x_min: float = Field(ge=-200.0, le=200.0, description="Upstream end of the box.",
                         json_schema_extra={"unit": "a"})
    x_max: float = Field(ge=-200.0, le=200.0, description="Downstream end of the box.",
                         json_schema_extra={"unit": "a"})
    y_min: float = Field(0.0, ge=0.0, le=200.0, description="Lower bound of the box in |y|.",
                         json_schema_extra={"unit": "a"})
    y_max: float = Field(gt=0.0, le=200.0, description="Upper bound of the box in |y|.",
                         json_schema_extra={"unit": "a"})
    size: float = Field(gt=0.0, le=10.0, description="In-plane cell size inside the box.",
                        json_schema_extra={"unit": "a"})

    @model_validator(mode="after")
    def _ordered(self) -> "RefineBox":
        if not self.x_min < self.x_max:
            raise ValueError(f"x_min = {self.x_min:g} a must be below x_max = {self.x_max:g} a")
        if not self.y_min < self.y_max:
            raise ValueError(f"y_min = {self.y_min:g} a must be below y_max = {self.y_max:g} a")
        return self


class RefineBand(BaseModel):
    """A band of finer in-plane cells along a line (``mesh.refine``): cells of ``size`` within
    ``half_width`` of the polyline through ``points``, growing back to the level's size
    further out. Like a box it refines the free quads only. ``ehlfoam band CASE`` writes the
    bands that follow a run's mid-gap meniscus."""

    model_config = STRICT
    points: Annotated[tuple[tuple[float, float], ...], BeforeValidator(as_tuples)] = Field(
        min_length=2, max_length=10_000,
        description="The points (x, |y|) of the polyline the band follows (a half domain's "
                    "line serves the full domain too).",
        json_schema_extra={"unit": "a"})
    half_width: float = Field(gt=0.0, le=20.0,
                              description="How far the band reaches either side of its line.",
                              json_schema_extra={"unit": "a"})
    size: float = Field(gt=0.0, le=10.0, description="In-plane cell size within the band.",
                        json_schema_extra={"unit": "a"})

    @field_validator("points")
    @classmethod
    def _points_in_range(cls, points: tuple[tuple[float, float], ...]):
        for x, y in points:
            if not (-200.0 <= x <= 200.0 and 0.0 <= y <= 200.0):
                raise ValueError(f"point ({x:g}, {y:g}) a lies outside -200 <= x <= 200, "
                                 "0 <= y <= 200 (units of a, y = |y|)")
        return points


def _refine_kind(value: Any) -> str:
    """Which kind of refinement a ``mesh.refine`` entry is: a band has points."""
    if isinstance(value, dict):
        return "band" if "points" in value else "box"
    return "band" if isinstance(value, RefineBand) else "box"


#: the kinds of ``mesh.refine`` entries, by the tag pydantic puts in an error's location
REFINE_KINDS: dict[str, type[BaseModel]] = {"box": RefineBox, "band": RefineBand}

#: an entry of ``mesh.refine``: a box, or a band along a line
Refinement = Annotated[Union[tuple(Annotated[m, Tag(t)] for t, m in REFINE_KINDS.items())],
                       Discriminator(_refine_kind)]


class SideBox(BaseModel):
    """Where the followed meniscus is the flooded region's side (``mesh.follow.sides``): the
    band's points with x_min <= x <= x_max and |y| >= y_min get a second, finer band. The
    region's width is set there."""

    model_config = STRICT
    x_min: float = Field(ge=-200.0, le=200.0,
                         description="Upstream end of the sides' stretch of the meniscus.",
                         json_schema_extra={"unit": "a"})
    x_max: float = Field(ge=-200.0, le=200.0,
                         description="Downstream end of the sides' stretch of the meniscus.",
                         json_schema_extra={"unit": "a"})
    y_min: float = Field(0.0, ge=0.0, le=200.0,
                         description="The sides' points lie at |y| >= y_min.",
                         json_schema_extra={"unit": "a"})
    size: float | None = Field(None, gt=0.0, le=10.0,
                               description="In-plane cell size of the side band; none: half "
                                           "the level's band cells.",
                               json_schema_extra={"unit": "a"})
    half_width: float | None = Field(None, gt=0.0, le=20.0,
                                     description="Half-width of the side band; none: half "
                                                 "that of the band along the meniscus.",
                                     json_schema_extra={"unit": "a"})

    @model_validator(mode="after")
    def _ordered(self) -> "SideBox":
        if not self.x_min < self.x_max:
            raise ValueError(f"x_min = {self.x_min:g} a must be below x_max = {self.x_max:g} a")
        return self

    def holds(self, points: np.ndarray) -> np.ndarray:
        """Which of the (k, 2) points (x, |y|), units of a, lie in the box (bool, k)."""
        x, y = points[:, 0], np.abs(points[:, 1])
        return (x >= self.x_min) & (x <= self.x_max) & (y >= self.y_min)


class Follow(BaseModel):
    """A mesh that follows the meniscus of the state the case starts from (``mesh.follow``,
    with ``ehlfoam case --start-from``): bands of the level's cells (:data:`FOLLOW_LEVELS`)
    along the start state's mid-gap meniscus, and optionally a finer band on the region's
    sides. The written case has the bands in ``mesh.refine`` and the level's sizes spelled
    out."""

    model_config = STRICT
    half_width: float = Field(1.0, gt=0.0, le=20.0,
                              description="How far the bands reach either side of the start "
                                          "state's mid-gap meniscus.",
                              json_schema_extra={"unit": "a"})
    sides: SideBox | None = Field(None, description="A finer band where the meniscus is the "
                                                    "region's side; none: no side band.")


class Mesh(BaseModel):
    """The resolution level (:data:`RESOLUTIONS`, or :data:`FOLLOW_LEVELS` with ``follow``)
    and its overrides."""

    model_config = STRICT
    resolution: Literal["coarse", "medium", "fine"] = Field(
        "medium", description='The resolution level: "coarse", "medium" or "fine".')
    n_layers: int | None = Field(
        None, ge=1, le=64, description="Cells across the gap; none: the level's.")
    size_rim: float | None = Field(
        None, gt=0.0, le=10.0,
        description="In-plane cell size at the island rim; none: the level's.",
        json_schema_extra={"unit": "a"})
    size_far: float | None = Field(
        None, gt=0.0, le=50.0,
        description="In-plane cell size far from the contact; the nominal menisci sit in "
                    "cells of about this size, and the flooded width depends on it. None: the "
                    "level's.",
        json_schema_extra={"unit": "a"})
    wall_grading: float | None = Field(
        None, ge=1.0, le=100.0,
        description="Mid-gap cell height over the wall cell's (1: uniform layers); finer "
                    "cells at the walls carry the supply layers and the films left behind. "
                    "None: the level's.")
    wall_cell: float | None = Field(
        None, ge=1e-8, le=1e-4,
        description="Instead of wall_grading, one wall-cell height everywhere: each column of "
                    "cells graded just enough for it (uniform where the gap is too thin, "
                    "graded at most 100). None: the level's grading, or with follow the "
                    "level's wall cell.",
        json_schema_extra={"unit": "m"})
    polar_radius: float | Literal["auto"] | None = Field(
        "auto",
        description='Outer radius of a structured log-polar ring of cells around the island, '
                    'which a circular meniscus meets the same way in every cell; below 0.95 x '
                    'the nearest boundary. "auto": POLAR_RING_SHARE x the nearest boundary '
                    '(FOLLOW_POLAR_RADIUS with follow); none: free quads everywhere.',
        json_schema_extra={"unit": "a"})
    columns: Literal["normal", "vertical"] = Field(
        "normal",
        description='How the columns of nodes cross the gap: "normal" leans each column to '
                    'meet every layer at right angles (an in-plane shift of a few um at most); '
                    '"vertical" keeps them upright, which makes every face where the ball '
                    'slopes non-orthogonal.')
    refine: Annotated[tuple[Refinement, ...], BeforeValidator(as_tuples)] = Field(
        (),
        description="Boxes and bands along a line of finer in-plane cells (free quads only), "
                    "e.g. [{x_min = 5, x_max = 14, y_max = 8, size = 0.1}] where the rear "
                    "meniscus lays its films; `ehlfoam band CASE` writes bands along a run's "
                    "meniscus.")
    follow: Follow | None = Field(
        None,
        description="A mesh that follows the meniscus of the state the case starts from "
                    "(--start-from): the level then sets the bands' cells and the wall cell, "
                    "on FOLLOW_BASE. None: the levels of RESOLUTIONS.")
    max_cells: int = Field(
        5_000_000, ge=1, le=10**9,
        description="The most cells a case's mesh may have: a spec whose mesh, estimated from "
                    "its sizes (in-plane quads x n_layers) before anything is meshed, exceeds "
                    "it is refused with the estimate. A bound on the work, not on the result.")

    @field_validator("polar_radius", mode="before")
    @classmethod
    def _polar_radius_valid(cls, value: Any) -> Any:
        if value is None or value == "auto":
            return value
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not 1.0 < value <= 200.0:
            raise ValueError('must be a radius in units of a (1 < radius <= 200), "auto" '
                             f'({POLAR_RING_SHARE:g} x the nearest boundary) or none (free '
                             'quads)')
        return float(value)

    @model_validator(mode="after")
    def _one_wall_rule(self) -> "Mesh":
        if self.wall_cell is not None and self.wall_grading is not None:
            raise ValueError(f"set one of wall_grading ({self.wall_grading:g}) and wall_cell "
                             f"({self.wall_cell:g} m): the wall cell fixes each column's "
                             f"grading")
        return self

    def level(self) -> dict[str, float | None]:
        """The level's sizes with the overrides applied: ``n_layers``, ``size_rim`` and
        ``size_far`` (a), ``wall_grading`` (-) and ``wall_cell`` [m]. One of the last two
        is None: with ``wall_cell`` set the columns are graded for it and the level's
        grading does not apply."""
        if self.follow is None:
            out = dict(RESOLUTIONS[self.resolution])
            wall_cell = self.wall_cell
        else:
            out = {**FOLLOW_BASE, "wall_grading": None}
            wall_cell = self.wall_cell
            if wall_cell is None and self.wall_grading is None:   # the level's wall cell
                wall_cell = FOLLOW_LEVELS[self.resolution]["wall_cell"]
        for key in ("n_layers", "size_rim", "size_far", "wall_grading"):
            if getattr(self, key) is not None:
                out[key] = getattr(self, key)
        out["n_layers"] = int(out["n_layers"])
        out["wall_cell"] = wall_cell
        if wall_cell is not None:
            out["wall_grading"] = None
        return out

    @property
    def follow_band(self) -> float | None:
        """In-plane cell size (a) of the band along the followed meniscus (None without
        ``follow``)."""
        return None if self.follow is None else FOLLOW_LEVELS[self.resolution]["band"]
