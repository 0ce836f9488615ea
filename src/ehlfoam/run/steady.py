"""The run monitor's steady-state tests on the history of written times.

A run is steady when the oil volume's least-squares trend over the last transit is within the
tolerance and either the last write is within it of the write one transit earlier ("last
write") or the means over the last two transits agree within it ("window mean": a
statistically steady flow).
"""

from __future__ import annotations

import statistics

from ehlfoam.run.fields import Sample

__all__ = ["steady_test"]


#: Pattern positions the steady-state tests follow (units a).
_POSITIONS = ("inlet_meniscus_distance_over_a", "flooded_length_over_a", "flooded_width_over_a",
              "wake_gas_length_over_a", "bubble_length_over_a")


def _steady_now(history: list[Sample], window: float, tol: float,
                length_scale: float) -> bool:
    """Oil volume and bubble volume within ``tol`` (relative to the oil volume), meniscus
    and bubble-tip positions within ``tol * length_scale`` (units a) of their values one
    ``window`` ago."""
    if not history or history[-1].time - history[0].time < window * (1 - 1e-9):
        return False
    now = history[-1]
    then = min(history, key=lambda s: abs(s.time - (now.time - window)))
    if now.time - then.time < 0.5 * window:
        return False
    if abs(now.oil_volume - then.oil_volume) > tol * max(now.oil_volume, 1e-300):
        return False
    if now.pattern.get("state") != then.pattern.get("state"):
        return False
    for key in _POSITIONS:
        a, b = now.pattern.get(key), then.pattern.get(key)
        if (a is None) != (b is None):
            return False
        if a is not None and abs(a - b) > tol * length_scale:
            return False
    # the bubble's volume, relative to the oil volume (a vanishing bubble is steady)
    a, b = now.pattern.get("bubble_volume_m3"), then.pattern.get("bubble_volume_m3")
    if a is not None and b is not None and abs(a - b) > tol * max(now.oil_volume, 1e-300):
        return False
    return True


def _steady_in_mean(history: list[Sample], window: float, tol: float,
                    length_scale: float) -> bool:
    """Statistically steady: over the last ``window`` and the one before it, the flow kept one
    state at every write, and the window means of the oil volume (and bubble volume) agree
    within ``tol`` of the oil volume and those of the positions within ``tol * length_scale``.

    A flooded region fed with ample oil keeps shedding fingers at its sides and rear: its
    width jumps by 5-10 % from write to write around a fixed mean, so the test on the last
    write alone never passes although the oil volume has stopped growing.
    """
    if not history or history[-1].time - history[0].time < 2 * window * (1 - 1e-9):
        return False
    now = history[-1].time
    last = [s for s in history if now - window < s.time <= now]
    before = [s for s in history if now - 2 * window < s.time <= now - window]
    if len(last) < 3 or len(before) < 3:
        return False
    if len({s.pattern.get("state") for s in last + before}) != 1:
        return False

    def mean(samples, value):
        vals = [value(s) for s in samples]
        return None if any(v is None for v in vals) else sum(vals) / len(vals)

    volume = mean(last, lambda s: s.oil_volume)
    if abs(volume - mean(before, lambda s: s.oil_volume)) > tol * max(volume, 1e-300):
        return False
    for key in _POSITIONS + ("bubble_volume_m3",):
        a = mean(last, lambda s: s.pattern.get(key))
        b = mean(before, lambda s: s.pattern.get(key))
        if (a is None) != (b is None):
            return False
        limit = tol * (max(volume, 1e-300) if key == "bubble_volume_m3" else length_scale)
        if a is not None and abs(a - b) > limit:
            return False
    return True


def _oil_trend_within(history: list[Sample], window: float, tol: float) -> bool:
    """The oil volume's least-squares trend over the last ``window`` changes it by less than
    ``tol`` of itself per window.

    Both tests below compare two points or two means a window apart; a flooded region that
    had settled and then starts to fill again can pass them while the oil still rises
    (docs/models/interface.md#running-steady-state-starting-from-other-states). The trend
    over the last window sees that."""
    now = history[-1].time
    last = [s for s in history if s.time >= now - window * (1 + 1e-9)]
    if len(last) < 2:
        return False
    slope = statistics.linear_regression([s.time for s in last],
                                         [s.oil_volume for s in last]).slope
    return abs(slope) * window <= tol * max(history[-1].oil_volume, 1e-300)


def steady_test(history: list[Sample], window: float, tol: float,
                length_scale: float) -> str | None:
    """Which steady-state test the run passes now: "last write" (the last write against the
    one a ``window`` earlier), "window mean" (:func:`_steady_in_mean`), or None; either only
    while the oil volume's trend over the last window is within the tolerance too
    (:func:`_oil_trend_within`)."""
    if not history or not _oil_trend_within(history, window, tol):
        return None
    if _steady_now(history, window, tol, length_scale):
        return "last write"
    if _steady_in_mean(history, window, tol, length_scale):
        return "window mean"
    return None
