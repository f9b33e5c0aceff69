"""Nav2's action-client nodes on the project's navigation client: planner, controller,
behaviours, navigator, the cancel nodes and the selectors. Their mechanics live in ``bases.py``.

Goals go to ``context.navigation`` (``NavigationClient``: ``sim.nav.NavStack`` in simulation).
Behaviour error codes are mapped to the per-action Nav2 codes (the stack reports the generic
700 range: BackUp 710-714, DriveOnHeading 720-724, Wait 740).
"""

from __future__ import annotations

import asyncio
import math
from typing import Any

import numpy as np

from bt_runtime.node import SyncActionNode
from bt_runtime.ports import BOOL, DOUBLE, INT, STRING, input_port, output_port
from bt_runtime.runtime.messages import ActionStatus, NavErrorCode, NavResult, Path, Pose2D, wrap_angle
from bt_runtime.status import FAILURE, SUCCESS, NodeStatus

from ..robot import navigation, robot_pose
from ..types import GOALS, PATH, POSE, TRACKING_FEEDBACK, TrackingFeedback, empty_path
from .bases import (
    NONE,
    BtActionNode,
    BtCancelActionNode,
    SelectorNode,
    error_ports,
    safe_set_output,
    server_ports,
    start_task,
)
from .common import closest_index, increment_recovery_count, is_empty, log, points_of, same_path

# ---------------------------------------------------------------------------------------------
# Planner server
# ---------------------------------------------------------------------------------------------

async def plan_through(nav: Any, poses: list[Pose2D], start: Pose2D | None, planner_id: str,
                       code_offset: int = 0) -> NavResult:
    """Chain ``compute_path_to_pose`` legs through ``poses`` (ComputePathThroughPoses and
    ComputePathToPose ``viapoints``). The first leg starts at ``start`` (else the robot)."""
    pieces: list[np.ndarray] = []
    stamp = 0.0
    for i, goal in enumerate(poses):
        leg_start = start if i == 0 else poses[i - 1]
        res = await nav.compute_path_to_pose(goal, start=leg_start, planner_id=planner_id,
                                             use_start=leg_start is not None)
        if res.status is not ActionStatus.SUCCEEDED:
            code = int(res.error_code)
            if code_offset and 200 <= code < 300:
                code += code_offset
            return NavResult(res.status, code, res.error_msg)
        pts = points_of(res.path)
        pieces.append(pts if not pieces else pts[1:])
        stamp = res.path.stamp if res.path is not None else stamp
    points = np.concatenate(pieces) if pieces else np.empty((0, 3))
    return NavResult(ActionStatus.SUCCEEDED, path=Path(stamp, points))


