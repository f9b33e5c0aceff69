"""The port types of every robot node (ours and the Nav2-named ones), with Nav2's C++ type
names and string forms: one vocabulary, so that our nodes and Nav2's share blackboard entries
(``{goal}``, ``{path}``) without a type clash, and Groot2 shows the names Nav2 users know.

Blackboard values are the project's Python objects: a pose is a ``Pose2D`` (map frame), a path
a ``messages.Path``, a list of goals a ``list[Pose2D]``, error codes plain ``int``
(``unsigned short`` for Nav2's ``uint16``).

Literals in XML parse from Nav2's forms (``nav2_behavior_tree/bt_utils.hpp``) and the project's
short ones, so both the project's trees and Nav2's stock trees load:

* PoseStamped: ``x;y[;yaw]`` or ``x,y[,yaw]``; Nav2's ``stamp;frame;x;y;z;qx;qy;qz;qw`` (9
  fields); or ``json:{...}``;
* vector<PoseStamped>: 9 fields per pose, or ``x,y[,yaw]`` poses separated by ``|``, or
  ``json:[...]``;
* Path: ``stamp;frame`` followed by 9 fields per pose, or ``json:[[x, y(, yaw)], ...]``.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from enum import IntEnum
from typing import Any

import numpy as np

from bt_runtime.errors import BTRuntimeError
from bt_runtime.ports import INT, MILLISECONDS, STRING, PortType, vector_of
from bt_runtime.runtime.messages import Path, Pose2D, yaw_from_quaternion

from .contact import ContactArc

_NUMBER = re.compile(r"\s*[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?\s*$")


def _is_number(text: str) -> bool:
    return bool(_NUMBER.match(text))


def _pose_from_fields(fields: list[str]) -> Pose2D:
    """Nav2's 9-field PoseStamped: stamp;frame;x;y;z;qx;qy;qz;qw (frame and stamp dropped)."""
    x, y, _z, qx, qy, qz, qw = (float(f) for f in fields[2:9])
    return Pose2D(x, y, yaw_from_quaternion(qx, qy, qz, qw))


def _pose_from_json(data: Any) -> Pose2D:
    if isinstance(data, (list, tuple)):
        return Pose2D(*(float(v) for v in data))
    if "pose" in data:  # ROS-like {"header": .., "pose": {"position": .., "orientation": ..}}
        data = data["pose"]
    if "position" in data:
        p = data["position"]
        q = data.get("orientation", {})
        yaw = yaw_from_quaternion(q.get("x", 0.0), q.get("y", 0.0), q.get("z", 0.0), q.get("w", 1.0))
        return Pose2D(float(p["x"]), float(p["y"]), yaw)
    return Pose2D(float(data["x"]), float(data["y"]), float(data.get("yaw", 0.0)))


def _load_json(text: str) -> Any:
    try:
        return json.loads(text[5:])
    except ValueError as exc:
        raise BTRuntimeError(f"Can't parse JSON [{text[5:]}]: {exc}") from None


def parse_pose(text: str) -> Pose2D:
    """A pose literal: Nav2's PoseStamped string, ``json:``, ``x;y[;yaw]`` or ``x,y[,yaw]``."""
    text = text.strip()
    try:
        if text.startswith("json:"):
            return _pose_from_json(_load_json(text))
        parts = [p for p in text.split(";")]
        if len(parts) == 9:
            return _pose_from_fields(parts)
        return Pose2D.from_string(text)
    except BTRuntimeError:
        raise
    except (ValueError, TypeError, KeyError) as exc:
        raise BTRuntimeError(f"Can't convert string [{text}] to a pose (x;y[;yaw] or Nav2's "
                             f"stamp;frame;x;y;z;qx;qy;qz;qw): {exc}") from None


def pose_to_string(pose: Any) -> str:
    return pose.to_string() if isinstance(pose, Pose2D) else str(pose)


def parse_goals(text: str) -> list[Pose2D]:
    """A list of poses: Nav2's 9 fields per pose, ``x,y[,yaw]|x,y[,yaw]`` or ``json:[...]``."""
    text = text.strip()
    if not text:
        return []
    try:
        if text.startswith("json:"):
            return [_pose_from_json(item) for item in _load_json(text)]
        if "|" in text:
            return [parse_pose(part) for part in text.split("|") if part.strip()]
        parts = text.split(";")
        if len(parts) % 9 == 0 and not _is_number(parts[1]):
            return [_pose_from_fields(parts[i:i + 9]) for i in range(0, len(parts), 9)]
        return [parse_pose(text)]
    except BTRuntimeError:
        raise
    except (ValueError, TypeError, KeyError) as exc:
        raise BTRuntimeError(f"Can't convert string [{text}] to a list of poses: {exc}") from None


