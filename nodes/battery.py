"""Battery behaviours (fn_req9): will the robot reach this goal and keep a reserve?

Energy follows the paper's linear power model (idle + driving terms) over the time needed to
drive the planned path (or the straight line times a detour factor when no path is known),
with a safety factor for stops and detours. The model starts from the nominal constants the
driver gives (``context.robot``) and is corrected online from the measured state of charge
(``nodes.energy``), with an uncertainty margin; it never sees the simulator's constants.
"""

from __future__ import annotations

import math

from bt_runtime import ConditionNode, NodeStatus, SyncActionNode
from bt_runtime.ports import input_port, output_port
from bt_runtime.runtime.messages import BatteryState, Path, Pose2D, wrap_angle

from .energy import energy_model
from .robot import robot_pose
from .types import PATH, POSE

SUCCESS, FAILURE = NodeStatus.SUCCESS, NodeStatus.FAILURE


def energy_for_path(length_m: float, turn_rad: float, speed: float, turn_rate: float, robot) -> float:
    """Wh to drive ``length_m`` at ``speed`` and turn ``turn_rad`` at ``turn_rate``."""
    drive_time = length_m / max(speed, 1e-3)
    turn_time = turn_rad / max(turn_rate, 1e-3)
    return (robot.power(speed, 0.0) * drive_time + robot.power(0.0, turn_rate) * turn_time) / 3600.0


def path_turning_parts(points) -> tuple[float | None, float]:
    """(heading of the first leg, heading change along the rest) of a polyline; (None, 0) if it
    has no leg. The second part depends on the path alone, so it is computed once per path."""
    first, rest, prev = None, 0.0, 0.0
    for (x0, y0), (x1, y1) in zip(points[:-1, :2], points[1:, :2]):
        if x0 == x1 and y0 == y1:
            continue
        heading = math.atan2(y1 - y0, x1 - x0)
        if first is None:
            first = heading
        else:
            rest += abs(wrap_angle(heading - prev))
        prev = heading
    return first, rest


def path_turning(points, start_yaw: float) -> float:
    """Total heading change along a polyline (rad), starting from ``start_yaw``."""
    first, rest = path_turning_parts(points)
    return 0.0 if first is None else abs(wrap_angle(first - start_yaw)) + rest


def return_energy(goal: Pose2D, dock: Pose2D | None, detour_factor: float, speed: float, turn_rate: float,
                  robot) -> float:
    """Wh (nominal) to get from ``goal`` back to ``dock``: the straight line times the detour
    factor and a half turn, as for a goal with no plan (the way back is not planned yet);
    0 without a dock."""
    if dock is None:
        return 0.0
    return energy_for_path(goal.distance_to(dock) * detour_factor, math.pi, speed, turn_rate, robot)


class BatteryCanReach(ConditionNode):
    """SUCCESS if the state of charge covers the energy to reach ``goal`` (along ``path`` if
    given) and then get back to ``dock`` (when the robot has one: a robot must never be left
    where it cannot reach its charger), times the learned factor and ``safety_factor``, plus
    ``reserve`` percent. Writes the estimate."""

    @classmethod
    def provided_ports(cls):
        return [input_port("goal", POSE, "{goal}"),
                input_port("path", PATH, description="planned path (optional; else straight line x detour)"),
                input_port("reserve", float, 10.0, "percent to keep"),
                input_port("safety_factor", float, 1.5),
                input_port("detour_factor", float, 1.5, "used without a path"),
                input_port("speed", float, 0.0, "m/s (0: the robot's nominal speed)"),
                input_port("dock", POSE, "{dock_pose}",
                           "the dock to get back to after the goal (none: no return trip counted)"),
                output_port("required", float, "{battery_required}", "percent needed incl. reserve"),
                output_port("available", float, "{battery_available}", "percent now"),
                output_port("energy_factor", float, "{battery_energy_factor}",
                            "learned consumption / nominal, with the margin")]

    def __init__(self, name, config=None):
        super().__init__(name, config)
        self._model = energy_model(self.context)  # starts learning now, not at the first goal
        # ChargeUntil ticks this at 100 Hz while the battery reports at 1 Hz and the pose at
        # 10 Hz: the estimate is recomputed only when one of its inputs is a new object
        self._inputs: tuple = ()
        self._required = 0.0
        self._path: tuple = (None, 0.0, None, 0.0)  # (path, length, first heading, rest of the turning)

    def tick(self):
        ctx = self.context
        battery = ctx.backup.latest("battery")
        pose = robot_pose(self)
        if not isinstance(battery, BatteryState) or pose is None or not math.isfinite(battery.percentage):
            return FAILURE  # unknown charge or position: cannot promise anything
        goal: Pose2D = self.get_input("goal")
        path: Path | None = self.get_input("path", None)
        dock = self.get_input("dock", None)
        model = self._model
        inputs = (battery, pose, goal, path, dock, model.readings if model is not None else 0)
        cached = self._inputs
        if len(cached) == len(inputs) and all(a is b for a, b in zip(cached, inputs)):
            required = self._required
        else:
            required = self._estimate(battery, pose, goal, path, dock if isinstance(dock, Pose2D) else None)
            self._inputs, self._required = inputs, required
        if model is not None:
            self.set_output("energy_factor", model.factor)
        self.set_output("required", required)
        self.set_output("available", float(battery.percentage))
        return SUCCESS if battery.percentage >= required else FAILURE

    def _estimate(self, battery: BatteryState, pose: Pose2D, goal: Pose2D, path: Path | None,
                  dock: Pose2D | None) -> float:
        """Percent needed: the trip and the way back to the dock, learned factor, safety factor, reserve."""
        robot = self.context.robot
        speed = self.get_input("speed") or min(robot.max_linear, 0.25)
        if path is not None and len(path) >= 2:
            if self._path[0] is not path:  # a new plan: its length and turns, once
                self._path = (path, path.length, *path_turning_parts(path.points))
            _, length, first, rest = self._path
            turning = 0.0 if first is None else abs(wrap_angle(first - pose.yaw)) + rest
        else:
            length = pose.distance_to(goal) * self.get_input("detour_factor")
            turning = math.pi
        turn_rate = min(robot.max_angular, 1.0)
        energy = energy_for_path(length, turning, speed, turn_rate, robot)
        energy += return_energy(goal, dock, self.get_input("detour_factor"), speed, turn_rate, robot)
        if self._model is not None:
            energy = self._model.energy(energy)
        voltage = battery.voltage if battery.voltage > 0 else None
        return robot.percent_for(energy, voltage) * self.get_input("safety_factor") + self.get_input("reserve")


class BatteryAbove(ConditionNode):
    """SUCCESS if the state of charge is above ``percent``."""

    @classmethod
    def provided_ports(cls):
        return [input_port("percent", float, 20.0)]

    def tick(self):
        battery = self.context.backup.latest("battery")
        ok = isinstance(battery, BatteryState) and battery.percentage > self.get_input("percent")
        return SUCCESS if ok else FAILURE


class RefuseGoal(SyncActionNode):
    """Refuse the current goal: writes ``REFUSED`` to the goal status and logs why."""

    @classmethod
    def provided_ports(cls):
        return [input_port("goal", POSE, "{goal}"), input_port("reason", str, "out of range"),
                output_port("status", str, "{goal_status}")]

    def tick(self):
        import structlog

        goal = self.get_input("goal", None)
        structlog.get_logger("nodes.battery").warning(
            "goal_refused", goal=None if goal is None else goal.to_string(), reason=self.get_input("reason"),
            sim_time=round(self.context.clock(), 3))
        self.set_output("status", "REFUSED")
        return SUCCESS
