"""What makes a velocity command safe for the base: finite, within the robot's speed and
acceleration limits and the current speed limit.

The decision gate runs every command through ``CommandLimiter.apply`` whatever its source
(tree, navigation, e-stop release, teleop), so this is the one place these rules live.
Braking is never delayed: a command between zero and the last output passes at once; only
moving away from zero (speeding up, or the far side of a reversal) is rate-limited.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .messages import ZERO_TWIST, RobotInfo, Twist


@dataclass(slots=True, frozen=True)
class MotionLimits:
    """Speed (m/s, rad/s) and acceleration (m/s^2, rad/s^2) limits; inf = no limit."""

    max_linear: float = math.inf
    max_angular: float = math.inf
    max_linear_accel: float = math.inf
    max_angular_accel: float = math.inf

    @classmethod
    def from_robot(cls, robot: RobotInfo) -> MotionLimits:
        return cls(robot.max_linear, robot.max_angular, robot.max_linear_accel, robot.max_angular_accel)


def is_finite(twist: Twist) -> bool:
    return math.isfinite(twist.linear) and math.isfinite(twist.angular)


def _ramp(target: float, previous: float, step: float) -> float:
    """Limit the move from ``previous`` towards ``target`` to ``step``, except when braking."""
    if previous >= 0.0 and 0.0 <= target <= previous or previous <= 0.0 and previous <= target <= 0.0:
        return target  # braking (or holding): never delayed
    base = previous if (previous > 0.0) == (target > 0.0) else 0.0  # a reversal brakes to zero first
    return min(max(target, base - step), base + step)


class CommandLimiter:
    """Clamps finite commands to the limits; the caller refuses non-finite ones first."""

    def __init__(self, limits: MotionLimits | None = None):
        self.limits = limits or MotionLimits()

    def apply(self, twist: Twist, previous: Twist, dt: float,
              speed_limit: tuple[float, float] | None = None) -> Twist:
        """``twist`` limited in speed (keeping the curvature while scaling the linear speed)
        and in acceleration relative to ``previous``, sent ``dt`` seconds ago."""
        if twist.is_zero:
            return ZERO_TWIST
        lim = self.limits
        v, w = self._speed(twist, speed_limit)
        dt = max(0.0, dt)
        if math.isfinite(lim.max_linear_accel):
            v = _ramp(v, previous.linear, lim.max_linear_accel * dt)
        if math.isfinite(lim.max_angular_accel):
            w = _ramp(w, previous.angular, lim.max_angular_accel * dt)
        return Twist(v, w)

    def clamp(self, twist: Twist, speed_limit: tuple[float, float] | None = None) -> Twist:
        """``twist`` within the speed limits only: where ``apply`` ends once no ramp is left
        (``apply(t, clamp(t), dt)`` is ``clamp(t)`` for every ``dt``)."""
        if twist.is_zero:
            return ZERO_TWIST
        return Twist(*self._speed(twist, speed_limit))

    def _speed(self, twist: Twist, speed_limit: tuple[float, float] | None) -> tuple[float, float]:
        lim = self.limits
        vmax, wmax = lim.max_linear, lim.max_angular
        if speed_limit is not None:
            vmax, wmax = min(vmax, speed_limit[0]), min(wmax, speed_limit[1])
        v, w = twist.linear, twist.angular
        if abs(v) > vmax:  # scale both, keeping the curvature
            scale = vmax / abs(v)
            # the linear speed set to the limit itself: v * scale can round one unit above it
            v, w = math.copysign(vmax, v), w * scale
        if abs(w) > wmax:
            w = math.copysign(wmax, w)
        return v, w
