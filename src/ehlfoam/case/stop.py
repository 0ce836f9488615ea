"""The walls' stop (``[stop]``, :mod:`ehlfoam.spec.stop`) in a 3D case: every velocity the
walls set on the boundary follows the walls' speed over time, as OpenFOAM v1912 reads it
without compiling anything.

- the disc, ``uniformFixedValue`` with a ``table`` Function1 of (u(t), 0, 0);
- the ball, ``rotatingWallVelocity`` with its ``omega`` a ``table`` Function1 of -u(t) / R;
- the island (the rolling velocity projected on its wall, face by face) and a supply whose
  faces differ (the gas-release scene's), ``timeVaryingMappedFixedValue`` with
  ``mapMethod nearest`` on their own face centres, the faces' values at t = 0, at the stop
  and at rest in ``constant/boundaryData/PATCH/TIME/U`` (linear in between, the last held
  after it);
- a uniform supply, ``uniformFixedValue`` like the disc.

The samples are :func:`~ehlfoam.spec.stop.wall_speed_at`'s corners: the ramp is linear, so
OpenFOAM's linear interpolation between them is the function itself. SI units.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ehlfoam._io import atomic_write_text
from ehlfoam.spec.case import CaseSpec
from ehlfoam.spec.stop import wall_speed_at

__all__ = ["BOUNDARY_DATA", "stop_entries", "stop_times", "write_boundary_data"]

#: where timeVaryingMappedFixedValue reads its samples, under the case
BOUNDARY_DATA = Path("constant") / "boundaryData"
#: a stop of no duration: the walls at rest this much later [s] (a table needs rising times)
INSTANT = 1e-9


def stop_times(spec: CaseSpec) -> np.ndarray:
    """The sample times [s] of the walls' speed: 0, the stop and rest (rest just after the
    stop for one of no duration); the table's first and last values hold before and after."""
    stop = spec.stop
    times = [0.0, stop.at, stop.at + max(stop.duration, INSTANT)]
    return np.unique(np.asarray(times, float))


def _number(v: float) -> str:
    return repr(float(v))


def _value(v) -> str:
    v = np.asarray(v, float)
    return _number(v) if v.ndim == 0 else "(" + " ".join(_number(c) for c in v) + ")"


def table_text(times: np.ndarray, values: list) -> str:
    """``table ((t0 v0) (t1 v1) ...)``: an OpenFOAM table Function1 written inline."""
    return "table (" + " ".join(f"({_number(t)} {_value(v)})" for t, v in zip(times, values)) \
        + ")"


def _factors(spec: CaseSpec, times: np.ndarray) -> np.ndarray:
    """u(t) / u at the sample times (the rest one exactly 0)."""
    f = np.asarray(wall_speed_at(spec.stop, 1.0, times), float)
    f[-1] = 0.0
    return f


def stop_entries(spec: CaseSpec) -> dict[str, str]:
    """The inline tables of the uniform velocities: ``disc`` (uniformValue), ``ball``
    (omega) and ``supply`` (uniformValue, where it is uniform)."""
    times = stop_times(spec)
    f = _factors(spec, times)
    u, radius = spec.wall_speed, spec.contact.radius
    return {"disc": table_text(times, [np.array([u * k, 0.0, 0.0]) for k in f]),
            "ball": table_text(times, [-u * k / radius for k in f])}


def write_boundary_data(spec: CaseSpec, case: Path, patch: str, centres: np.ndarray,
                        values: np.ndarray) -> None:
    """``constant/boundaryData/PATCH/points`` (the faces' centres [m]) and
    ``.../TIME/U`` (their velocity at full speed, ``values`` [m/s], times u(t) / u) at each
    sample time, for timeVaryingMappedFixedValue with mapMethod nearest."""
    folder = Path(case) / BOUNDARY_DATA / patch
    folder.mkdir(parents=True, exist_ok=True)
    atomic_write_text(folder / "points", _vectors(centres))
    times = stop_times(spec)
    for t, k in zip(times, _factors(spec, times)):
        sub = folder / _time_name(t)
        sub.mkdir(exist_ok=True)
        atomic_write_text(sub / "U", _vectors(k * np.asarray(values, float)))


def _time_name(t: float) -> str:
    return "0" if t == 0 else repr(float(t))


def _vectors(values: np.ndarray) -> str:
    values = np.asarray(values, float)
    rows = "\n".join(_value(v) for v in values)
    return f"{len(values)}\n(\n{rows}\n)\n"
