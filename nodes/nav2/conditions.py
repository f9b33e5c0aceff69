"""Nav2's conditions (nav2_behavior_tree/plugins/condition).

Robot state comes from the data backup (``context.backup``): ``pose`` (LocalizedPose, for
Nav2's TF lookups), ``odom`` (Odometry), ``battery`` (BatteryState). Time is the tree clock.
"""

from __future__ import annotations

from typing import Any, ClassVar

from bt_runtime.node import ConditionNode, NodeConfig
from bt_runtime.ports import BOOL, DOUBLE, STRING, input_port
from bt_runtime.runtime.messages import POWER_SUPPLY_CHARGING, POWER_SUPPLY_UNKNOWN
from bt_runtime.status import FAILURE, IDLE, SUCCESS, NodeStatus

from ..robot import latest, navigation, robot_pose
from ..types import ERROR_CODE, GOALS, INT_LIST, PATH, POSE, SERVER_TIMEOUT, TRACKING_FEEDBACK
from .common import (
    closest_index,
    first_after_integrated_distance,
    input_or_blackboard,
    is_empty,
    path_length,
    points_of,
    remember_goals,
    same_path,
    server_timeout,
)

_STATUS = {True: SUCCESS, False: FAILURE}


class GoalUpdated(ConditionNode):
    """SUCCESS when the goal (or goals) changed since the last tick of this activation.

    The first tick of an activation stores the goal and returns FAILURE. As in Nav2, a
    reactive parent resets this node to IDLE while a sibling runs, so inside the default
    tree's ReactiveFallback it cannot fire while a recovery action is RUNNING (Nav2 issue
    #6082); kept as upstream for an honest baseline.
    """

    @classmethod
    def provided_ports(cls):
        return [input_port("goal", POSE, description="Destination"),
                input_port("goals", GOALS, description="Vector of navigation goals")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.goal: Any = None
        self.goals: Any = None
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        changed = remember_goals(self)
        return SUCCESS if changed and self._status is not IDLE else FAILURE


class GlobalUpdatedGoal(ConditionNode):
    """Like GoalUpdated, but its memory lives as long as the node (not reset by halts) and the
    very first tick ever returns SUCCESS ("updated")."""

    @classmethod
    def provided_ports(cls):
        return [input_port("goal", POSE, description="Destination"),
                input_port("goals", GOALS, description="Vector of navigation goals")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.first_time = True
        self.goal: Any = None
        self.goals: Any = None
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        changed = remember_goals(self)
        if self.first_time:
            self.first_time = False
            return SUCCESS
        return SUCCESS if changed else FAILURE


class IsGoalNearby(ConditionNode):
    """SUCCESS if the path length left from the path pose closest to the robot is below
    ``proximity_threshold``. With ``max_robot_pose_search_dist`` >= 0 the search for the
    closest pose starts at the last one found and looks that far ahead along the path.
    FAILURE on an empty path or without a robot pose."""

    @classmethod
    def provided_ports(cls):
        return [input_port("path", PATH, description="Planned Path"),
                input_port("proximity_threshold", DOUBLE, 1.0,
                           "Proximity length (m) of the remaining path considered as a nearby"),
                input_port("max_robot_pose_search_dist", DOUBLE, -1.0,
                           "Maximum forward integrated distance along the path (starting from the last "
                           "detected pose) to bound the search for the closest pose to the robot. When "
                           "set to negative value (default), the whole path is searched every time"),
                input_port("global_frame", STRING, description="Global frame"),
                input_port("robot_base_frame", STRING, description="Robot base frame")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.path: Any = None
        self.begin = 0
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        new_path = self.get_input("path", None)
        threshold = float(self.get_input("proximity_threshold", 0.0))
        search = float(self.get_input("max_robot_pose_search_dist", -1.0))
        if is_empty(new_path):
            return FAILURE
        pruning = search >= 0.0
        if not pruning or not same_path(new_path, self.path):
            self.path = new_path
            self.begin = 0
        pose = robot_pose(self)
        if pose is None:
            return FAILURE
        pts = points_of(self.path)
        end = len(pts)
        if pruning:
            end = first_after_integrated_distance(pts, self.begin, len(pts), search)
        idx = closest_index(pts, pose, self.begin, max(end, self.begin + 1))
        self.begin = idx
        return _STATUS[path_length(self.path, idx) < threshold]


class IsPathValid(ConditionNode):
    """SUCCESS if the path, from the pose closest to the robot on, is still collision free
    (planner server ``is_path_valid`` service: no lethal / inscribed cost, inside the map).
    FAILURE on an empty path or when the planner server cannot answer."""

    @classmethod
    def provided_ports(cls):
        return [input_port("path", PATH, description="Path to Check"),
                input_port("server_timeout", SERVER_TIMEOUT, description="Service timeout (ms)")]

    def tick(self) -> NodeStatus:
        path = self.get_input("path", None)
        if is_empty(path):
            return FAILURE
        server_timeout(self)  # synchronous service: nothing to wait for
        try:
            return _STATUS[bool(navigation(self).is_path_valid(path))]
        except Exception:  # the service is down / failed: Nav2 returns FAILURE
            return FAILURE


class PathExpiringTimer(ConditionNode):
    """FAILURE until ``seconds`` have passed since the path last changed, then SUCCESS once
    (and the timer restarts). The first tick ever stores the path and returns FAILURE."""

    @classmethod
    def provided_ports(cls):
        return [input_port("seconds", DOUBLE, 1.0, "Seconds"),
                input_port("path", PATH, description="Check if path has been updated to enable timer reset")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.first_time = True
        self.period = 1.0
        self.prev_path: Any = None
        self.start = 0.0
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        clock = self.config.clock
        if self.first_time:
            self.period = float(self.get_input("seconds", 1.0))
            self.prev_path = self.get_input("path", None)
            self.first_time = False
            self.start = clock()
            return FAILURE
        path = self.get_input("path", None)
        if not same_path(path, self.prev_path):
            self.prev_path = path
            self.start = clock()
        if clock() - self.start < self.period:
            return FAILURE
        self.start = clock()
        return SUCCESS


class AreErrorCodesPresent(ConditionNode):
    """SUCCESS if ``error_code`` is one of ``error_codes_to_check``. An unset error code
    (never written this goal) reads as 0 = NONE."""

    CODES: ClassVar[frozenset[int] | None] = None  # subclasses: a fixed set (the port is ignored)

    @classmethod
    def provided_ports(cls):
        return [input_port("error_code", ERROR_CODE, description="The active error codes"),
                input_port("error_codes_to_check", INT_LIST, description="Error codes to check")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        super().__init__(name, config)
        if self.CODES is not None:
            self.codes = self.CODES
        else:
            self.codes = frozenset(int(c) for c in (self.get_input("error_codes_to_check", None) or ()))

    def tick(self) -> NodeStatus:
        code = self.get_input("error_code", 0)
        return _STATUS[int(code or 0) in self.codes]


class WouldAControllerRecoveryHelp(AreErrorCodesPresent):
    """SUCCESS if the FollowPath error is one a recovery may fix: UNKNOWN (100),
    PATIENCE_EXCEEDED (104), FAILED_TO_MAKE_PROGRESS (105), NO_VALID_CONTROL (106)."""

    CODES = frozenset({100, 104, 105, 106})


class WouldAPlannerRecoveryHelp(AreErrorCodesPresent):
    """SUCCESS if the planner error is one a recovery may fix: UNKNOWN (200/300), TIMEOUT
    (207/307), NO_VALID_PATH (208/308) of ComputePathToPose / ComputePathThroughPoses."""

    CODES = frozenset({200, 207, 208, 300, 307, 308})


class WouldARouteRecoveryHelp(AreErrorCodesPresent):
    """SUCCESS for route-server errors UNKNOWN (400), TIMEOUT (404), NO_VALID_ROUTE (405)."""

    CODES = frozenset({400, 404, 405})


class WouldASmootherRecoveryHelp(AreErrorCodesPresent):
    """SUCCESS for smoother errors UNKNOWN (500), TIMEOUT (502), SMOOTHED_PATH_IN_COLLISION
    (503), FAILED_TO_SMOOTH_PATH (504)."""

    CODES = frozenset({500, 502, 503, 504})


class ArePosesNear(ConditionNode):
    """SUCCESS if the two poses are within ``tolerance`` metres (x, y)."""

    @classmethod
    def provided_ports(cls):
        return [input_port("ref_pose", POSE, description="Destination"),
                input_port("target_pose", POSE, description="Destination"),
                input_port("global_frame", STRING, description="World frame"),
                input_port("tolerance", DOUBLE, 0.5, "Tolerance")]

    def tick(self) -> NodeStatus:
        a = self.get_input("ref_pose", None)
        b = self.get_input("target_pose", None)
        tol = float(self.get_input("tolerance", 0.5))
        if a is None or b is None:
            return FAILURE
        dx, dy = a.x - b.x, a.y - b.y
        return _STATUS[dx * dx + dy * dy <= tol * tol]


class IsStuck(ConditionNode):
    """SUCCESS (= stuck) when the last two odometry messages show a deceleration harder than
    10 m/s^2 (a sudden stop, e.g. a bump). Nav2's only stuck test; not moving at all is the
    controller's progress checker's business."""

    BRAKE_ACCEL_LIMIT = -10.0

    def tick(self) -> NodeStatus:
        ctx = self.context
        backup = getattr(ctx, "backup", None) if ctx is not None else None
        if backup is None:
            return FAILURE
        msgs = backup.last_n("odom", 2)
        if len(msgs) < 2:
            return FAILURE
        prev, curr = msgs
        dt = curr.stamp - prev.stamp
        if dt <= 0:
            return FAILURE
        accel = (curr.twist.linear - prev.twist.linear) / dt
        return _STATUS[accel < self.BRAKE_ACCEL_LIMIT]


class IsBatteryLow(ConditionNode):
    """SUCCESS if the last battery message reports a charge at or below ``min_battery``: a
    fraction 0..1 as ROS's ``BatteryState.percentage`` (our BatteryState holds 0..100, divided
    by 100 here), or volts with ``is_voltage``. No message yet: FAILURE. No staleness check
    (as Nav2)."""

    @classmethod
    def provided_ports(cls):
        return [input_port("min_battery", DOUBLE, description="Minimum battery percentage/voltage"),
                input_port("battery_topic", STRING, "/battery_status", "Battery topic"),
                input_port("is_voltage", BOOL, False, "If true voltage will be used to check for low battery")]

    def tick(self) -> NodeStatus:
        msg = latest(self, "battery")
        if msg is None:
            return FAILURE
        min_battery = float(self.get_input("min_battery", 0.0))
        if self.get_input("is_voltage", False):
            return _STATUS[msg.voltage <= min_battery]
        return _STATUS[msg.percentage / 100.0 <= min_battery]


class IsBatteryCharging(ConditionNode):
    """SUCCESS if the last battery message says the battery is charging: ``power_supply_status
    == CHARGING`` (Nav2's test); a monitor that reports no status (UNKNOWN) is charging when its
    current flows in (current < 0)."""

    @classmethod
    def provided_ports(cls):
        return [input_port("battery_topic", STRING, "/battery_status", "Battery topic")]

    def tick(self) -> NodeStatus:
        msg = latest(self, "battery")
        if msg is None:
            return FAILURE
        status = getattr(msg, "power_supply_status", POWER_SUPPLY_UNKNOWN)
        if status != POWER_SUPPLY_UNKNOWN:
            return _STATUS[status == POWER_SUPPLY_CHARGING]
        return _STATUS[msg.current < 0.0]


class GoalReached(ConditionNode):
    """SUCCESS if the robot is within ``goal_reached_tol`` (0.25 m, Nav2's parameter default)
    of ``goal`` (x, y)."""

    GOAL_REACHED_TOL = 0.25

    @classmethod
    def provided_ports(cls):
        return [input_port("goal", POSE, description="Destination"),
                input_port("global_frame", STRING, description="Global frame"),
                input_port("robot_base_frame", STRING, description="Robot base frame")]

    def tick(self) -> NodeStatus:
        goal = self.get_input("goal", None)
        pose = robot_pose(self)
        if goal is None or pose is None:
            return FAILURE
        return _STATUS[pose.distance_to(goal) <= self.GOAL_REACHED_TOL]


class TimeExpired(ConditionNode):
    """FAILURE on the first tick of an activation (starts the timer); afterwards SUCCESS once
    every ``seconds`` (the timer restarts), FAILURE in between."""

    @classmethod
    def provided_ports(cls):
        return [input_port("seconds", DOUBLE, 1.0, "Seconds")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.period = 1.0
        self.start = 0.0
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        clock = self.config.clock
        if self._status is IDLE:
            self.period = float(self.get_input("seconds", 1.0))
            self.start = clock()
            return FAILURE
        if clock() - self.start < self.period:
            return FAILURE
        self.start = clock()
        return SUCCESS


class DistanceTraveled(ConditionNode):
    """FAILURE on the first tick of an activation (stores the pose); afterwards SUCCESS each
    time the robot is ``distance`` m (straight line) from the stored pose (then it moves the
    reference), FAILURE otherwise or without a pose."""

    @classmethod
    def provided_ports(cls):
        return [input_port("distance", DOUBLE, 1.0, "Distance"),
                input_port("global_frame", STRING, description="Global frame"),
                input_port("robot_base_frame", STRING, description="Robot base frame")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.start_pose = None
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        if self._status is IDLE:
            self.start_pose = robot_pose(self)
            return FAILURE
        current = robot_pose(self)
        if current is None or self.start_pose is None:
            if self.start_pose is None:
                self.start_pose = current
            return FAILURE
        if self.start_pose.distance_to(current) < float(self.get_input("distance", 1.0)):
            return FAILURE
        self.start_pose = current
        return SUCCESS


class TransformAvailable(ConditionNode):
    """SUCCESS once the transform ``parent`` -> ``child`` exists (then for good). Without TF,
    a frame pair involving ``map`` exists when localization publishes a pose, one involving
    ``odom`` when odometry publishes; other pairs (robot-fixed frames) always exist."""

    @classmethod
    def provided_ports(cls):
        return [input_port("child", STRING, "", "Child frame for transform"),
                input_port("parent", STRING, "", "Parent frame for transform")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.was_found = False
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        if self.was_found:
            return SUCCESS
        child = self.get_input("child", "")
        parent = self.get_input("parent", "")
        if not child or not parent:
            raise RuntimeError("TransformAvailableCondition: Child or parent frames not provided!")
        frames = {child.lstrip("/"), parent.lstrip("/")}
        if "map" in frames:
            ok = robot_pose(self) is not None
        elif "odom" in frames:
            ok = latest(self, "odom") is not None
        else:
            ok = True
        self.was_found = ok
        return _STATUS[ok]


class InitialPoseReceived(ConditionNode):
    """SUCCESS if the blackboard flag ``initial_pose_received`` is true (Nav2 sets it when an
    initial pose is published); FAILURE if false or unset."""

    @classmethod
    def provided_ports(cls):
        return [input_port("initial_pose_received", BOOL, description="Initial pose received")]

    def tick(self) -> NodeStatus:
        return _STATUS[bool(input_or_blackboard(self, "initial_pose_received", False))]


class IsWithinPathTrackingBounds(ConditionNode):
    """SUCCESS while FollowPath's ``tracking_feedback`` is within the bounds: cross-track error
    (+ = left) at most ``max_error_left`` / ``max_error_right``, heading error at most
    ``max_error_heading``; SUCCESS before any feedback exists."""

    @classmethod
    def provided_ports(cls):
        return [input_port("max_error_left", DOUBLE, 0.5, "Maximum allowed tracking error left side"),
                input_port("max_error_right", DOUBLE, 0.5, "Maximum allowed tracking error right side"),
                input_port("max_error_heading", DOUBLE, 3.14, "Maximum allowed heading error (rad)"),
                input_port("tracking_feedback", TRACKING_FEEDBACK, description="Tracking feedback")]

    def tick(self) -> NodeStatus:
        fb = self.get_input("tracking_feedback", None)
        if fb is None:
            return SUCCESS
        err = fb.position_tracking_error
        if err >= 0.0:
            ok = err <= float(self.get_input("max_error_left", 0.5))
        else:
            ok = -err <= float(self.get_input("max_error_right", 0.5))
        ok = ok and abs(fb.heading_tracking_error) <= float(self.get_input("max_error_heading", 3.14))
        return _STATUS[ok]