class ComputePathToPose(BtActionNode):
    """Plans a path to ``goal`` (planner server ``compute_path_to_pose``) into ``path``.

    Starts at the robot, or at ``start`` (given, or with ``use_start``). ``viapoints`` (Nav2
    main) are planned through in order by chaining plans. Abort: empty path + the planner's
    error code (200-208); cancel or halt: empty path, SUCCESS on cancel.
    """

    server = "compute_path_to_pose"

    @classmethod
    def provided_ports(cls):
        return [input_port("start", POSE, description="Used as the planner start pose instead of the "
                                                        "current robot pose, if use_start is not false "
                                                        "(i.e. not provided or set to true)"),
                input_port("use_start", BOOL, description="For using or not using (i.e. ignoring) the "
                                                           "provided start pose"),
                input_port("goal", POSE, description="Destination to plan to"),
                input_port("viapoints", GOALS, description="Viapoints to plan through, in order"),
                input_port("planner_id", STRING, "", "Mapped name to the planner plugin type to use"),
                output_port("path", PATH, description="Path created by ComputePathToPose node"),
                *error_ports("Compute path to pose"),
                *server_ports("compute_path_to_pose")]

    def on_tick(self) -> None:
        goal = self.get_input("goal", None)
        if goal is None:
            log.warning("nav2_missing_goal", node=self.config.path)
            self.should_send_goal = False
            return
        self.goal = {"goal": goal, "planner_id": self.get_input("planner_id", "") or "",
                     "viapoints": self.get_input("viapoints", None) or []}
        start = self.get_input("start", None)
        if "use_start" in self.config.input_ports:
            use_start = bool(self.get_input("use_start", False))
            if use_start and start is None:
                log.error("nav2_use_start_without_start", node=self.config.path)
                use_start = False
        else:
            use_start = start is not None
        self.goal["start"] = start if use_start else None

    def send_goal(self) -> Any:
        nav = navigation(self)
        g = self.goal
        if g["viapoints"]:
            return start_task(self, plan_through(nav, [*g["viapoints"], g["goal"]], g["start"],
                                                 g["planner_id"]))
        return start_task(self, nav.compute_path_to_pose(g["goal"], start=g["start"],
                                                         planner_id=g["planner_id"],
                                                         use_start=g["start"] is not None))

    def on_success(self, result: NavResult) -> NodeStatus:
        safe_set_output(self, "path", result.path if result.path is not None else empty_path())
        return super().on_success(result)

    def on_aborted(self, result: NavResult) -> NodeStatus:
        safe_set_output(self, "path", empty_path(self.config.clock()))
        code = int(result.error_code) or int(NavErrorCode.PLANNER_UNKNOWN)
        safe_set_output(self, "error_code_id", code)
        safe_set_output(self, "error_msg", result.error_msg)
        return FAILURE

    def on_cancelled(self) -> NodeStatus:
        safe_set_output(self, "path", empty_path(self.config.clock()))
        return super().on_cancelled()

    def halt(self) -> None:
        safe_set_output(self, "path", empty_path(self.config.clock()))
        super().halt()


class ComputePathThroughPoses(BtActionNode):
    """Plans a path through ``goals`` in order into ``path`` (``compute_path_through_poses``).

    The navigation client has no through-poses planner, so the legs are planned one after the
    other with ``compute_path_to_pose`` and joined; planner errors are reported with the
    ThroughPoses codes (300-309; 309 NO_VIAPOINTS_GIVEN for an empty list).
    """

    server = "compute_path_through_poses"

    @classmethod
    def provided_ports(cls):
        return [input_port("start", POSE, description="Start pose of the path if overriding current "
                                                        "robot pose"),
                input_port("goals", GOALS, description="Destinations to plan through"),
                input_port("planner_id", STRING, "", "Mapped name to the planner plugin type to use"),
                output_port("path", PATH, description="Path created by ComputePathThroughPoses node"),
                output_port("last_reached_index", INT, description="In the case of a partial plan, index "
                                                                    "of the last reached pose in the "
                                                                    "goals list"),
                *error_ports("Compute path through poses"),
                *server_ports("compute_path_through_poses")]

    def on_tick(self) -> None:
        self.goal = {"goals": list(self.get_input("goals", None) or []),
                     "planner_id": self.get_input("planner_id", "") or "",
                     "start": self.get_input("start", None)}

    def send_goal(self) -> Any:
        g = self.goal
        if not g["goals"]:
            async def no_viapoints() -> NavResult:
                return NavResult(ActionStatus.ABORTED, 309, "no viapoints given")
            return start_task(self, no_viapoints())
        return start_task(self, plan_through(navigation(self), g["goals"], g["start"], g["planner_id"],
                                             code_offset=100))

    def on_success(self, result: NavResult) -> NodeStatus:
        safe_set_output(self, "path", result.path)
        safe_set_output(self, "last_reached_index", len(self.goal.get("goals", ())) - 1)
        return super().on_success(result)

    def on_aborted(self, result: NavResult) -> NodeStatus:
        safe_set_output(self, "path", empty_path(self.config.clock()))
        code = int(result.error_code) or 300
        safe_set_output(self, "error_code_id", code)
        safe_set_output(self, "error_msg", result.error_msg)
        return FAILURE

    def on_cancelled(self) -> NodeStatus:
        safe_set_output(self, "path", empty_path(self.config.clock()))
        return super().on_cancelled()


