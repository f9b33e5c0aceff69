"""Port types shared by the robot nodes.

Poses travel on the blackboard as ``Pose2D`` objects. Their port type carries Nav2's type name
(``geometry_msgs::msg::PoseStamped``) so that our nodes and the Nav2-named nodes can share one
blackboard entry (``{goal}``) without a type clash, and Groot2 shows the name Nav2 users know.
Literals in XML are ``x;y[;yaw]`` (or ``x,y[,yaw]``).
"""

from __future__ import annotations

import math
from typing import Any

from bt_runtime.errors import BTRuntimeError
from bt_runtime.ports import STRING, PortType, vector_of
from bt_runtime.runtime.messages import Path, Pose2D


def parse_pose(text: str) -> Pose2D:
    try:
        return Pose2D.from_string(text)
    except (ValueError, TypeError) as exc:
        raise BTRuntimeError(f"Can't convert string [{text}] to a pose (x;y[;yaw]): {exc}") from None


def pose_to_string(pose: Any) -> str:
    return pose.to_string() if isinstance(pose, Pose2D) else str(pose)


POSE = PortType("geometry_msgs::msg::PoseStamped", "custom", Pose2D, from_string=parse_pose,
                to_string=pose_to_string)
PATH = PortType("nav_msgs::msg::Path", "custom", Path)
NAMES = vector_of(STRING)  # 'a;b;c' lists of component names


def heading_to(a: Pose2D, b: Pose2D) -> float:
    return math.atan2(b.y - a.y, b.x - a.x)


def wrap_angle(angle: float) -> float:
    return (angle + math.pi) % (2 * math.pi) - math.pi
