"""Is this message fresh and plausible? The supervisor's checks beyond "a message arrived".

A driver can keep publishing and still be broken: it republishes its last message (the stamp
stops advancing), it re-stamps one frozen reading (a scan or IMU reading identical to the previous
one, which sensor noise never produces), or its data is invalid (NaN/inf where a number must be, or a
share of scan ranges that are NaN or outside [range_min, range_max] above a threshold), or its pose
is frozen while the robot is commanded to move and other sensors show that it does (odometry,
localization: ``motion_check``). Each
check returns None for a good message or a short reason; the supervisor fails a component
whose data has been bad for longer than its timeout, with that reason.

Per REP 117, +inf/-inf scan ranges mean "nothing within range" / "too close" and are valid.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .messages import BatteryState, Imu, LaserScan, LocalizedPose, Odometry
from .motion_check import MotionWitness


class DataCheck:
    """Checks the messages of one stream, remembering what it needs from the previous one."""

    __slots__ = ("invalid_share", "_stamp", "_ranges", "_imu", "_motion")

    def __init__(self, invalid_share: float = 0.3, motion: MotionWitness | None = None):
        self.invalid_share = invalid_share
        self._motion = motion
        self._stamp: float | None = None
        self._ranges: np.ndarray | None = None
        self._imu: tuple[float, float, float] | None = None

    def __call__(self, msg: Any) -> str | None:
        stamp = getattr(msg, "stamp", None)
        if stamp is not None:
            previous = self._stamp
            if previous is not None and not stamp > previous:
                return "stale data: timestamps not advancing"
            self._stamp = stamp
        kind = type(msg)
        if kind is LaserScan:
            return self._scan(msg)
        if kind is Imu:
            reading = (msg.yaw_rate, msg.accel_x, msg.accel_y)
            problem = _non_finite(*reading)
            if problem is not None:
                return problem
            previous, self._imu = self._imu, reading
            if reading == previous:  # an IMU's noise never repeats a reading exactly
                return "stale data: identical readings repeated"
            return None
        if kind is Odometry:
            p, t = msg.pose, msg.twist
            problem = _non_finite(p.x, p.y, p.yaw, t.linear, t.angular)
            return problem if problem is not None or self._motion is None else self._motion.frozen("odom", p)
        if kind is LocalizedPose:
            p = msg.pose
            problem = _non_finite(p.x, p.y, p.yaw)
            return problem if problem is not None or self._motion is None else self._motion.frozen("pose", p)
        if kind is BatteryState:
            return _non_finite(msg.percentage, msg.voltage)
        return None

    def _scan(self, msg: LaserScan) -> str | None:
        ranges = np.asarray(msg.ranges)
        n = len(ranges)
        if n == 0:
            return "invalid data: empty scan"
        previous = self._ranges
        self._ranges = ranges
        if previous is not None and (previous is ranges or np.array_equal(previous, ranges)):
            if np.isfinite(ranges).any():
                return "stale data: identical scans repeated"
        with np.errstate(invalid="ignore"):
            bad = np.isnan(ranges) | (np.isfinite(ranges) & ((ranges < msg.range_min) | (ranges > msg.range_max)))
        share = float(np.count_nonzero(bad)) / n
        if share > self.invalid_share:
            return f"invalid data: {share:.0%} of scan ranges NaN or out of range"
        return None


def _non_finite(*values: float) -> str | None:
    for v in values:
        if not math.isfinite(v):
            return "invalid data: non-finite values"
    return None