class SmoothPath(SyncActionNode):
    """Path smoothing (smoother server). The project's planner already returns smoothed,
    collision-checked paths, so this passes ``unsmoothed_path`` through unchanged
    (``was_completed`` true, ``smoothing_duration`` 0); an empty path fails with 505
    INVALID_PATH."""

    @classmethod
    def provided_ports(cls):
        return [input_port("unsmoothed_path", PATH, description="Path to be smoothed"),
                input_port("max_smoothing_duration", DOUBLE, 3.0, "Maximum smoothing duration"),
                input_port("check_for_collisions", BOOL, False, "Bool if collision check should be performed"),
                input_port("smoother_id", STRING, description="Smoother id"),
                output_port("smoothed_path", PATH, description="Smoothed path"),
                output_port("smoothing_duration", DOUBLE, description="Smoothing duration"),
                output_port("was_completed", BOOL, description="True if smoothing was not interrupted by time "
                                                              "limit"),
                *error_ports("Smooth path"),
                *server_ports("smooth_path")]

    def tick(self) -> NodeStatus:
        path = self.get_input("unsmoothed_path", None)
        if is_empty(path):
            safe_set_output(self, "error_code_id", 505)
            safe_set_output(self, "error_msg", "empty path")
            return FAILURE
        safe_set_output(self, "smoothed_path", path)
        safe_set_output(self, "smoothing_duration", 0.0)
        safe_set_output(self, "was_completed", True)
        safe_set_output(self, "error_code_id", NONE)
        safe_set_output(self, "error_msg", "")
        return SUCCESS


# ---------------------------------------------------------------------------------------------
# Controller server
# ---------------------------------------------------------------------------------------------

class FollowPath(BtActionNode):
    """Follows ``path`` with the controller server (``follow_path``) until the goal checker
    is satisfied: SUCCESS; abort: FAILURE with the controller's code (100-107).

    While running, a new ``{path}`` (or controller / goal-checker / progress-checker id) is
    passed to the running action (``handle.update_path``: a Nav2 preempting goal, which keeps
    the progress checker), or re-sent as a new goal when the client cannot update. An empty
    new path is ignored. ``tracking_feedback`` (Nav2 main) is computed from the robot pose and
    the path each tick.
    """

    server = "follow_path"

    @classmethod
    def provided_ports(cls):
        return [input_port("path", PATH, description="Path to follow"),
                input_port("controller_id", STRING, description="Mapped name of the controller plugin "
                                                                 "type to use"),
                input_port("goal_checker_id", STRING, description="Mapped name of the goal checker plugin "
                                                                   "type to use"),
                input_port("progress_checker_id", STRING, description="Mapped name of the progress checker "
                                                                       "plugin type to use"),
                input_port("path_handler_id", STRING, description="Mapped name of the path handler plugin "
                                                                   "type to use"),
                output_port("tracking_feedback", TRACKING_FEEDBACK,
                            description="Tracking feedback of the controller (cross-track and heading error)"),
                *error_ports("Follow path"),
                *server_ports("follow_path")]

    _IDS = ("controller_id", "goal_checker_id", "progress_checker_id", "path_handler_id")

    def on_tick(self) -> None:
        self.goal = {"path": self.get_input("path", None)}
        self._id_ports = [key for key in self._IDS if key in self.config.input_ports]  # given ones
        for key in self._IDS:
            self.goal[key] = self.get_input(key, "") or "" if key in self._id_ports else ""
        self._ids_changed = False

    def send_goal(self) -> Any:
        g = self.goal
        path = g["path"] if g["path"] is not None else empty_path()
        return navigation(self).follow_path(path, controller_id=g["controller_id"],
                                            goal_checker_id=g["goal_checker_id"],
                                            progress_checker_id=g["progress_checker_id"])

    def on_wait_for_result(self) -> None:
        new_path = self.get_input("path", None)
        if not is_empty(new_path) and not same_path(self.goal["path"], new_path):
            self.goal["path"] = new_path
            self.goal_updated = True
        for key in self._id_ports:
            value = self.get_input(key, "") or ""
            if value != self.goal[key]:
                self.goal[key] = value
                self.goal_updated = True
                self._ids_changed = True
        if "tracking_feedback" in self.config.output_ports:
            fb = self.tracking_feedback()
            if fb is not None:
                safe_set_output(self, "tracking_feedback", fb)

    def update_goal(self) -> None:
        update = getattr(self.handle, "update_path", None)
        if not self._ids_changed and update is not None and update(self.goal["path"]):
            return
        self._ids_changed = False
        self._send()

    def tracking_feedback(self) -> TrackingFeedback | None:
        pose = robot_pose(self)
        pts = points_of(self.goal.get("path"))
        if pose is None or len(pts) == 0:
            return None
        i = closest_index(pts, pose)
        if len(pts) >= 2:
            j = min(i + 1, len(pts) - 1)
            k = j - 1
            dx, dy = pts[j, 0] - pts[k, 0], pts[j, 1] - pts[k, 1]
            seg = math.hypot(dx, dy) or 1.0
            cross = (dx * (pose.y - pts[k, 1]) - dy * (pose.x - pts[k, 0])) / seg
            path_yaw = math.atan2(dy, dx)
        else:
            cross = math.hypot(pose.x - pts[0, 0], pose.y - pts[0, 1])
            path_yaw = pose.yaw
        d = np.diff(pts[i:, :2], axis=0)
        remaining = float(np.hypot(d[:, 0], d[:, 1]).sum()) if len(d) else 0.0
        fb = getattr(self.handle, "feedback", None)
        speed = float(getattr(fb, "speed", 0.0) or 0.0)
        return TrackingFeedback(self.config.clock(), float(cross), wrap_angle(pose.yaw - path_yaw), int(i),
                                pose, math.hypot(pts[-1, 0] - pose.x, pts[-1, 1] - pose.y), speed, remaining)


