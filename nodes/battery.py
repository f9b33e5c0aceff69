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


def path_turning(points, start_yaw: float) -> float:
    """Total heading change along a polyline (rad), starting from ``start_yaw``."""
    total, yaw = 0.0, start_yaw
    for (x0, y0), (x1, y1) in zip(points[:-1, :2], points[1:, :2]):
        if x0 == x1 and y0 == y1:
            continue
        heading = math.atan2(y1 - y0, x1 - x0)
        total += abs(wrap_angle(heading - yaw))
        yaw = heading
    return total


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

    def tick(self):
        ctx = self.context
        battery = ctx.backup.latest("battery")
        pose = robot_pose(self)
        if not isinstance(battery, BatteryState) or pose is None or not math.isfinite(battery.percentage):
            return FAILURE  # unknown charge or position: cannot promise anything
        goal: Pose2D = self.get_input("goal")
        path: Path | None = self.get_input("path", None)
        robot = ctx.robot
        speed = self.get_input("speed") or min(robot.max_linear, 0.25)
        if path is not None and len(path) >= 2:
            length, turning = path.length, path_turning(path.points, pose.yaw)
        else:
            length = pose.distance_to(goal) * self.get_input("detour_factor")
            turning = math.pi
        turn_rate = min(robot.max_angular, 1.0)
        energy = energy_for_path(length, turning, speed, turn_rate, robot)
        dock = self.get_input("dock", None)
        energy += return_energy(goal, dock if isinstance(dock, Pose2D) else None, self.get_input("detour_factor"),
                                speed, turn_rate, robot)
        if self._model is not None:
            energy = self._model.energy(energy)
            self.set_output("energy_factor", self._model.factor)
        voltage = battery.voltage if battery.voltage > 0 else None
        required = robot.percent_for(energy, voltage) * self.get_input("safety_factor") + self.get_input("reserve")
        self.set_output("required", required)
        self.set_output("available", float(battery.percentage))
        return SUCCESS if battery.percentage >= required else FAILURE


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
