"""Nav2's action- and service-client nodes on the project's navigation client.

``BtActionNode`` reproduces ``nav2_behavior_tree::BtActionNode``: the first tick of an
activation reads the ports (``on_tick``) and sends the goal, and the node returns RUNNING
until the result is in. SUCCEEDED -> ``on_success`` (SUCCESS), ABORTED -> ``on_aborted``
(FAILURE, the server's error code on ``error_code_id``), **CANCELED -> ``on_cancelled``
(SUCCESS)**. While running, ``on_wait_for_result`` may change the goal (FollowPath does when
``{path}`` changes) and the goal is re-sent. Halting a running node cancels its goal (and
calls ``on_cancelled``, as Nav2 does, so outputs such as the path are written).

``BtServiceNode`` reproduces ``BtServiceNode``: the request goes out on the first tick; SUCCESS
when the response arrives, FAILURE when it does not within ``server_timeout`` (ms; port, else
the blackboard's ``server_timeout``, else bt_navigator's 20 ms) or when the call fails.

Goals go to ``context.navigation`` (``NavigationClient``: ``sim.nav.NavStack`` in simulation);
the ticks never await: coroutines (planning, costmap services) run as tasks that are polled.
Behaviour error codes are mapped to the per-action Nav2 codes (the stack reports the generic
700 range: BackUp 710-714, DriveOnHeading 720-724, Wait 740).
"""

from __future__ import annotations

import asyncio
import math
from typing import Any, ClassVar

import numpy as np

from bt_runtime.errors import LogicError
from bt_runtime.node import NodeConfig, StatefulActionNode, SyncActionNode
from bt_runtime.ports import BOOL, DOUBLE, INT, STRING, input_port, output_port
from bt_runtime.runtime.messages import ActionStatus, NavErrorCode, NavResult, Path, Pose2D, wrap_angle
from bt_runtime.status import FAILURE, RUNNING, SUCCESS, NodeStatus

from ..robot import navigation, robot_pose
from ..types import (
    ERROR_CODE,
    GOALS,
    PATH,
    POSE,
    SERVER_TIMEOUT,
    STRING_LIST,
    TRACKING_FEEDBACK,
    TrackingFeedback,
    empty_path,
)
from .common import (
    closest_index,
    increment_recovery_count,
    is_empty,
    log,
    points_of,
    same_path,
    server_timeout,
)

NONE = 0


def server_ports(default_server: str, service: bool = False) -> list:
    kind = "Service" if service else "Action server"
    return [input_port("server_name", STRING, description=f"{kind} name. If not specified, "
                                                            f"`{default_server}` is used."),
            input_port("server_timeout", SERVER_TIMEOUT,
                       description=f"{kind} timeout (ms). If not provided, uses the BT Navigator's "
                                   "`default_server_timeout` (20 ms)")]


def error_ports(what: str) -> list:
    return [output_port("error_code_id", ERROR_CODE, description=f"{what} error code"),
            output_port("error_msg", STRING, description=f"{what} error message")]


def safe_set_output(node: Any, name: str, value: Any) -> None:
    """Write an output if the XML remaps it to a blackboard entry (BT.CPP's setOutput returns
    an error, it does not throw, when the port is not connected)."""
    raw = node.config.output_ports.get(name)
    if raw is None:
        return
    s = raw.strip()
    if raw in ("=", "{=}") or (len(s) >= 3 and s[0] == "{" and s[-1] == "}"):
        node.set_output(name, value)


def _running_loop(node: Any) -> asyncio.AbstractEventLoop:
    try:
        return asyncio.get_running_loop()
    except RuntimeError:
        raise LogicError(f"'{node.config.path}' [{node.registration_name}] needs a running asyncio event loop "
                         "(run the tree with the runtime or tick_while_running_async)") from None


class TaskHandle:
    """A coroutine of the navigation client (planning, a costmap service) as a handle."""

    __slots__ = ("task", "cancel_requested")

    def __init__(self, task: asyncio.Task):
        self.task = task
        self.cancel_requested = False

    def done(self) -> bool:
        return self.task.done()

    def cancel(self) -> None:
        if not self.task.done():
            self.cancel_requested = True
            self.task.cancel()

    def result(self) -> NavResult:
        task = self.task
        if task.cancelled():
            return NavResult(ActionStatus.CANCELED, NavErrorCode.NONE, "canceled")
        exc = task.exception()
        if exc is not None:
            return NavResult(ActionStatus.ABORTED, NavErrorCode.NONE, f"{type(exc).__name__}: {exc}")
        value = task.result()
        if isinstance(value, NavResult):
            return value
        return NavResult(ActionStatus.SUCCEEDED)

    @property
    def feedback(self) -> Any:
        return None


