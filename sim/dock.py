"""The world's charging dock: where its contacts are and when the robot's touch them.

The dock pose (world file ``dock``) is where the robot's base stands when it is docked, facing
the dock (opennav_docking's convention for a forward-docking charger). The robot's charging
contacts sit at the front of its footprint, the dock's at the dock's face; they touch when the
base is within ``CONTACT_ALONG`` of the dock pose along the dock's axis, ``CONTACT_ACROSS``
across it, and heads within ``CONTACT_YAW`` of the dock's heading (spring-loaded pads give
that much play). The dock is a low charging plate: it is not an obstacle to the lidar or the
body. This is ground truth, for the battery model and for judging; the robot learns that it is
charging only from its battery messages.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from bt_runtime.runtime.messages import Pose2D, wrap_angle

CONTACT_ALONG = 0.05  # m along the dock's axis
CONTACT_ACROSS = 0.05  # m across it
CONTACT_YAW = 0.35  # rad


@dataclass(frozen=True, slots=True)
class Dock:
    """A dock at ``pose``; ``touching`` says whether a base at (x, y, yaw) has contact."""

    pose: Pose2D
    along: float = CONTACT_ALONG
    across: float = CONTACT_ACROSS
    yaw_tolerance: float = CONTACT_YAW

    def offset(self, x: float, y: float) -> tuple[float, float]:
        """(along, across) of a point from the dock pose, in the dock's frame."""
        c, s = math.cos(self.pose.yaw), math.sin(self.pose.yaw)
        dx, dy = x - self.pose.x, y - self.pose.y
        return c * dx + s * dy, -s * dx + c * dy

    def touching(self, x: float, y: float, yaw: float) -> bool:
        along, across = self.offset(x, y)
        return (abs(along) <= self.along and abs(across) <= self.across
                and abs(wrap_angle(yaw - self.pose.yaw)) <= self.yaw_tolerance)
