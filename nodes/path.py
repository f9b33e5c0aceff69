"""Path behaviours (fn_req7, fn_req8): rate planned paths and find reachable goals nearby.

``FindAlternativeGoal`` is the paper's future work, made safe and stable: candidates on rings
of increasing radius around an unreachable goal; only candidates with clearance from lethal
cells count (the inflation radius plus a margin preferred, the robot's radius plus a margin
accepted); among the reachable ones of the nearest rings the one with the lowest cost (path
length plus a weight on the distance to the goal) wins, so a candidate behind a wall with a
much longer path loses to one on the robot's side. The choice is remembered per goal and kept
while the planner still reaches it.
"""

from __future__ import annotations

import math

import numpy as np
import structlog

from bt_runtime import AsyncActionNode, ConditionNode, NodeStatus
from bt_runtime.ports import input_port, output_port
from bt_runtime.runtime.messages import NavErrorCode, Path, Pose2D, wrap_angle

from .robot import robot_pose
from .types import ERROR_CODE, PATH, POSE

log = structlog.get_logger("nodes.path")
SUCCESS, FAILURE = NodeStatus.SUCCESS, NodeStatus.FAILURE


class RatePathQuality(ConditionNode):
    """SUCCESS if ``path`` is valid on the current costmap, not longer than ``max_length_ratio``
    times the straight line, and keeps ``min_clearance`` m from lethal cells.

    The stretch of the path within ``escape_radius`` m of the robot is not judged: a robot that
    stands in an inflation zone (beside its own obstacle mark, say) must be able to drive out
    of it, and every path starts in the robot's own inflated cell then."""

    @classmethod
    def provided_ports(cls):
        return [input_port("path", PATH, "{path}"), input_port("goal", POSE, "{goal}"),
                input_port("max_length_ratio", float, 3.0), input_port("min_clearance", float, 0.0, "m"),
                input_port("escape_radius", float, 0.6, "m around the robot not judged"),
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
        ahead = beyond(path, pose, self.get_input("escape_radius"))
        if ahead is None:  # the whole path lies within the escape radius
            clearance, valid = math.inf, True
        else:
            clearance = nav.path_clearance(ahead)
            valid = nav.is_path_valid(ahead)
        quality = 0.0 if not valid else min(1.0, 1.0 / max(ratio, 1.0)) * min(1.0, clearance / 0.5)
        self.set_output("quality", float(quality))
        ok = valid and ratio <= self.get_input("max_length_ratio") and clearance >= self.get_input("min_clearance")
        return SUCCESS if ok else FAILURE


class PathReachesGoal(ConditionNode):
    """SUCCESS if ``path`` ends within ``tolerance`` m of ``goal``.

    Nav2's NavFn (default ``tolerance`` 0.5 m) answers a goal inside an obstacle with a plan to
    the nearest plannable cell, which lies in the inflation zone, right beside the obstacle.
    Following it drives the robot against what the scan then marks. A plan that stops short
    means the goal is occupied: FAILURE, and ``error_code_id`` is set to GOAL_OCCUPIED (206) so
    the tree searches a safe alternative instead."""

    @classmethod
    def provided_ports(cls):
        return [input_port("path", PATH, "{path}"), input_port("goal", POSE, "{goal}"),
                input_port("tolerance", float, 0.1, "m between the path's end and the goal"),
                output_port("error_code_id", ERROR_CODE, "{plan_error}", "206 (GOAL_OCCUPIED) when it stops short")]

    def tick(self):
        path: Path | None = self.get_input("path", None)
        goal: Pose2D = self.get_input("goal")
        if path is not None and ends_at(path, goal, self.get_input("tolerance")):
            return SUCCESS
        self.set_output("error_code_id", int(NavErrorCode.GOAL_OCCUPIED))
        return FAILURE


class PlannerAnswers(AsyncActionNode):
    """SUCCESS if the planner plans a trivial request (from the robot to where it stands).

    Tells "the planner is broken" from "the goal is cut off": both fail ComputePathToPose with
    NO_VALID_PATH, but a planner that fails every request fails this one too. After a restart
    that did not help and no alternative, a planner that answers means the goal is unreachable:
    retrying (and restarting the planner again) cannot help."""

    async def run(self):
        pose = robot_pose(self)
        if pose is None:
            return FAILURE
        result = await self.context.navigation.compute_path_to_pose(pose)
        return SUCCESS if result.succeeded else FAILURE


def ends_at(path: Path, goal: Pose2D, tolerance: float) -> bool:
    """Does ``path`` end within ``tolerance`` m of ``goal``?"""
    if len(path) < 1:
        return False
    end = path.points[-1]
    return math.hypot(float(end[0]) - goal.x, float(end[1]) - goal.y) <= tolerance


def beyond(path: Path, pose: Pose2D, radius: float) -> Path | None:
    """The part of ``path`` from its first point farther than ``radius`` from ``pose`` on."""
    pts = path.points
    d = np.hypot(pts[:, 0] - pose.x, pts[:, 1] - pose.y)
    far = np.flatnonzero(d > radius)
    if not len(far):
        return None
    return Path(path.stamp, pts[far[0]:])


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
    """Search a safe, reachable goal around an unreachable one; writes it, its path and a
    ``detail`` line saying which pose was used. FAILURE if none within ``max_radius``.

    Keeps the alternative chosen for a goal while the planner reaches it. Otherwise, ring by
    ring (nearest first), candidates with ``clearance`` m from lethal cells (``min_clearance``
    when no candidate has that much) are planned to; once a ring has reachable ones, the next
    ``extra_rings`` rings are planned too and the candidate with the least ``path length +
    distance_weight * distance to the goal`` wins.
    """

    @classmethod
    def provided_ports(cls):
        return [input_port("goal", POSE, "{goal}"), input_port("max_radius", float, 1.0, "m"),
                input_port("step", float, 0.1, "m between rings"),
                input_port("directions", int, 16, "candidates per ring"),
                input_port("clearance", float, 0.55, "m from lethal cells preferred (inflation radius + margin)"),
                input_port("min_clearance", float, 0.0, "m from lethal cells at least (0: robot radius + 0.1, "
                                                          "two cells, so re-marking from the scan does not "
                                                          "put it in the inscribed zone)"),
                input_port("extra_rings", int, 2, "rings planned beyond the first reachable one"),
                input_port("distance_weight", float, 2.0, "cost per m from the goal, in m of path"),
                output_port("alternative", POSE, "{nav_goal}"), output_port("path", PATH, "{path}"),
                output_port("tried", int, "{alternatives_tried}"),
                output_port("detail", str, "{goal_detail}", "which alternative was used")]

    async def run(self):
        nav = self.context.navigation
        goal: Pose2D = self.get_input("goal")
        memory = self.context.extras.setdefault("alternative_goals", {})
        kept = memory.get(goal)
        floor = self.get_input("min_clearance") or (self.context.robot.radius + 0.1)
        if kept is not None and _clearance(nav, kept) >= floor - 0.05:  # one cell of re-marking tolerated
            result = await nav.compute_path_to_pose(kept)
            if _reaches(result, kept):
                return self._use(goal, kept, result.path, 1)
            memory.pop(goal, None)  # it became invalid: search again
        robot = robot_pose(self)
        candidates = ring_candidates(goal, robot, self.get_input("max_radius"), self.get_input("step"),
                                     self.get_input("directions"))
        clear = [(c, _clearance(nav, c)) for c in candidates]
        for need in (self.get_input("clearance"), floor):
            best, tried = await self._search(nav, goal, [c for c, d in clear if d >= need])
            if best is not None:
                memory[goal] = best[1]
                return self._use(goal, best[1], best[2], tried)
        self.set_output("tried", len(candidates))
        return FAILURE

    async def _search(self, nav, goal: Pose2D, candidates: list[Pose2D]):
        """The best reachable candidate (cost, pose, path) of the nearest reachable rings."""
        weight = self.get_input("distance_weight")
        step = self.get_input("step")
        best = None
        last_ring = math.inf
        tried = 0
        for candidate in candidates:
            ring = round(candidate.distance_to(goal) / step)
            if ring > last_ring:
                break
            tried += 1
            result = await nav.compute_path_to_pose(candidate)
            if result.error_code in (NavErrorCode.PLANNER_UNKNOWN, NavErrorCode.PLANNER_TF_ERROR):
                return None, tried  # the planner itself is down: searching further cannot help
            if not _reaches(result, candidate):
                continue
            cost = result.path.length + weight * candidate.distance_to(goal)
            if best is None or cost < best[0]:
                best = (cost, candidate, result.path)
            if last_ring == math.inf:
                last_ring = ring + self.get_input("extra_rings")
        return best, tried

    def _use(self, goal: Pose2D, alternative: Pose2D, path: Path, tried: int):
        self.set_output("alternative", alternative)
        self.set_output("path", path)
        self.set_output("tried", tried)
        self.set_output("detail", f"alternative goal {alternative.x:.2f};{alternative.y:.2f};{alternative.yaw:.2f} "
                                  f"({alternative.distance_to(goal):.2f} m from the requested goal)")
        return SUCCESS


def _reaches(result, pose: Pose2D) -> bool:
    """A plan that ends at ``pose`` (not one the planner's goal tolerance moved elsewhere: the
    candidate itself is occupied then)."""
    return bool(result.succeeded and result.path is not None and ends_at(result.path, pose, 0.1))


def _clearance(nav, pose: Pose2D) -> float:
    return nav.path_clearance(Path(0.0, np.array([[pose.x, pose.y, pose.yaw]])))


class EscapeInflation(AsyncActionNode):
    """A way out for a robot that stands too close to a lethal cell (e.g. beside its own
    obstacle mark): there every path and every controller projection starts "in collision",
    so neither planning nor Nav2's BackUp gets it out. Looks ``distance`` m around the robot
    in ``directions`` directions for the point with the most clearance, turns to it and drives
    there with the costmap collision check off (it drives away from what is near). SUCCESS at
    once when the robot already has ``clearance`` m (0: robot radius + 0.1); FAILURE if no
    direction is better than where it stands or the motion failed."""

    @classmethod
    def provided_ports(cls):
        return [input_port("clearance", float, 0.0, "m from lethal cells that needs no escape (0: radius + 0.1)"),
                input_port("distance", float, 0.3, "m to drive out"),
                input_port("directions", int, 16),
                input_port("speed", float, 0.08, "m/s")]

    async def run(self):
        nav = self.context.navigation
        pose = robot_pose(self)
        if pose is None:
            return FAILURE
        need = self.get_input("clearance") or (self.context.robot.radius + 0.1)
        here = _clearance(nav, pose)
        if here >= need:
            return SUCCESS
        distance = self.get_input("distance")
        n = self.get_input("directions")
        best_angle, best = None, here
        for k in range(n):
            a = 2 * math.pi * k / n
            c = _clearance(nav, Pose2D(pose.x + distance * math.cos(a), pose.y + distance * math.sin(a)))
            if c > best + 1e-6:
                best_angle, best = a, c
        if best_angle is None:
            return FAILURE
        turn = wrap_angle(best_angle - pose.yaw)
        log.info("escape_inflation", clearance=round(here, 3), heading=round(best_angle, 2),
                 target_clearance=round(best, 3))
        if abs(turn) > 0.15:
            result = await nav.spin(turn, time_allowance=10.0, disable_collision_checks=True)
            if not result.succeeded:
                return FAILURE
        result = await nav.drive_on_heading(distance, self.get_input("speed"), time_allowance=10.0,
                                            disable_collision_checks=True)
        return SUCCESS if result.succeeded else FAILURE