def start_task(node: Any, coro: Any) -> TaskHandle:
    loop = _running_loop(node)
    return TaskHandle(loop.create_task(coro, name=f"bt:{node.config.path}"))


def _goal_registry(node: Any) -> dict[str, set]:
    extras = getattr(node.context, "extras", None)
    if extras is None:
        return {}
    return extras.setdefault("nav2_goals", {})


# ---------------------------------------------------------------------------------------------
# BtActionNode
# ---------------------------------------------------------------------------------------------

class BtActionNode(StatefulActionNode):
    """Base of the Nav2 action-client nodes (see the module docstring)."""

    server: ClassVar[str] = ""  # Nav2's default action name (also the cancel-node registry key)
    code_map: ClassVar[dict[int, int]] = {}  # stack error code -> this action's Nav2 code

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.handle: Any = None
        self.goal: dict[str, Any] = {}
        self.goal_updated = False
        self.should_send_goal = True
        super().__init__(name, config)

    # -- hooks (Nav2's names) --------------------------------------------------------------------
    def on_tick(self) -> None:
        """Read the ports into ``self.goal``; set ``should_send_goal = False`` to fail."""

    def send_goal(self) -> Any:
        raise NotImplementedError

    def update_goal(self) -> None:
        """The goal changed while running: re-send it (Nav2 send_new_goal)."""
        self._send()

    def on_wait_for_result(self) -> None:
        """Called each tick while waiting; may set ``goal_updated``."""

    def on_success(self, result: NavResult) -> NodeStatus:
        safe_set_output(self, "error_code_id", NONE)
        safe_set_output(self, "error_msg", "")
        return SUCCESS

    def on_aborted(self, result: NavResult) -> NodeStatus:
        safe_set_output(self, "error_code_id", self.map_code(result.error_code))
        safe_set_output(self, "error_msg", result.error_msg)
        return FAILURE

    def on_cancelled(self) -> NodeStatus:
        safe_set_output(self, "error_code_id", NONE)
        safe_set_output(self, "error_msg", "")
        return SUCCESS

    def map_code(self, code: int) -> int:
        code = int(code)
        return self.code_map.get(code, code)

    # -- mechanics ---------------------------------------------------------------------------------
    def _send(self) -> None:
        old = self.handle
        self.handle = self.send_goal()
        reg = _goal_registry(self)
        if reg is not None and self.server:
            goals = reg.setdefault(self.server, set())
            if old is not None:
                goals.discard(old)
            goals.add(self.handle)

    def _forget(self) -> None:
        reg = _goal_registry(self)
        if self.handle is not None and self.server in reg:
            reg[self.server].discard(self.handle)
        self.handle = None

    def on_start(self) -> NodeStatus:
        self.should_send_goal = True
        self.goal_updated = False
        self.goal = {}
        self.on_tick()
        if not self.should_send_goal:
            return FAILURE
        try:
            self._send()
        except LogicError:
            raise
        except Exception as exc:  # Nav2: "send_goal failed" -> FAILURE
            log.warning("nav2_send_goal_failed", node=self.config.path, error=f"{type(exc).__name__}: {exc}")
            self.handle = None
            return FAILURE
        return self._poll()

    def on_running(self) -> NodeStatus:
        return self._poll()

    def _poll(self) -> NodeStatus:
        handle = self.handle
        if handle is None:
            return FAILURE
        if not handle.done():
            self.on_wait_for_result()
            if self.goal_updated:
                self.goal_updated = False
                self.update_goal()
                handle = self.handle
            if not handle.done():
                return RUNNING
        result = handle.result()
        self._forget()
        if result.status is ActionStatus.SUCCEEDED:
            return self.on_success(result)
        if result.status is ActionStatus.ABORTED:
            return self.on_aborted(result)
        return self.on_cancelled()

    def on_halted(self) -> None:
        handle = self.handle
        if handle is not None and not handle.done():
            handle.cancel()
            self.on_cancelled()
        self._forget()


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
# Cancel nodes (BtCancelActionNode)
# ---------------------------------------------------------------------------------------------