def goals_to_string(goals: Any) -> str:
    return "|".join(pose_to_string(g) for g in goals) if isinstance(goals, (list, tuple)) else str(goals)


def parse_path(text: str) -> Path:
    """Nav2's ``stamp;frame;<9 fields per pose>...`` or ``json:[[x, y(, yaw)], ...]``."""
    text = text.strip()
    try:
        if text.startswith("json:"):
            items = _load_json(text)
            poses = [_pose_from_json(item) for item in items]
        else:
            parts = text.split(";")
            if len(parts) < 2 or (len(parts) - 2) % 9 != 0:
                raise ValueError("invalid number of fields for Path attribute")
            poses = [_pose_from_fields(parts[i:i + 9]) for i in range(2, len(parts), 9)]
    except BTRuntimeError:
        raise
    except (ValueError, TypeError, KeyError) as exc:
        raise BTRuntimeError(f"Can't convert string [{text}] to a path: {exc}") from None
    return path_from_poses(poses)


def path_from_poses(poses: list[Pose2D], stamp: float = 0.0) -> Path:
    pts = np.array([[p.x, p.y, p.yaw] for p in poses], dtype=float).reshape(-1, 3)
    return Path(stamp, pts)


def empty_path(stamp: float = 0.0) -> Path:
    return Path(stamp, np.empty((0, 3), dtype=float))


def path_to_string(path: Any) -> str:
    if isinstance(path, Path):
        return f"Path({len(path)} poses, {path.length:.2f} m)"
    return str(path)


# ---------------------------------------------------------------------------------------------
# Messages Nav2 has and the project does not (yet)
# ---------------------------------------------------------------------------------------------

@dataclass(slots=True, frozen=True)
class TrackingFeedback:
    """nav2_msgs/TrackingFeedback (main): how well the robot follows the path.

    ``position_tracking_error`` is the signed cross-track distance (m, + = robot left of the
    path), ``heading_tracking_error`` the robot's heading minus the path's (rad)."""

    stamp: float
    position_tracking_error: float
    heading_tracking_error: float
    current_path_index: int
    robot_pose: Pose2D
    distance_to_goal: float
    speed: float
    remaining_path_length: float


class WaypointStatusCode(IntEnum):
    PENDING = 0
    COMPLETED = 1
    SKIPPED = 2
    FAILED = 3


@dataclass(slots=True)
class WaypointStatus:
    """nav2_msgs/WaypointStatus (main)."""

    waypoint_status: WaypointStatusCode
    waypoint_index: int
    waypoint_pose: Pose2D
    error_code: int = 0
    error_msg: str = ""


# ---------------------------------------------------------------------------------------------
# Port types
# ---------------------------------------------------------------------------------------------

POSE = PortType("geometry_msgs::msg::PoseStamped", "custom", Pose2D, from_string=parse_pose,
                to_string=pose_to_string)
PATH = PortType("nav_msgs::msg::Path", "custom", Path, from_string=parse_path, to_string=path_to_string)
_POSES_CPP = "geometry_msgs::msg::PoseStamped"
GOALS = PortType(f"std::vector<{_POSES_CPP}, std::allocator<{_POSES_CPP}> >", "custom", list,
                 from_string=parse_goals, to_string=goals_to_string)
ERROR_CODE = PortType("unsigned short", "int", int, lo=0, hi=65535)
INT_LIST = vector_of(INT)
STRING_LIST = vector_of(STRING)
NAMES = STRING_LIST  # 'a;b;c' lists of component names
SERVER_TIMEOUT = MILLISECONDS
ROUTE = PortType("nav2_msgs::msg::Route", "custom", object)
DURATION = PortType("builtin_interfaces::msg::Duration", "custom", float)
TRACKING_FEEDBACK = PortType("nav2_msgs::msg::TrackingFeedback", "custom", TrackingFeedback)
_WS_CPP = "nav2_msgs::msg::WaypointStatus"
WAYPOINT_STATUSES = PortType(f"std::vector<{_WS_CPP}, std::allocator<{_WS_CPP}> >", "custom", list)


def parse_contact_arc(text: str) -> ContactArc:
    """A contact arc literal: ``x;y;bearing;half_width;radius[;heading]`` (``nodes.contact.ContactArc``)."""
    parts = [float(p) for p in text.replace(",", ";").split(";") if p.strip()]
    if len(parts) not in (5, 6):
        raise ValueError(f"a contact arc is 'x;y;bearing;half_width;radius[;heading]', got {text!r}")
    return ContactArc(*parts)


CONTACT_ARC = PortType("bt_runtime::ContactArc", "custom", ContactArc, from_string=parse_contact_arc,
                       to_string=lambda a: a.to_string() if isinstance(a, ContactArc) else str(a))
