"""The walls' contact angle, as the ``alpha.oil`` condition of the disc, the ball and the
island.

A static angle (``physics.contact_angle``, or advancing and receding angles set equal) is
v1912's ``constantAlphaContactAngle``. With ``physics.advancing_angle`` and
``physics.receding_angle`` apart the angle follows the oil's speed across the contact line
relative to the wall: v1912's ``dynamicAlphaContactAngle``,

    theta = theta0 + (thetaA - thetaR) tanh(u_w / uTheta),

where u_w is the wall cell's velocity relative to the wall, tangent to it, along the
interface's normal on the wall (which points into the oil). An oil front advancing over the
wall moves against that normal, u_w < 0, so the condition's ``thetaA - thetaR`` is the
receding angle less the advancing one, halved, about ``theta0``, their mean: the advancing line
takes the advancing angle, the receding one the receding angle (checked on the contact-line
strip, ``tests/case/test_strip.py``). The tanh is symmetric about u_w = 0: oil at rest on the
wall (a line at rest, the layers the walls carry) takes the mean of the two.

Why: a wall at the Cox-Voinov angle of the rolling speed everywhere tilts the surface of
sub-micron supply layers that the wall carries and breaks them into drops
(docs/models/interface.md#a-wall-angle-that-follows-the-line).
"""

from __future__ import annotations

from ehlfoam.spec.case import CaseSpec

__all__ = ["ANGLE_SPEED_SHARE", "wall_angle_entry"]

#: uTheta over the rolling speed: a line the walls drive at a tenth of their speed takes
#: tanh(1) = 76 % of the way from the mean to its limit; one at the rolling speed all of it
ANGLE_SPEED_SHARE = 0.1


def wall_angle_entry(spec: CaseSpec) -> dict:
    """The ``alpha.oil`` entry of the walls (angles in deg, ``uTheta`` in m/s) for the spec's
    ``physics`` angles: static where the advancing and receding angles are one, dynamic
    where they differ (its velocity scale :data:`ANGLE_SPEED_SHARE` of ``contact.speed``)."""
    advancing, receding = spec.physics.wall_angles
    if advancing == receding:
        return {"type": "constantAlphaContactAngle", "theta0": advancing, "limit": "gradient",
                "value": 0.0}
    return {"type": "dynamicAlphaContactAngle", "theta0": 0.5 * (advancing + receding),
            "uTheta": ANGLE_SPEED_SHARE * spec.speed, "thetaA": 0.5 * receding,
            "thetaR": 0.5 * advancing, "limit": "gradient", "value": 0.0}