class BtCancelActionNode(SyncActionNode):
    """Cancels every goal this tree's Nav2 nodes sent to the action server (Nav2 cancels all
    goals of the server sent more than 10 ms ago). SUCCESS (also when nothing runs)."""

    server: ClassVar[str] = ""

    @classmethod
    def provided_ports(cls):
        return server_ports(cls.server)

    def tick(self) -> NodeStatus:
        self.set_status(RUNNING)
        for handle in list(_goal_registry(self).get(self.server, ())):
            if not handle.done():
                handle.cancel()
        return SUCCESS


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
# Services
# ---------------------------------------------------------------------------------------------

class BtServiceNode(StatefulActionNode):
    """Base of the Nav2 service-client nodes (see the module docstring)."""

    service: ClassVar[str] = ""

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.future: TaskHandle | None = None
        self.sent_time = 0.0
        self.timeout = 0.02
        self.should_send_request = True
        super().__init__(name, config)

    def on_tick(self) -> None:
        """Fill the request; set ``should_send_request = False`` to fail."""

    def call(self) -> Any:
        """The coroutine (or plain value) that serves the request."""
        raise NotImplementedError

    def on_completion(self, response: Any) -> NodeStatus:
        return SUCCESS

    def on_start(self) -> NodeStatus:
        self.should_send_request = True
        self.on_tick()
        if not self.should_send_request:
            return FAILURE
        self.timeout = server_timeout(self)
        try:
            result = self.call()
        except LogicError:
            raise
        except Exception as exc:
            log.warning("nav2_service_failed", node=self.config.path, error=f"{type(exc).__name__}: {exc}")
            return FAILURE
        if asyncio.iscoroutine(result):
            self.future = start_task(self, result)
            self.sent_time = self.config.clock()
            return self.check_future()
        return self.on_completion(result)

    def on_running(self) -> NodeStatus:
        return self.check_future()

    def check_future(self) -> NodeStatus:
        future = self.future
        if future is None:
            return FAILURE
        if future.done():
            self.future = None
            task = future.task
            if task.cancelled() or task.exception() is not None:
                exc = None if task.cancelled() else task.exception()
                log.warning("nav2_service_failed", node=self.config.path,
                            error=f"{type(exc).__name__}: {exc}" if exc else "cancelled")
                return FAILURE
            return self.on_completion(task.result())
        if self.config.clock() - self.sent_time < self.timeout:
            return RUNNING
        log.warning("nav2_service_timeout", node=self.config.path, service=self.service,
                    timeout_ms=round(self.timeout * 1000))
        future.cancel()
        self.future = None
        return FAILURE

    def on_halted(self) -> None:
        if self.future is not None:
            self.future.cancel()
            self.future = None


def _which_costmap(service_name: str) -> str:
    name = service_name or ""
    if "local" in name:
        return "local"
    if "global" in name:
        return "global"
    return "both"


class ClearEntireCostmap(BtServiceNode):
    """Clears a costmap's sensor data (``<costmap>/clear_entirely_<costmap>``): local or global
    by ``service_name``, both if the name says neither. Counts as a recovery. ``plugins``
    (Nav2 main: clear only some layers) is accepted; every obstacle layer is cleared."""

    service = "clear_entirely_costmap"

    @classmethod
    def provided_ports(cls):
        return [input_port("service_name", STRING, description="Service name"),
                input_port("plugins", STRING_LIST, description="List of specific plugins to clear. If "
                                                                "empty, all plugins are cleared."),
                input_port("server_timeout", SERVER_TIMEOUT,
                           description="Server timeout (ms). If not provided, uses the BT Navigator's "
                                       "`default_server_timeout` (20 ms)")]

    def on_tick(self) -> None:
        increment_recovery_count(self)

    def call(self) -> Any:
        return navigation(self).clear_costmaps(_which_costmap(self.get_input("service_name", "") or ""))


