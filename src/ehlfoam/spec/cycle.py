"""The ``[cycle]`` table of a case spec and the checks of ``supply.mode = "rig"``.

In "rig" mode nobody sets the supply: the oil on the rig (on the disc's track and the ball's)
goes round, and each pass of the contact takes in what the passes before left on the tracks
after its reflow over a revolution (:mod:`ehlfoam.run.cycle`). The table says how the tracks
are modelled and when the cycle ends. SI units; the reflow's width in units of a.
"""

from __future__ import annotations

import math
from typing import Any

from pydantic import BaseModel, Field

from ehlfoam.errors import SpecError
from ehlfoam.spec.sections import STRICT

#: A case spec (:class:`ehlfoam.spec.case.CaseSpec`): not imported here
CaseSpec = Any

__all__ = ["Cycle", "check_rig", "rig_layers"]


class Cycle(BaseModel):
    """The cycle of passes of ``supply.mode = "rig"`` (docs/models/supply-cycle.md); the
    other supply modes ignore it."""

    model_config = STRICT
    passes_max: int = Field(
        100, ge=1, le=100_000,
        description="The most passes (ball revolutions) the cycle makes; it ends there "
                    "(end reason passes_max) unless it settled before.")
    tolerance: float = Field(
        1e-3, gt=0.0, le=0.5,
        description="The cycle is periodic when the supply the inlet takes in and the oil "
                    "in the contact's domain change by less than this, relative, from a "
                    "disc revolution to the next (K passes, the disc's arcs) and from a pass "
                    "to the next, and the contact lays back what it takes in within it.")
    period_max: int = Field(
        8, ge=2, le=100,
        description="The longest limit cycle (in passes) looked for: the passes' supply "
                    "and oil repeating with that period within cycle.tolerance, twice over.")
    side: float | None = Field(
        None, gt=0.0, le=1000.0,
        description="Half-width of the tracks' lateral domain for the reflow; none: three "
                    "times domain.side. At least domain.side (the contact's rows).",
        json_schema_extra={"unit": "a"})
    refine: int = Field(
        2, ge=1, le=16,
        description="The reflow's cells per row of the contact's grid.")
    reflow_steps: int = Field(
        40, ge=4, le=10_000,
        description="Backward Euler steps of a revolution's reflow (growing by 15 % each).")
    precursor: float = Field(
        1e-9, ge=0.0, le=1e-6,
        description="The reflow's precursor film: mobility on dry ground (no oil).",
        json_schema_extra={"unit": "m"})
    centrifugal: bool = Field(
        False, description="The disc's layer feels the centrifugal force rho u^2 / r across "
                           "its track too (levelled on the full width, folded back).")
    disc_share: float = Field(
        0.5, ge=0.0, le=1.0,
        description="The share of the contact's outflow laid on the disc (the rest on the "
                    "ball): 1/2 in pure rolling.")


def rig_layers(spec: CaseSpec) -> tuple[float, float]:
    """The mean layers (disc, ball) [m] on the tracks at the start of a "rig" supply:
    ``supply.disc_oil`` over the disc's track (2 pi track_radius by 2 track_half_width) or
    ``supply.disc_layer``; the ball's likewise on its great circle (contact.radius)."""
    s = spec.supply
    width = 2.0 * s.track_half_width
    disc = s.disc_layer if s.disc_oil is None else \
        s.disc_oil / (2 * math.pi * s.track_radius * width)
    ball = s.ball_layer if s.ball_oil is None else \
        s.ball_oil / (2 * math.pi * spec.contact.radius * width)
    return disc, ball


def check_rig(spec: CaseSpec) -> None:
    """Refuse a "rig" supply (:class:`SpecError`, every problem in one line) in a scene
    other than the thin-film one, with no oil on the rig, with a track radius that does not
    clear the contact's domain, or a reflow narrower than the domain. Nothing for the other
    supply modes."""
    if spec.supply.mode != "rig":
        return
    problems = []
    s, d = spec.supply, spec.domain
    if spec.scene != "thin-film":
        problems.append(f'supply.mode = "rig" needs scene = "thin-film" (here '
                        f'"{spec.scene}"; valid for the 3D scenes: "flooded", "layers", '
                        '"submerged")')
    disc, ball = rig_layers(spec)
    if not disc + ball > 0:
        problems.append(f"supply.disc_layer = {s.disc_layer:g} m and supply.ball_layer = "
                        f"{s.ball_layer:g} m leave no oil on the rig: set one > 0 (or "
                        "supply.disc_oil, supply.ball_oil > 0 m3)")
    length = (d.upstream + d.downstream) * spec.a
    if not s.track_radius > length:
        problems.append(f"supply.track_radius = {s.track_radius:g} m is out of range: must "
                        f"be > {length:.4g} m, the contact's domain length (domain.upstream + "
                        f"domain.downstream = {d.upstream + d.downstream:g} a), and <= 1 m")
    side = spec.cycle.side
    if side is not None and not side >= d.side:
        problems.append(f"cycle.side = {side:g} a is out of range: must be in "
                        f"[{d.side:g}, 1000] a (at least domain.side, the contact's rows)")
    if problems:
        raise SpecError("invalid case spec: " + "; ".join(problems))
