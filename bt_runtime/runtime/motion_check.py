"""Is the robot moving? Frozen odometry or localization detected against other evidence.

A driver can publish a frozen pose with fresh timestamps: every message looks new, nothing is
NaN, and a robot standing still publishes exactly such a stream, so no single stream shows it.
``MotionWitness`` compares streams: the commands that reached the base (``cmd_vel_out``) say
the robot is told to move, the IMU's yaw rate and the scan's change say it does move. A pose
that stays put for ``hold`` s while both hold is frozen.

No false alarm where the pose is right to stay put: without a command (standing), or commanded
but blocked (the scan does not change and the IMU feels no turn), or with no independent
evidence at all (IMU and lidar down too) nothing is reported. Once frozen, a pose stays
reported until it changes (a restarted driver starts again from zero).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from .messages import Imu, LaserScan, Pose2D, Twist


class MotionWitness:
    """Evidence of commanded and measured motion, and a frozen-pose check per stream."""

    __slots__ = ("clock", "min_linear", "min_angular", "hold", "min_yaw_rate", "scan_shift", "scan_share", "scan_gap",
                 "_commanded_since", "_command", "_imu_moving_at", "_scan_moving_at", "_ref_scan",
                 "_ref_t", "_poses")

    def __init__(self, clock: Callable[[], float], *, min_linear: float = 0.05, min_angular: float = 0.25,
                 hold: float = 1.0, min_yaw_rate: float = 0.12, scan_shift: float = 0.08,
                 scan_share: float = 0.03, scan_gap: float = 1.0):
        self.clock = clock
        self.min_linear = min_linear  # m/s commanded: a command that moves any base
        self.min_angular = min_angular  # rad/s
        self.hold = hold  # s of commanded motion and of an unchanged pose before it is frozen
        self.min_yaw_rate = min_yaw_rate  # rad/s the IMU must feel (its noise is ~0.01)
        # m: a range that changed by more than this between two scans moved (a lidar's noise,
        # sigma 0.01-0.015 m, makes 4 sigma of the difference ~0.06-0.085 m); driving past walls
        # beside the robot changes few ranges (those along the wall stay), the oblique ones a lot
        self.scan_shift = scan_shift
        self.scan_share = scan_share  # of the beams with a return in both scans
        self.scan_gap = scan_gap  # s between the scans compared
        self._commanded_since: float | None = None
        self._command = (0.0, 0.0)
        self._imu_moving_at = -math.inf
        self._scan_moving_at = -math.inf
        self._ref_scan: np.ndarray | None = None
        self._ref_t = -math.inf
        self._poses: dict[str, list] = {}  # stream -> [pose, unchanged since, frozen]

    # -- evidence --------------------------------------------------------------------------------
    def on_command(self, msg: Twist) -> None:
        if not isinstance(msg, Twist):
            return
        command = (msg.linear, msg.angular)
        if command == self._command:  # the base repeats its command every step: nothing new
            return
        self._command = command
        if abs(command[0]) < self.min_linear and abs(command[1]) < self.min_angular:
            self._commanded_since = None
        elif self._commanded_since is None:
            self._commanded_since = self.clock()

    def on_imu(self, msg: Imu) -> None:
        if isinstance(msg, Imu) and abs(msg.yaw_rate) >= self.min_yaw_rate:
            self._imu_moving_at = self.clock()

    def on_scan(self, msg: LaserScan) -> None:
        if not isinstance(msg, LaserScan) or self._commanded_since is None:
            self._ref_scan = None  # compare only scans taken while commanded to move
            return
        now = self.clock()
        ranges = np.asarray(msg.ranges, dtype=float)
        ref = self._ref_scan
        if ref is None or len(ref) != len(ranges):
            self._ref_scan, self._ref_t = ranges, now
            return
        if now - self._ref_t < self.scan_gap:
            return
        both = np.isfinite(ranges) & np.isfinite(ref)
        n = np.count_nonzero(both)
        if n >= 20 and np.count_nonzero(np.abs(ranges[both] - ref[both]) > self.scan_shift) >= self.scan_share * n:
            self._scan_moving_at = now
        self._ref_scan, self._ref_t = ranges, now

    def moving(self, now: float) -> str | None:
        """Why the robot is believed to move (commanded for ``hold`` s and felt), else None."""
        since = self._commanded_since
        if since is None or now - since < self.hold:
            return None
        felt = []
        if now - self._imu_moving_at <= self.hold:
            felt.append("the IMU feels a turn")
        if now - self._scan_moving_at <= self.hold + self.scan_gap:
            felt.append("the scan changes")
        if not felt:
            return None
        v, w = self._command
        return f"commanded {v:.2f} m/s, {w:.2f} rad/s for {now - since:.1f} s and {' and '.join(felt)}"

    # -- the check -------------------------------------------------------------------------------
    def frozen(self, stream: str, pose: Pose2D) -> str | None:
        """None for a pose that moves (or may rightly stand still); the reason for a frozen one."""
        now = self.clock()
        entry = self._poses.get(stream)
        if entry is None or _moved(entry[0], pose):
            self._poses[stream] = [pose, now, False]
            return None
        if not entry[2]:
            why = self.moving(now)
            if why is None or now - entry[1] < self.hold:
                return None
            entry[2] = True
            entry.append(why)
        return f"stale data: pose frozen for {now - entry[1]:.1f} s while {entry[3]}"


def _moved(a: Pose2D, b: Pose2D) -> bool:
    return abs(a.x - b.x) > 1e-4 or abs(a.y - b.y) > 1e-4 or abs(a.yaw - b.yaw) > 1e-4