class ClearCostmapAroundRobot(ClearEntireCostmap):
    """Nav2 clears the obstacle data within ``reset_distance`` of the robot; the navigation
    client can only clear a whole costmap's sensor data, which this does (a superset)."""

    service = "clear_around_costmap"

    @classmethod
    def provided_ports(cls):
        return [input_port("reset_distance", DOUBLE, 1.0, "Distance from the robot to clear"),
                *super().provided_ports()]


class ClearCostmapExceptRegion(ClearEntireCostmap):
    """Nav2 clears the obstacle data outside ``reset_distance`` of the robot; the client
    clears the whole costmap's sensor data (a superset)."""

    service = "clear_except_costmap"

    @classmethod
    def provided_ports(cls):
        return [input_port("reset_distance", DOUBLE, 1.0, "Distance from the robot to keep"),
                *super().provided_ports()]


class ClearCostmapAroundPose(ClearEntireCostmap):
    """Nav2 clears the obstacle data within ``reset_distance`` of ``pose``; the client clears
    the whole costmap's sensor data (a superset)."""

    service = "clear_around_pose"

    @classmethod
    def provided_ports(cls):
        return [input_port("pose", POSE, description="Pose around which to clear"),
                input_port("reset_distance", DOUBLE, 1.0, "Distance from the pose to clear"),
                *super().provided_ports()]


class ValidatePath(BtServiceNode):
    """Nav2 main's path check (planner server ``is_path_valid``): SUCCESS if ``path`` from
    the pose closest to the robot on is free. ``max_cost`` as Nav2 (254 = lethal only), capped
    at 253 (inscribed) because the robot footprint is a circle, as Nav2 does for a
    ``robot_radius`` costmap. ``layer_name``, ``footprint``, ``max_lookahead_distance`` and
    ``collision_poses`` are not supported by the client (accepted, ignored)."""

    service = "is_path_valid"

    @classmethod
    def provided_ports(cls):
        return [input_port("path", PATH, description="Path to validate"),
                input_port("max_cost", "unsigned int", 254, "Maximum cost allowed for a pose"),
                input_port("consider_unknown_as_obstacle", BOOL, False, "Unknown cells are obstacles"),
                input_port("layer_name", STRING, "", "Costmap layer to check (empty: master costmap)"),
                input_port("footprint", STRING, "", "Footprint to check (empty: the robot's)"),
                input_port("stop_at_first_collision", BOOL, True, "Stop at the first pose in collision"),
                input_port("max_lookahead_distance", DOUBLE, -1.0,
                           "Maximum distance along the path to check (negative: all)"),
                output_port("collision_poses", GOALS, description="Poses of the path in collision"),
                *server_ports("is_path_valid", service=True)]

    def on_tick(self) -> None:
        self.path = self.get_input("path", None)

    def call(self) -> Any:
        if is_empty(self.path):
            return False
        max_cost = min(int(self.get_input("max_cost", 254)), 253)
        return bool(navigation(self).is_path_valid(self.path, max_cost))

    def on_completion(self, response: Any) -> NodeStatus:
        return SUCCESS if response else FAILURE


class SelectorNode(SyncActionNode):
    """A selector: outputs the id last published on its topic, else the default; FAILURE if
    neither exists. Publish with ``nodes.nav2.common.publish(context, topic, "id")``."""

    topic_default: ClassVar[str] = ""
    default_port: ClassVar[str] = ""
    output_name: ClassVar[str] = ""
    what: ClassVar[str] = ""

    @classmethod
    def provided_ports(cls):
        return [input_port("topic_name", STRING, cls.topic_default, f"the input topic name to select the "
                                                                     f"{cls.what}"),
                input_port(cls.default_port, STRING, description=f"the default {cls.what} to use if there "
                                                                 "is not any external topic message received."),
                output_port(cls.output_name, STRING, description=f"Selected {cls.what} by subscription")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        super().__init__(name, config)
        self.topic = self.get_input("topic_name", self.topic_default) or self.topic_default
        self.last_selected = ""

    def tick(self) -> NodeStatus:
        from .common import nav2_topics

        msg = nav2_topics(self.context).get(self.topic)
        if isinstance(msg, str) and msg:
            self.last_selected = msg
        if not self.last_selected:
            default = self.get_input(self.default_port, "") or ""
            if not default:
                return FAILURE
            self.last_selected = default
        safe_set_output(self, self.output_name, self.last_selected)
        return SUCCESS


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

