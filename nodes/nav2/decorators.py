"""Nav2's decorators (nav2_behavior_tree/plugins/decorator): rate, distance, speed and goal
gated re-ticking, goal updates, patience on approach, single trigger.

Time is the tree's clock (``config.clock()``: the event loop's, virtual in simulation), never
the wall clock (Nav2's RateController uses ``high_resolution_clock``).
"""

from __future__ import annotations

import math
from typing import Any

from bt_runtime.errors import BehaviorTreeException
from bt_runtime.node import DecoratorNode, NodeConfig
from bt_runtime.ports import DOUBLE, STRING, input_port, output_port
from bt_runtime.status import FAILURE, IDLE, RUNNING, SKIPPED, SUCCESS, NodeStatus

from ..robot import robot_pose
from ..types import GOALS, PATH, POSE
from .common import input_or_blackboard, nav2_topics, path_length, points_of, remember_goals


def _tick_child(node: DecoratorNode) -> NodeStatus:
    return node.child.execute_tick()


class RateController(DecoratorNode):
    """Ticks its child at most ``hz`` times per second.

    The child runs on the first tick of an activation, then again once ``1/hz`` s have passed
    since it last succeeded, and on every tick while it is RUNNING. In between the node
    returns RUNNING without ticking the child (a PipelineSequence passes over it).
    """

    @classmethod
    def provided_ports(cls):
        return [input_port("hz", DOUBLE, 10.0, "Rate")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.period = 0.1
        self.start = 0.0
        self.first_time = False
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        clock = self.config.clock
        if self._status is IDLE:
            hz = float(self.get_input("hz", 1.0))
            self.period = 1.0 / hz if hz > 0 else math.inf
            self.start = clock()
            self.first_time = True
        self.set_status(RUNNING)
        elapsed = clock() - self.start
        if self.first_time or self.child._status is RUNNING or elapsed >= self.period:
            self.first_time = False
            status = _tick_child(self)
            if status is SUCCESS:
                self.start = clock()
                return SUCCESS
            if status in (SKIPPED, RUNNING, FAILURE):
                return status
            return FAILURE
        return self._status


class DistanceController(DecoratorNode):
    """Ticks its child each time the robot has moved ``distance`` m (straight line) since the
    child last succeeded (and on the first tick, and while the child is RUNNING). FAILURE if
    the robot pose is not available."""

    @classmethod
    def provided_ports(cls):
        return [input_port("distance", DOUBLE, 1.0, "Distance"),
                input_port("global_frame", STRING, description="Global frame"),
                input_port("robot_base_frame", STRING, description="Robot base frame")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.start_pose = None
        self.first_time = False
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        if self._status is IDLE:
            self.start_pose = robot_pose(self)
            if self.start_pose is None:
                return FAILURE
            self.first_time = True
        self.set_status(RUNNING)
        current = robot_pose(self)
        if current is None:
            return FAILURE
        travelled = self.start_pose.distance_to(current)
        distance = float(self.get_input("distance", 1.0))
        if self.first_time or self.child._status is RUNNING or travelled >= distance:
            self.first_time = False
            status = _tick_child(self)
            if status is SKIPPED or status is RUNNING:
                return status
            if status is SUCCESS:
                pose = robot_pose(self)
                if pose is None:
                    return FAILURE
                self.start_pose = pose
                return SUCCESS
            return FAILURE
        return self._status


class SpeedController(DecoratorNode):
    """Ticks its child at a rate that scales with the robot's speed: from ``min_rate`` at
    ``min_speed`` to ``max_rate`` at ``max_speed`` (clamped). Speed is the odometry twist
    averaged over the last 0.3 s (Nav2's OdomSmoother ``filter_duration``). A new goal (or
    goals) resets the period to ``1/max_rate`` and ticks the child at once."""

    FILTER_DURATION = 0.3

    @classmethod
    def provided_ports(cls):
        return [input_port("min_rate", DOUBLE, 0.1, "Minimum rate"),
                input_port("max_rate", DOUBLE, 1.0, "Maximum rate"),
                input_port("min_speed", DOUBLE, 0.0, "Minimum speed"),
                input_port("max_speed", DOUBLE, 0.5, "Maximum speed"),
                input_port("goal", POSE, description="Destination"),
                input_port("goals", GOALS, description="Destinations")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        super().__init__(name, config)
        self.min_rate = float(self.get_input("min_rate", 0.1))
        self.max_rate = float(self.get_input("max_rate", 1.0))
        self.min_speed = float(self.get_input("min_speed", 0.0))
        self.max_speed = float(self.get_input("max_speed", 0.5))
        if self.min_rate <= 0.0 or self.max_rate <= 0.0:
            raise BehaviorTreeException("SpeedController node cannot have rate <= 0.0")
        self.d_rate = self.max_rate - self.min_rate
        self.d_speed = self.max_speed - self.min_speed
        self.period = 1.0 / self.max_rate
        self.start = 0.0
        self.first_tick = False
        self.goal: Any = None
        self.goals: Any = None

    def speed(self) -> float:
        ctx = self.context
        backup = getattr(ctx, "backup", None) if ctx is not None else None
        if backup is None:
            return 0.0
        now = self.config.clock()
        msgs = backup.since("odom", now - self.FILTER_DURATION) if hasattr(backup, "since") else []
        if not msgs:
            msg = backup.latest("odom")
            msgs = [msg] if msg is not None else []
        if not msgs:
            return 0.0
        v = sum(m.twist.linear for m in msgs) / len(msgs)
        return abs(v)

    def scaled_rate(self, speed: float) -> float:
        if self.d_speed == 0:
            return self.max_rate
        rate = (speed - self.min_speed) / self.d_speed * self.d_rate + self.min_rate
        return max(min(rate, self.max_rate), self.min_rate)

    def tick(self) -> NodeStatus:
        clock = self.config.clock
        if self._status is IDLE:
            self.goals = input_or_blackboard(self, "goals")
            self.goal = input_or_blackboard(self, "goal")
            self.period = 1.0 / self.max_rate
            self.start = clock()
            self.first_tick = True
        goals = input_or_blackboard(self, "goals")
        goal = input_or_blackboard(self, "goal")
        if goal != self.goal or goals != self.goals:
            self.period = 1.0 / self.max_rate
            self.start = clock()
            self.first_tick = True
            self.goal, self.goals = goal, goals
        self.set_status(RUNNING)
        elapsed = clock() - self.start
        if self.first_tick or self.child._status is RUNNING or elapsed >= self.period:
            self.first_tick = False
            if elapsed >= self.period:
                self.period = 1.0 / self.scaled_rate(self.speed())
                self.start = clock()
            return _tick_child(self)
        return self._status


class GoalUpdatedController(DecoratorNode):
    """Ticks its child only when the goal (or goals) changed, on the first tick of an
    activation, and while the child is RUNNING; otherwise RUNNING."""

    @classmethod
    def provided_ports(cls):
        return [input_port("goal", POSE, description="Destination"),
                input_port("goals", GOALS, description="Destinations")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.goal: Any = None
        self.goals: Any = None
        self.goal_was_updated = False
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        if self._status is IDLE:
            remember_goals(self)
            self.goal_was_updated = True
        self.set_status(RUNNING)
        if remember_goals(self):
            self.goal_was_updated = True
        if self.child._status is RUNNING or self.goal_was_updated:
            self.goal_was_updated = False
            return _tick_child(self)
        return self._status


class GoalUpdater(DecoratorNode):
    """Outputs the goal to use, then ticks its child: the latest pose published on the
    ``goal_update`` "topic" if it is newer than the input goal, else the input goal.

    Publish updates with ``nodes.nav2.common.publish_stamped(context, "goal_update", pose)``
    (a ``(stamp, pose)`` pair on the tree clock; ``goals_update`` for ``input_goals``). Nav2
    compares message stamps and ignores zero stamps; our input goal carries no stamp, so an
    update counts as newer when it was published after this node first saw the current input
    goal value.
    """

    @classmethod
    def provided_ports(cls):
        return [input_port("input_goal", POSE, description="Original goal in"),
                input_port("input_goals", GOALS, description="Original goals in"),
                output_port("output_goal", POSE, description="Received goal by subscription"),
                output_port("output_goals", GOALS, description="Received goals by subscription")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._goal_seen: tuple[Any, float] | None = None
        self._goals_seen: tuple[Any, float] | None = None
        super().__init__(name, config)

    def _stamp_of(self, value: Any, seen: tuple[Any, float] | None) -> tuple[Any, float]:
        if seen is not None and seen[0] == value:
            return seen
        return (value, self.config.clock())

    @staticmethod
    def _update(topics: dict, topic: str) -> tuple[float, Any] | None:
        msg = topics.get(topic)
        if isinstance(msg, tuple) and len(msg) == 2 and isinstance(msg[0], (int, float)) and msg[0] != 0:
            return float(msg[0]), msg[1]
        return None

    def tick(self) -> NodeStatus:
        topics = nav2_topics(self.context)
        if "input_goal" in self.config.input_ports:
            goal = self.get_input("input_goal", None)
            self._goal_seen = self._stamp_of(goal, self._goal_seen)
            upd = self._update(topics, "goal_update")
            if upd is not None and upd[0] > self._goal_seen[1]:
                goal = upd[1]
            if "output_goal" in self.config.output_ports and goal is not None:
                self.set_output("output_goal", goal)
        if "input_goals" in self.config.input_ports:
            goals = self.get_input("input_goals", None)
            self._goals_seen = self._stamp_of(goals, self._goals_seen)
            upd = self._update(topics, "goals_update")
            if upd is not None and upd[0] > self._goals_seen[1]:
                goals = list(upd[1])
            if "output_goals" in self.config.output_ports and goals is not None:
                self.set_output("output_goals", goals)
        return _tick_child(self)


class PathLongerOnApproach(DecoratorNode):
    """Ticks its child (e.g. cancel control and wait) only when, close to the goal, a new path
    to the same goal is much longer than the old one: the path was just updated, the old path
    was shorter than ``prox_len`` and the new one is longer than ``length_factor`` times the
    old. Otherwise SUCCESS without ticking the child."""

    @classmethod
    def provided_ports(cls):
        return [input_port("path", PATH, description="Planned Path"),
                input_port("prox_len", DOUBLE, 3.0,
                           "Proximity length (m) for the path to be longer on approach"),
                input_port("length_factor", DOUBLE, 2.0,
                           "Length multiplication factor to check if the path is significantly longer")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.old_path: Any = None
        self.new_path: Any = None
        self.first_time = True
        super().__init__(name, config)

    @staticmethod
    def _last(path: Any):
        pts = points_of(path)
        return tuple(pts[-1]) if len(pts) else None

    def _is_path_updated(self) -> bool:
        old, new = points_of(self.old_path), points_of(self.new_path)
        return (len(old) != 0 and len(new) != 0 and len(new) != len(old)
                and tuple(old[-1, :2]) == tuple(new[-1, :2]))

    def tick(self) -> NodeStatus:
        self.new_path = self.get_input("path", None)
        prox_len = float(self.get_input("prox_len", 3.0))
        length_factor = float(self.get_input("length_factor", 2.0))
        if not self.first_time:
            old_last, new_last = self._last(self.old_path), self._last(self.new_path)
            if old_last is None or new_last is None or old_last != new_last:
                self.first_time = True
        self.set_status(RUNNING)
        if (self._is_path_updated() and path_length(self.old_path) < prox_len
                and path_length(self.new_path) > length_factor * path_length(self.old_path)
                and not self.first_time):
            status = _tick_child(self)
            if status is SKIPPED or status is RUNNING:
                return status
            self.old_path = self.new_path
            self.reset_child()
            return status if status in (SUCCESS, FAILURE) else FAILURE
        self.old_path = self.new_path
        self.first_time = False
        return SUCCESS


class SingleTrigger(DecoratorNode):
    """Ticks its child once per activation (until the child finishes); afterwards FAILURE."""

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.first_time = True
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        if self._status is IDLE:
            self.first_time = True
        self.set_status(RUNNING)
        if self.first_time:
            status = _tick_child(self)
            if status is SKIPPED or status is RUNNING:
                return status
            self.first_time = False
            return status if status in (SUCCESS, FAILURE) else FAILURE
        return FAILURE