# ---------------------------------------------------------------------------------------------
# Behavior server
# ---------------------------------------------------------------------------------------------

_B = NavErrorCode


def _motion_limits(node: BtActionNode) -> dict[str, Any]:
    """The keyword arguments every motion behaviour (spin, back up, drive on heading) sends:
    ``time_allowance``, and ``disable_collision_checks`` only when it is set."""
    limits: dict[str, Any] = {"time_allowance": float(node.get_input("time_allowance", 10.0))}
    if node.get_input("disable_collision_checks", False):
        limits["disable_collision_checks"] = True
    return limits


class Spin(BtActionNode):
    """Rotates in place by ``spin_dist`` rad (behavior server ``spin``); counts as a recovery
    when ``is_recovery``. Errors 700-703 (COLLISION_AHEAD 703, TIMEOUT 701)."""

    server = "spin"
    code_map = {int(_B.INVALID_INPUT): 700}

    @classmethod
    def provided_ports(cls):
        return [input_port("spin_dist", DOUBLE, 1.57, "Spin distance"),
                input_port("time_allowance", DOUBLE, 10.0, "Allowed time for spinning"),
                input_port("is_recovery", BOOL, True, "True if recovery"),
                input_port("disable_collision_checks", BOOL, False, "Disable collision checking"),
                *error_ports("Spin"),
                *server_ports("spin")]

    def on_tick(self) -> None:
        self.goal = {"spin_dist": float(self.get_input("spin_dist", 1.57)), "limits": _motion_limits(self)}
        if self.get_input("is_recovery", True):
            increment_recovery_count(self)

    def send_goal(self) -> Any:
        return navigation(self).spin(self.goal["spin_dist"], **self.goal["limits"])


