"""The ``[stop]`` table of a case spec: the walls decelerating to rest (the sudden stop), and
the one function that gives their speed at any time (:func:`wall_speed_at`).

The walls roll at ``contact.speed`` until ``stop.at`` [s, run time], slow linearly to rest
over ``stop.duration`` [s] and stay at rest; the run goes on ``stop.after`` [s] past rest
(its end time, in place of ``run.end_time`` / ``run.transits_max``) and keeps a frame of its
state every ``stop.frame_interval`` [s] from ``stop.frames_from`` before the stop on (the
report's GIF). Without ``stop.at`` the walls roll at u throughout. The thin-film scene's march
follows it step by step (:mod:`ehlfoam.thinfilm.march`), the 3D scenes' boundary conditions as
tables of time (:mod:`ehlfoam.case.stop`). SI units.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pydantic import BaseModel, Field

from ehlfoam.errors import SpecError
from ehlfoam.spec.sections import STRICT

#: A case spec (:class:`ehlfoam.spec.case.CaseSpec`): not imported here
CaseSpec = Any

__all__ = ["Stop", "check_stop", "stop_end_time", "wall_speed_at"]


class Stop(BaseModel):
    """The walls' stop: from ``contact.speed`` to rest, linearly, from ``at`` over
    ``duration``; the run goes on ``after`` past rest (docs/models/thin-film.md#the-sudden-stop)."""

    model_config = STRICT
    at: float | None = Field(
        None, ge=0.0, le=1e3,
        description="The run time at which the walls start to decelerate (a case started "
                    "from another's state starts at 0); none: no stop, the walls roll at "
                    "contact.speed throughout.",
        json_schema_extra={"unit": "s"})
    duration: float = Field(
        0.005, ge=0.0, le=10.0,
        description="The time the walls take from contact.speed to rest, linearly (0: at "
                    "once).",
        json_schema_extra={"unit": "s"})
    after: float = Field(
        0.1, gt=0.0, le=100.0,
        description="How long the run goes on past rest: its end time is at + duration + "
                    "after (run.end_time and run.transits_max do not apply; the "
                    "steady-state test does not end it).",
        json_schema_extra={"unit": "s"})
    frame_interval: float = Field(
        0.002, gt=0.0, le=1.0,
        description="A frame of the state (DIR/frames/, the report's GIF) every this much "
                    "run time from frames_from before the stop to the end (the thin-film "
                    "scene; a 3D case writes its fields run.writes_per_transit times a "
                    "transit, which its report animates).",
        json_schema_extra={"unit": "s"})
    frames_from: float = Field(
        0.01, ge=0.0, le=100.0,
        description="How long before the stop the frames begin.",
        json_schema_extra={"unit": "s"})


def wall_speed_at(stop: Stop, speed: float, t: float | np.ndarray) -> float | np.ndarray:
    """The walls' speed [m/s] at run time ``t`` [s] (a number or an array): ``speed`` before
    ``stop.at``, falling linearly to 0 over ``stop.duration``, 0 after; ``speed`` throughout
    without a stop. Every scene's one source of the walls' speed over time."""
    t_arr = np.asarray(t, dtype=float)
    if stop.at is None:
        out = np.full(t_arr.shape, float(speed))
    elif stop.duration > 0:
        out = speed * np.clip(1.0 - (t_arr - stop.at) / stop.duration, 0.0, 1.0)
    else:
        out = np.where(t_arr < stop.at, float(speed), 0.0)
    return float(out) if out.ndim == 0 else out


def stop_end_time(stop: Stop) -> float | None:
    """The run's end with a stop [s]: ``after`` past rest; None without a stop."""
    return None if stop.at is None else stop.at + stop.duration + stop.after


def check_stop(spec: CaseSpec) -> None:
    """Refuse (:class:`SpecError`) a stop with ``run.end_time`` (the stop sets the end), with
    still walls, in a cycle of passes (``supply.mode = "rig"``) and, in the 3D scenes, with
    a Navier slip on the walls (``physics.wall_slip_length``: its face velocities are not
    written to follow the stop)."""
    stop = spec.stop
    if stop.at is None:
        return
    problems = []
    if spec.run.end_time is not None:
        problems.append(f"run.end_time = {spec.run.end_time:g} s does not apply with stop.at "
                        f"= {stop.at:g} s (the run ends stop.after = {stop.after:g} s past "
                        "rest: leave run.end_time unset)")
    if not spec.walls_moving:
        problems.append(f"stop.at = {stop.at:g} s needs walls_moving = true (still walls "
                        "have nothing to stop)")
    if spec.supply.mode == "rig":
        problems.append(f"stop.at = {stop.at:g} s does not apply to supply.mode = \"rig\" (a "
                        "cycle of passes; valid: \"layers\", \"flooded\" or \"submerged\")")
    if spec.scene != "thin-film" and spec.physics.wall_slip_length > 0:
        problems.append(f"stop.at = {stop.at:g} s does not apply with "
                        f"physics.wall_slip_length = {spec.physics.wall_slip_length:g} m in "
                        f"scene = {spec.scene!r} (the slip walls' velocities do not follow "
                        "the stop; valid: 0 m)")
    if problems:
        raise SpecError("invalid case spec: " + "; ".join(problems))
