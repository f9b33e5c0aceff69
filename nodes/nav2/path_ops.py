"""Nav2's synchronous path and goal utilities: TruncatePath, TruncatePathLocal,
RemovePassedGoals, GetPoseFromPath, ConcatenatePaths, GetCurrentPose, AppendGoalPoseToGoals,
GetNextFewGoals."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from bt_runtime.node import NodeConfig, SyncActionNode
from bt_runtime.ports import DOUBLE, INT, STRING, input_port, output_port
from bt_runtime.runtime.messages import Path, Pose2D
from bt_runtime.status import FAILURE, RUNNING, SUCCESS, NodeStatus

from ..robot import robot_pose
from ..types import GOALS, PATH, POSE, WAYPOINT_STATUSES, WaypointStatusCode, empty_path
from .bases import safe_set_output
from .common import closest_index, first_after_integrated_distance, points_of, same_path


def _with_points(path: Any, pts: np.ndarray) -> Path:
    stamp = path.stamp if isinstance(path, Path) else 0.0
    return Path(stamp, pts)


class TruncatePath(SyncActionNode):
    """Drops the trailing poses closer than ``distance`` (straight line) to the final pose,
    keeping at least two, and turns the new last pose towards the original goal position."""

    @classmethod
    def provided_ports(cls):
        return [input_port("input_path", PATH, description="Original Path"),
                input_port("distance", DOUBLE, 1.0, "distance"),
                output_port("output_path", PATH, description="Path truncated to a certain distance")]

    def tick(self) -> NodeStatus:
        self.set_status(RUNNING)
        distance = float(self.get_input("distance", 1.0))
        path = self.get_input("input_path", None)
        pts = points_of(path)
        if len(pts) == 0:
            safe_set_output(self, "output_path", path if path is not None else empty_path())
            return SUCCESS
        final = pts[-1].copy()
        n = len(pts)
        while n > 2 and math.hypot(pts[n - 1, 0] - final[0], pts[n - 1, 1] - final[1]) < distance:
            n -= 1
        out = np.array(pts[:n], dtype=float)
        if out.shape[1] < 3:
            out = np.column_stack([out[:, :2], np.zeros(len(out))])
        angle = math.atan2(final[1] - out[-1, 1], final[0] - out[-1, 0])
        out[-1, 2] = angle if math.isfinite(angle) else 0.0
        safe_set_output(self, "output_path", _with_points(path, out))
        return SUCCESS


class TruncatePathLocal(SyncActionNode):
    """Outputs the part of ``input_path`` around the robot: from ``distance_backward`` behind
    to ``distance_forward`` ahead (integrated along the path) of the pose closest to the
    robot (or to ``pose``). ``distance_forward`` < 0 means the whole rest of the path (Nav2
    main). A finite ``max_robot_pose_search_dist`` bounds the closest-pose search to that far
    ahead of the previous match. FAILURE without a robot pose."""

    @classmethod
    def provided_ports(cls):
        return [input_port("input_path", PATH, description="Original Path"),
                output_port("output_path", PATH, description="Path truncated to a certain distance around "
                                                               "robot"),
                input_port("distance_forward", DOUBLE, 8.0, "Distance in forward direction"),
                input_port("distance_backward", DOUBLE, 4.0, "Distance in backward direction"),
                input_port("robot_frame", STRING, "base_link", "Robot base frame id"),
                input_port("robot_base_frame", STRING, description="Robot base frame id (Nav2 main)"),
                input_port("transform_tolerance", DOUBLE, 0.2, "Transform lookup tolerance"),
                input_port("pose", POSE, description="Manually specified pose to be used if overriding "
                                                       "current robot pose"),
                input_port("angular_distance_weight", DOUBLE, 0.0,
                           "Weight of angular distance relative to positional distance when finding which "
                           "path pose is closest to robot. Not applicable on paths without orientations "
                           "assigned"),
                input_port("max_robot_pose_search_dist", DOUBLE, math.inf,
                           "Maximum forward integrated distance along the path (starting from the last "
                           "detected pose) to bound the search for the closest pose to the robot. When set "
                           "to infinity (default), whole path is searched every time")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.path: Any = None
        self.begin = 0
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        self.set_status(RUNNING)
        forward = float(self.get_input("distance_forward", 8.0))
        backward = float(self.get_input("distance_backward", 4.0))
        weight = float(self.get_input("angular_distance_weight", 0.0))
        search = float(self.get_input("max_robot_pose_search_dist", math.inf))
        if forward < 0.0:
            forward = math.inf
        pruning = math.isfinite(search)
        new_path = self.get_input("input_path", None)
        if not pruning or not same_path(new_path, self.path):
            self.path = new_path
            self.begin = 0
        pose = self.get_input("pose", None)
        if pose is None:
            pose = robot_pose(self)
            if pose is None:
                return FAILURE
        pts = points_of(self.path)
        if len(pts) == 0:
            safe_set_output(self, "output_path", self.path if self.path is not None else empty_path())
            return SUCCESS
        end = len(pts)
        if pruning:
            end = first_after_integrated_distance(pts, self.begin, len(pts), search)
        current = closest_index(pts, pose, self.begin, max(end, self.begin + 1), weight)
        if pruning:
            self.begin = current
        fwd = first_after_integrated_distance(pts, current, len(pts), forward)
        # walking backwards from the closest pose: the first pose beyond distance_backward
        bwd = first_after_integrated_distance(pts, current, -1, backward, step=-1)
        start = bwd + 1
        safe_set_output(self, "output_path", _with_points(self.path, np.array(pts[start:fwd])))
        return SUCCESS


class RemovePassedGoals(SyncActionNode):
    """Removes the leading goals within ``radius`` of the robot (never the last one) and
    marks them COMPLETED in the waypoint statuses (Nav2 main). FAILURE without a pose."""

    @classmethod
    def provided_ports(cls):
        return [input_port("input_goals", GOALS, description="Original goals to remove viapoints from"),
                output_port("output_goals", GOALS, description="Goals with passed viapoints removed"),
                input_port("radius", DOUBLE, 0.5, "radius to goal for it to be considered for removal"),
                input_port("global_frame", STRING, description="Global frame"),
                input_port("robot_base_frame", STRING, description="Robot base frame"),
                input_port("input_waypoint_statuses", WAYPOINT_STATUSES,
                           description="Original waypoint_statuses to mark waypoint status from"),
                output_port("output_waypoint_statuses", WAYPOINT_STATUSES,
                            description="Waypoint_statuses with passed waypoints marked")]

    def tick(self) -> NodeStatus:
        goals = list(self.get_input("input_goals", None) or [])
        if not goals:
            safe_set_output(self, "output_goals", goals)
            return SUCCESS
        pose = robot_pose(self)
        if pose is None:
            return FAILURE
        radius = float(self.get_input("radius", 0.5))
        statuses = self.get_input("input_waypoint_statuses", None)
        statuses = [s for s in statuses] if statuses is not None else None
        while len(goals) > 1:
            if goals[0].distance_to(pose) > radius:
                break
            if statuses is not None:
                idx = next((i for i, s in enumerate(statuses)
                            if s.waypoint_status == WaypointStatusCode.PENDING and s.waypoint_pose == goals[0]),
                           -1)
                if idx == -1:
                    return FAILURE
                statuses[idx].waypoint_status = WaypointStatusCode.COMPLETED
            goals.pop(0)
        safe_set_output(self, "output_goals", goals)
        if statuses is not None:
            safe_set_output(self, "output_waypoint_statuses", statuses)
        return SUCCESS


class GetPoseFromPath(SyncActionNode):
    """Outputs the pose at ``index`` of ``path`` (negative indices count from the end);
    FAILURE on an empty path or an index out of range."""

    @classmethod
    def provided_ports(cls):
        return [input_port("path", PATH, description="Path to extract pose from"),
                input_port("index", INT, 0, "Index of pose to extract from. -1 is end of list"),
                output_port("pose", POSE, description="Pose from the path")]

    def tick(self) -> NodeStatus:
        self.set_status(RUNNING)
        pts = points_of(self.get_input("path", None))
        index = int(self.get_input("index", 0))
        if len(pts) == 0:
            return FAILURE
        if index < 0:
            index += len(pts)
        if index < 0 or index >= len(pts):
            return FAILURE
        row = pts[index]
        yaw = float(row[2]) if len(row) >= 3 else 0.0
        safe_set_output(self, "pose", Pose2D(float(row[0]), float(row[1]), yaw))
        return SUCCESS


class ConcatenatePaths(SyncActionNode):
    """Outputs ``input_path1`` followed by ``input_path2``; FAILURE if both are empty."""

    @classmethod
    def provided_ports(cls):
        return [input_port("input_path1", PATH, description="Input Path 1 to concatenate"),
                input_port("input_path2", PATH, description="Input Path 2 to concatenate"),
                output_port("output_path", PATH, description="Paths concatenated")]

    def tick(self) -> NodeStatus:
        self.set_status(RUNNING)
        p1, p2 = self.get_input("input_path1", None), self.get_input("input_path2", None)
        a, b = points_of(p1), points_of(p2)
        if len(a) == 0 and len(b) == 0:
            return FAILURE
        parts = [x for x in (a, b) if len(x)]
        cols = min(x.shape[1] for x in parts)
        pts = np.concatenate([x[:, :cols] for x in parts])
        stamp = p1.stamp if isinstance(p1, Path) and p1.stamp else (p2.stamp if isinstance(p2, Path) else 0.0)
        safe_set_output(self, "output_path", Path(stamp, pts))
        return SUCCESS


class GetCurrentPose(SyncActionNode):
    """Outputs the robot's current map-frame pose; FAILURE without one."""

    @classmethod
    def provided_ports(cls):
        return [input_port("global_frame", STRING, description="Global frame to transform pose into"),
                input_port("robot_base_frame", STRING, description="Robot base frame"),
                output_port("current_pose", POSE, description="Current pose output")]

    def tick(self) -> NodeStatus:
        pose = robot_pose(self)
        if pose is None:
            return FAILURE
        safe_set_output(self, "current_pose", pose)
        return SUCCESS


