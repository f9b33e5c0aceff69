"""How every node reads the robot: through ``node.context`` (the runtime's ``RuntimeContext``,
or any object with the same attributes), never through the simulator.

``robot_pose`` is the one pose reader of the node library. ``context.backup.latest("pose")``
stands for Nav2's TF lookup map -> base_link, and a pose older than ``POSE_TIMEOUT`` counts as
missing, as Nav2's ``getCurrentPose`` fails when the transform is older than its tolerance: a
node that decides from a stale pose decides from where the robot was, not where it is.
"""

from __future__ import annotations

import math
from typing import Any

from bt_runtime.errors import LogicError
from bt_runtime.runtime.messages import LocalizedPose, Pose2D

# Our localization publishes at 10 Hz and the stand-in navigation stack gives up after 1 s
# without a pose: older than this, the pose is "transform not available".
POSE_TIMEOUT = 1.0


def navigation(node: Any) -> Any:
    """The Nav2-like client (``context.navigation``); a clear error if the tree has none."""
    ctx = node.context
    nav = getattr(ctx, "navigation", None) if ctx is not None else None
    if nav is None:
        raise LogicError(f"node '{node.config.path}' [{node.registration_name}] needs a runtime context "
                         "with a navigation client (context.navigation); create the factory with "
                         "the runtime's context")
    return nav


def latest(node: Any, stream: str) -> Any:
    """The newest message of ``stream`` in the data backup (None: none, or no backup)."""
    ctx = node.context
    backup = getattr(ctx, "backup", None) if ctx is not None else None
    return backup.latest(stream) if backup is not None else None


def robot_pose(node: Any, max_age: float = POSE_TIMEOUT) -> Pose2D | None:
    """The robot's map-frame pose, or None when localization is missing, older than ``max_age``
    s, or not finite (a NaN pose is no position: every check that used it would pass or fail
    at random)."""
    ctx = node.context
    backup = getattr(ctx, "backup", None) if ctx is not None else None
    if backup is None:
        return None
    msg = backup.latest("pose")
    if msg is None:
        return None
    age = backup.age("pose") if hasattr(backup, "age") else None
    if age is not None and age > max_age:
        return None
    pose = msg.pose if isinstance(msg, LocalizedPose) else getattr(msg, "pose", msg)
    if not (math.isfinite(pose.x) and math.isfinite(pose.y) and math.isfinite(pose.yaw)):
        return None
    return pose