class BackUp(BtActionNode):
    """Drives straight backwards ``backup_dist`` m at ``backup_speed`` m/s (behavior server
    ``backup``); counts as a recovery. Errors 710-714 (COLLISION_AHEAD 714, TIMEOUT 711)."""

    server = "backup"
    code_map = {700: 710, 701: 711, 702: 712, 703: 714, 704: 713}

    @classmethod
    def provided_ports(cls):
        return [input_port("backup_dist", DOUBLE, 0.15, "Total distance to backup (m)."),
                input_port("backup_speed", DOUBLE, 0.025, "Backup speed (m/s)."),
                input_port("time_allowance", DOUBLE, 10.0, "Time to invoke behavior for, if exceeds "
                                                           "considers it a stuck condition or failure "
                                                           "case (seconds)."),
                input_port("disable_collision_checks", BOOL, False, "Disable collision checking."),
                *error_ports("Backup"),
                *server_ports("backup")]

    def on_tick(self) -> None:
        self.goal = {"dist": float(self.get_input("backup_dist", 0.15)),
                     "speed": float(self.get_input("backup_speed", 0.025)), "limits": _motion_limits(self)}
        increment_recovery_count(self)

    def send_goal(self) -> Any:
        g = self.goal
        return navigation(self).back_up(g["dist"], g["speed"], **g["limits"])


class DriveOnHeading(BtActionNode):
    """Drives straight ``dist_to_travel`` m at ``speed`` m/s (signs must match) (behavior
    server ``drive_on_heading``). Errors 720-724 (COLLISION_AHEAD 723, INVALID_INPUT 724)."""

    server = "drive_on_heading"
    code_map = {700: 720, 701: 721, 702: 722, 703: 723, 704: 724}

    @classmethod
    def provided_ports(cls):
        return [input_port("dist_to_travel", DOUBLE, 0.15, "Distance to travel (m)."),
                input_port("speed", DOUBLE, 0.025, "Speed at which to travel (m/s)."),
                input_port("time_allowance", DOUBLE, 10.0, "Time to invoke behavior for, if exceeds "
                                                           "considers it a stuck condition or failure "
                                                           "case (seconds)."),
                input_port("disable_collision_checks", BOOL, False, "Disable collision checking."),
                *error_ports("Drive on heading"),
                *server_ports("drive_on_heading")]

    def on_tick(self) -> None:
        self.goal = {"dist": float(self.get_input("dist_to_travel", 0.15)),
                     "speed": float(self.get_input("speed", 0.025)), "limits": _motion_limits(self)}

    def send_goal(self) -> Any:
        g = self.goal
        return navigation(self).drive_on_heading(g["dist"], g["speed"], **g["limits"])


class Wait(BtActionNode):
    """Waits ``wait_duration`` s (behavior server ``wait``; a negative or zero duration is made
    positive, as Nav2); counts as a recovery."""

    server = "wait"
    code_map = {700: 740, 701: 741}

    @classmethod
    def provided_ports(cls):
        return [input_port("wait_duration", DOUBLE, 1.0, "Wait time"),
                *error_ports("Wait"),
                *server_ports("wait")]

    def on_tick(self) -> None:
        duration = float(self.get_input("wait_duration", 1.0))
        if duration <= 0:
            log.warning("nav2_wait_duration_not_positive", node=self.config.path, duration=duration)
            duration = -duration
        self.goal = {"duration": duration}
        increment_recovery_count(self)

    def send_goal(self) -> Any:
        return navigation(self).wait(self.goal["duration"])


# ---------------------------------------------------------------------------------------------
# Navigator (nested navigation)
# ---------------------------------------------------------------------------------------------

class NavigateToPose(BtActionNode):
    """Navigates to ``goal`` with the navigation client's own ``navigate_to_pose`` (in
    simulation: plan, follow and replan at 1 Hz, no recoveries). Error codes are the
    client's (planner 2xx / controller 1xx)."""

    server = "navigate_to_pose"

    @classmethod
    def provided_ports(cls):
        return [input_port("goal", POSE, description="Destination to plan to"),
                input_port("behavior_tree", STRING, description="Behavior tree to run"),
                *error_ports("Navigate to pose"),
                *server_ports("navigate_to_pose")]

    def on_tick(self) -> None:
        goal = self.get_input("goal", None)
        if goal is None:
            log.warning("nav2_missing_goal", node=self.config.path)
            self.should_send_goal = False
        self.goal = {"goal": goal, "behavior_tree": self.get_input("behavior_tree", "") or ""}

    def send_goal(self) -> Any:
        return navigation(self).navigate_to_pose(self.goal["goal"], behavior_tree=self.goal["behavior_tree"])