class AppendGoalPoseToGoals(SyncActionNode):
    """Outputs ``input_goals`` with ``goal_pose`` appended."""

    @classmethod
    def provided_ports(cls):
        return [input_port("goal_pose", POSE, description="Goal pose to append"),
                input_port("input_goals", GOALS, description="Input goals to append to"),
                output_port("output_goals", GOALS, description="Output goals with goal pose appended")]

    def tick(self) -> NodeStatus:
        self.set_status(RUNNING)
        goals = list(self.get_input("input_goals", None) or [])
        pose = self.get_input("goal_pose", None)
        if pose is not None:
            goals.append(pose)
        safe_set_output(self, "output_goals", goals)
        return SUCCESS


class GetNextFewGoals(SyncActionNode):
    """Outputs the first ``num_goals`` of ``input_goals``; FAILURE if there are none."""

    @classmethod
    def provided_ports(cls):
        return [input_port("num_goals", "unsigned int", description="Number of goals to get"),
                input_port("input_goals", GOALS, description="Input goals to get the next few from"),
                output_port("output_goals", GOALS, description="Output goals")]

    def tick(self) -> NodeStatus:
        self.set_status(RUNNING)
        goals = list(self.get_input("input_goals", None) or [])
        n = int(self.get_input("num_goals", 0) or 0)
        if not goals:
            return FAILURE
        safe_set_output(self, "output_goals", goals[:n])
        return SUCCESS
