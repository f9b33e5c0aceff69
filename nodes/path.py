"""Path behaviours (fn_req7, fn_req8): rate planned paths and find reachable goals nearby.

``FindAlternativeGoal`` is the paper's future work: candidates on rings of increasing radius
around an unreachable goal, in all directions, nearest first (on a ring, those closer to the
robot first); the first one the planner reaches wins.
"""

from __future__ import annotations

import math

from bt_runtime import AsyncActionNode, ConditionNode, NodeStatus
from bt_runtime.ports import input_port, output_port
from bt_runtime.runtime.messages import NavErrorCode, Path, Pose2D, wrap_angle

from .robot import robot_pose
from .types import PATH, POSE

SUCCESS, FAILURE = NodeStatus.SUCCESS, NodeStatus.FAILURE


class RatePathQuality(ConditionNode):
    """SUCCESS if ``path`` is valid on the current costmap, not longer than ``max_length_ratio``
    times the straight line, and keeps ``min_clearance`` m from lethal cells."""

    @classmethod
    def provided_ports(cls):
        return [input_port("path", PATH, "{path}"), input_port("goal", POSE, "{goal}"),
                input_port("max_length_ratio", float, 3.0), input_port("min_clearance", float, 0.0, "m"),
                output_port("quality", float, "{path_quality}", "0 (unusable) .. 1 (straight, clear)")]

    def tick(self):
        nav = self.context.navigation
        path: Path | None = self.get_input("path", None)
        pose = robot_pose(self)
        if path is None or len(path) < 2 or pose is None:
            self.set_output("quality", 0.0)
            return FAILURE
        goal: Pose2D = self.get_input("goal")
        straight = max(pose.distance_to(goal), 1e-6)
        ratio = path.length / straight
        clearance = nav.path_clearance(path)
        valid = nav.is_path_valid(path)
        quality = 0.0 if not valid else min(1.0, 1.0 / max(ratio, 1.0)) * min(1.0, clearance / 0.5)
        self.set_output("quality", float(quality))
        ok = valid and ratio <= self.get_input("max_length_ratio") and clearance >= self.get_input("min_clearance")
        return SUCCESS if ok else FAILURE


def ring_candidates(goal: Pose2D, robot: Pose2D | None, max_radius: float, step: float,
                    directions: int) -> list[Pose2D]:
    """Candidates around ``goal``: by ring (nearest first), on a ring those facing the robot first."""
    out = []
    rings = int(round(max_radius / step))
    toward = math.atan2(robot.y - goal.y, robot.x - goal.x) if robot is not None else 0.0
    for i in range(1, rings + 1):
        r = i * step
        angles = [toward + 2 * math.pi * k / directions for k in range(directions)]
        angles.sort(key=lambda a: abs(wrap_angle(a - toward)))
        for a in angles:
            x, y = goal.x + r * math.cos(a), goal.y + r * math.sin(a)
            out.append(Pose2D(x, y, math.atan2(goal.y - y, goal.x - x)))
    return out


class FindAlternativeGoal(AsyncActionNode):
    """Search reachable goals around an unreachable one; writes the nearest reachable goal and
    its path. FAILURE if none within ``max_radius``."""

    @classmethod
    def provided_ports(cls):
        return [input_port("goal", POSE, "{goal}"), input_port("max_radius", float, 1.0, "m"),
                input_port("step", float, 0.1, "m between rings"),
                input_port("directions", int, 16, "candidates per ring"),
                output_port("alternative", POSE, "{nav_goal}"), output_port("path", PATH, "{path}"),
                output_port("tried", int, "{alternatives_tried}")]

    async def run(self):
        nav = self.context.navigation
        goal: Pose2D = self.get_input("goal")
        candidates = ring_candidates(goal, robot_pose(self), self.get_input("max_radius"),
                                     self.get_input("step"), self.get_input("directions"))
        tried = 0
        for candidate in candidates:
            tried += 1
            result = await nav.compute_path_to_pose(candidate)
            if result.succeeded and result.path is not None and len(result.path) >= 1:
                self.set_output("alternative", candidate)
                self.set_output("path", result.path)
                self.set_output("tried", tried)
                return SUCCESS
            if result.error_code in (NavErrorCode.PLANNER_UNKNOWN, NavErrorCode.PLANNER_TF_ERROR):
                break  # the planner itself is down: searching further cannot help
        self.set_output("tried", tried)
        return FAILURE
