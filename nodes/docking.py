"""Charging on the dock: ``ChargeUntil`` waits while the battery charges, until its child
condition holds (typically ``BatteryCanReach`` for the goal the robot was refused).

The robot learns that it charges only from its battery messages (``power_supply_status``
CHARGING or FULL), never from the simulator: when the monitor has not reported a charger for
``timeout`` seconds (contacts lost, charger off) the node fails, so the tree can give up or
dock again instead of waiting forever.
"""

from __future__ import annotations

import structlog

from bt_runtime import ConditionNode
from bt_runtime.node import DecoratorNode, NodeConfig
from bt_runtime.ports import DOUBLE, STRING, input_port
from bt_runtime.runtime.messages import BatteryState
from bt_runtime.status import FAILURE, IDLE, RUNNING, SKIPPED, SUCCESS, NodeStatus

from .robot import latest

log = structlog.get_logger("nodes.docking")


class GoalStatusIs(ConditionNode):
    """SUCCESS if the goal status is ``value`` (e.g. CHARGING: a goal kept while the robot
    charges); FAILURE otherwise, also before any goal was sent (no entry yet)."""

    @classmethod
    def provided_ports(cls):
        return [input_port("value", STRING, description="the status to test for"),
                input_port("status", STRING, "{goal_status}")]

    def tick(self) -> NodeStatus:
        return SUCCESS if self.get_input("status", "") == self.get_input("value", "") else FAILURE


class WhileGoalStatusIs(DecoratorNode):
    """Ticks its child while the goal status is ``value``; SKIPPED otherwise, without ticking it
    (a child still running is halted first, as BT.CPP's ``_while`` does). A branch that applies
    to one goal state (charging) then costs one blackboard read on every other tick, and no
    status changes; unlike a ``_while`` script it also works before any goal status exists."""

    @classmethod
    def provided_ports(cls):
        return [input_port("value", STRING, description="the status the child runs in"),
                input_port("status", STRING, "{goal_status}")]

    def tick(self) -> NodeStatus:
        if self.get_input("status", "") != self.get_input("value", ""):
            if self._status is RUNNING:
                self.halt()
            return SKIPPED
        self.set_status(RUNNING)
        return self.child.execute_tick()


class OnCharger(ConditionNode):
    """SUCCESS if the last battery message says a charger is connected: CHARGING, or FULL on the
    charger. Nav2's ``IsBatteryCharging`` tests CHARGING only, so a robot left full on its dock
    would drive off without undocking."""

    def tick(self) -> NodeStatus:
        msg = latest(self, "battery")
        return SUCCESS if isinstance(msg, BatteryState) and msg.on_charger else FAILURE


class ChargeUntil(DecoratorNode):
    """RUNNING while the robot charges; SUCCESS once the child (a condition, ticked every tick)
    succeeds or the state of charge reaches ``full`` percent; FAILURE when the battery monitor
    has not reported a charger for ``timeout`` s."""

    @classmethod
    def provided_ports(cls):
        return [input_port("full", DOUBLE, 99.0, "percent at which charging stops whatever the child says"),
                input_port("timeout", DOUBLE, 10.0, "s without the battery reporting a charger before failing")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._charger_seen = 0.0
        self._started = 0.0
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        now = self.config.clock()
        if self._status is IDLE:
            self._started = self._charger_seen = now
        self.set_status(RUNNING)
        msg = latest(self, "battery")
        battery = msg if isinstance(msg, BatteryState) else None
        if battery is not None and battery.on_charger:
            self._charger_seen = now
        status = self.child.execute_tick()
        self.reset_child()
        full = float(self.get_input("full", 99.0))
        if status is SUCCESS or (battery is not None and battery.percentage >= full):
            log.info("charged", percent=None if battery is None else round(battery.percentage, 1),
                     seconds=round(now - self._started, 1), sim_time=round(now, 3))
            return SUCCESS
        if now - self._charger_seen > float(self.get_input("timeout", 10.0)):
            log.warning("charging_lost", seconds_without_charger=round(now - self._charger_seen, 1),
                        sim_time=round(now, 3))
            return FAILURE
        return RUNNING
