"""What several Nav2-named nodes share: ``getInputOrBlackboard``, path geometry
(``nav2_util::geometry_utils``), the recovery counter and Nav2's "topics".

The robot itself (pose, latest messages, the navigation client) is read through
``nodes/robot.py``, as every node of the library does.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as np
import structlog

from bt_runtime.errors import BTRuntimeError
from bt_runtime.runtime.messages import Path, Pose2D, wrap_angle

log = structlog.get_logger("nodes.nav2")

# bt_navigator's default_server_timeout (ms): how long a service node waits for its response.
DEFAULT_SERVER_TIMEOUT_MS = 20

_MISSING = object()


# ---------------------------------------------------------------------------------------------
# Ports and blackboard
# ---------------------------------------------------------------------------------------------

def input_or_blackboard(node: Any, name: str, default: Any = None) -> Any:
    """BT.CPP/Nav2 ``getInputOrBlackboard``: the port if the XML (or a default) gives it, else
    the blackboard entry of the same name, else ``default``."""
    if name in node.config.input_ports:
        return node.get_input(name, default)
    return node.config.blackboard.get(name, default=default)


def remember_goals(node: Any) -> bool:
    """Read ``goal``/``goals`` (port or blackboard), store them on the node as ``node.goal`` and
    ``node.goals``, and say whether they changed (Nav2's goal-updated checks)."""
    goals = input_or_blackboard(node, "goals")
    goal = input_or_blackboard(node, "goal")
    changed = goal != node.goal or goals != node.goals
    node.goal, node.goals = goal, goals
    return changed


def optional_input(node: Any, name: str, default: Any = None) -> Any:
    """An input that may be absent (BT.CPP ``getInput`` returning an error): ``default``."""
    return node.get_input(name, default)


def increment_recovery_count(node: Any) -> None:
    """Nav2's ``number_recoveries`` blackboard counter (NavigateToPose feedback)."""
    bb = node.config.blackboard
    bb.set("number_recoveries", int(bb.get("number_recoveries", default=0)) + 1)


def nav2_topics(context: Any) -> dict[str, Any]:
    """Latched "topics" the selector and goal-updater nodes listen to (Nav2's std_msgs/String
    selector topics and ``goal_update``): ``publish(context, "planner_selector", "GridBased")``."""
    extras = getattr(context, "extras", None)
    if extras is None:
        return {}
    return extras.setdefault("nav2_topics", {})


def publish(context: Any, topic: str, message: Any) -> None:
    """Publish ``message`` on a Nav2 "topic" (latched, like the selectors' transient-local QoS)."""
    extras = getattr(context, "extras", None)
    if extras is None:
        raise BTRuntimeError("the context has no 'extras' dict to hold Nav2 topics")
    extras.setdefault("nav2_topics", {})[topic] = message


def publish_stamped(context: Any, topic: str, message: Any, stamp: float | None = None) -> None:
    """Publish ``(stamp, message)`` (stamp: the context's clock unless given), e.g. a goal
    update for ``GoalUpdater``."""
    if stamp is None:
        stamp = context.clock()
    publish(context, topic, (float(stamp), message))


def server_timeout(node: Any) -> float:
    """``server_timeout`` (ms) from the port, else the blackboard (as the navigator sets it),
    else bt_navigator's 20 ms; returned in seconds."""
    ms = node.get_input("server_timeout", None) if "server_timeout" in node.config.input_ports else None
    if ms is None:
        ms = node.config.blackboard.get("server_timeout", default=DEFAULT_SERVER_TIMEOUT_MS)
    try:
        return float(ms) / 1000.0
    except (TypeError, ValueError):
        return DEFAULT_SERVER_TIMEOUT_MS / 1000.0


# ---------------------------------------------------------------------------------------------
# Path geometry (nav2_util::geometry_utils)
# ---------------------------------------------------------------------------------------------

def points_of(path: Any) -> np.ndarray:
    if path is None:
        return np.empty((0, 3))
    pts = path.points if isinstance(path, Path) else np.asarray(path, dtype=float)
    return pts if pts.ndim == 2 else np.empty((0, 3))


def is_empty(path: Any) -> bool:
    return path is None or len(points_of(path)) == 0


def same_path(a: Any, b: Any) -> bool:
    """Message equality of two paths (stamp and poses), as Nav2 compares nav_msgs/Path."""
    if a is b:
        return True
    if a is None or b is None:
        return False
    if isinstance(a, Path) and isinstance(b, Path) and a.stamp != b.stamp:
        return False
    pa, pb = points_of(a), points_of(b)
    return pa.shape == pb.shape and bool(np.array_equal(pa, pb))


def path_length(path: Any, start: int = 0) -> float:
    """``calculate_path_length(path, start)``: summed segment lengths from pose ``start``."""
    pts = points_of(path)[start:]
    if len(pts) < 2:
        return 0.0
    d = np.diff(pts[:, :2], axis=0)
    return float(np.hypot(d[:, 0], d[:, 1]).sum())


def yaw_at(pts: np.ndarray, i: int) -> float:
    """Heading of pose ``i`` (third column, else along the path)."""
    if pts.shape[1] >= 3:
        return float(pts[i, 2])
    j = min(i + 1, len(pts) - 1)
    k = j - 1 if j > 0 else 0
    return math.atan2(pts[j, 1] - pts[k, 1], pts[j, 0] - pts[k, 0]) if j != k else 0.0


def first_after_integrated_distance(pts: np.ndarray, begin: int, end: int, distance: float,
                                    step: int = 1) -> int:
    """Index of the first pose (walking from ``begin`` towards ``end``, exclusive, in ``step``
    direction) whose integrated distance from ``begin`` exceeds ``distance``; ``end`` if none."""
    if begin == end or distance == math.inf:
        return end
    acc = 0.0
    i = begin
    while True:
        nxt = i + step
        if nxt == end:
            return end
        acc += math.hypot(pts[nxt, 0] - pts[i, 0], pts[nxt, 1] - pts[i, 1])
        if acc > distance:
            return nxt
        i = nxt


def closest_index(pts: np.ndarray, pose: Pose2D, begin: int = 0, end: int | None = None,
                  angular_weight: float = 0.0) -> int:
    """``min_by`` euclidean (plus weighted angular) distance over ``pts[begin:end]``."""
    end = len(pts) if end is None else end
    seg = pts[begin:end]
    if len(seg) == 0:
        return begin
    d2 = (seg[:, 0] - pose.x) ** 2 + (seg[:, 1] - pose.y) ** 2
    if angular_weight and seg.shape[1] >= 3:
        da = np.abs(wrap_angle(seg[:, 2] - pose.yaw)) * angular_weight
        d2 = d2 + da * da
    return begin + int(np.argmin(d2))


def poses_equal(a: Iterable[Any] | None, b: Iterable[Any] | None) -> bool:
    if a is None or b is None:
        return a is b
    return list(a) == list(b)