async def _navigate_through(nav: Any, goals: list[Pose2D], behavior_tree: str) -> NavResult:
    for goal in goals:
        handle = nav.navigate_to_pose(goal, behavior_tree=behavior_tree)
        try:
            res = await handle
        except asyncio.CancelledError:
            handle.cancel()
            raise
        if res.status is not ActionStatus.SUCCEEDED:
            return res
    return NavResult(ActionStatus.SUCCEEDED)


class NavigateThroughPoses(BtActionNode):
    """Navigates through ``goals`` in order. The client has no through-poses navigator, so
    this runs ``navigate_to_pose`` to each goal in turn (the robot meets the goal tolerance at
    every via-point instead of passing through it)."""

    server = "navigate_through_poses"

    @classmethod
    def provided_ports(cls):
        return [input_port("goals", GOALS, description="Destinations to plan through"),
                input_port("behavior_tree", STRING, description="Behavior tree to run"),
                *error_ports("Navigate through poses"),
                *server_ports("navigate_through_poses")]

    def on_tick(self) -> None:
        goals = list(self.get_input("goals", None) or [])
        if not goals:
            self.should_send_goal = False
        self.goal = {"goals": goals, "behavior_tree": self.get_input("behavior_tree", "") or ""}

    def send_goal(self) -> Any:
        return start_task(self, _navigate_through(navigation(self), self.goal["goals"],
                                                  self.goal["behavior_tree"]))


# ---------------------------------------------------------------------------------------------
# Cancel nodes
# ---------------------------------------------------------------------------------------------

class CancelControl(BtCancelActionNode):
    """Cancels the controller server's FollowPath goals."""

    server = "follow_path"


class CancelSpin(BtCancelActionNode):
    """Cancels Spin goals."""

    server = "spin"


class CancelBackUp(BtCancelActionNode):
    """Cancels BackUp goals."""

    server = "backup"


class CancelDriveOnHeading(BtCancelActionNode):
    """Cancels DriveOnHeading goals."""

    server = "drive_on_heading"


class CancelWait(BtCancelActionNode):
    """Cancels Wait goals."""

    server = "wait"


# ---------------------------------------------------------------------------------------------
# Selectors
# ---------------------------------------------------------------------------------------------

def _selector(cls_name: str, topic: str, default_port: str, output: str, what: str) -> type:
    doc = (f"Outputs the {what} id to use on ``{output}``: the last one published on the "
           f"``{topic}`` topic, else ``{default_port}``; FAILURE if neither exists.")
    return type(cls_name, (SelectorNode,), {"topic_default": topic, "default_port": default_port,
                                            "output_name": output, "what": what, "__doc__": doc,
                                            "__module__": __name__})


PlannerSelector = _selector("PlannerSelector", "planner_selector", "default_planner", "selected_planner",
                            "planner")
ControllerSelector = _selector("ControllerSelector", "controller_selector", "default_controller",
                               "selected_controller", "controller")
GoalCheckerSelector = _selector("GoalCheckerSelector", "goal_checker_selector", "default_goal_checker",
                                "selected_goal_checker", "goal_checker")
ProgressCheckerSelector = _selector("ProgressCheckerSelector", "progress_checker_selector",
                                    "default_progress_checker", "selected_progress_checker",
                                    "progress_checker")
SmootherSelector = _selector("SmootherSelector", "smoother_selector", "default_smoother",
                             "selected_smoother", "smoother")
PathHandlerSelector = _selector("PathHandlerSelector", "path_handler_selector", "default_path_handler",
                                "selected_path_handler", "path_handler")
