"""Health behaviours (fn_req1-5): ask the supervisor, restart components, slow down, stop.

Every query goes to the runtime's supervisor through ``node.context`` and never blocks:
restarts run in the background (``RequestRestarts``) or as an async action
(``RestartComponent``), so the tree keeps ticking while a driver comes back.
"""

from __future__ import annotations

import asyncio

from bt_runtime import AsyncActionNode, ConditionNode, NodeStatus, StatefulActionNode, SyncActionNode
from bt_runtime.node import NodeConfig
from bt_runtime.ports import blackboard_key, input_port, output_port
from bt_runtime.runtime.supervisor import Health

from .types import ERROR_CODE, NAMES

SUCCESS, FAILURE, RUNNING = NodeStatus.SUCCESS, NodeStatus.FAILURE, NodeStatus.RUNNING


def _listed(node, port: str = "components") -> list[str] | None:
    """The port's names (None when empty: every component), read once when the XML gives them
    literally (they cannot change then; a condition asked on every tick stays cheap), else on
    every call from the blackboard."""
    cached = node.__dict__.get("_listed_cache", _UNREAD)
    if cached is not _UNREAD:
        return cached
    names = node.get_input(port, [])
    value = list(names) if names else None
    raw = node.config.input_ports.get(port)
    if not isinstance(raw, str) or blackboard_key(raw, port) is None:
        node._listed_cache = value
    return value


_UNREAD = object()


def _names(node, port: str = "components") -> list[str]:
    """The listed components, or every watched component when the port is empty."""
    names = node.get_input(port, [])
    sup = node.context.supervisor
    return list(names) if names else [n for n in sup.components if n != "tree"]


class ComponentHealthy(ConditionNode):
    """SUCCESS if the supervisor reports ``component`` OK (silent > timeout reads as failed)."""

    @classmethod
    def provided_ports(cls):
        return [input_port("component", str, description="component name, e.g. lidar")]

    def tick(self):
        return SUCCESS if self.context.supervisor.is_healthy(self.get_input("component")) else FAILURE


class ComponentsHealthy(ConditionNode):
    """SUCCESS only if every listed component (all watched ones when empty) is OK; the others
    (failed, restarting, dead, or not heard from yet: UNKNOWN is not OK) are written to
    ``unhealthy``. Restarting is ``RequestRestarts``' job: it leaves a merely silent-at-start
    component alone."""

    @classmethod
    def provided_ports(cls):
        return [input_port("components", NAMES, "", "names separated by ';' (empty: all)"),
                output_port("unhealthy", NAMES, "{unhealthy}", "the components that are not OK")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._written: list[str] | None = None
        super().__init__(name, config)

    def tick(self):
        bad = self.context.supervisor.not_ok_among(_listed(self))
        if bad != self._written:  # writing an unchanged list every tick costs more than the check
            self._written = bad
            self.set_output("unhealthy", bad)
        return FAILURE if bad else SUCCESS


class AnyComponentDead(ConditionNode):
    """SUCCESS if a listed component is DEAD (its restarts failed); names go to ``dead``."""

    @classmethod
    def provided_ports(cls):
        return [input_port("components", NAMES, "", "names separated by ';' (empty: all)"),
                output_port("dead", NAMES, "{dead_components}")]

    def tick(self):
        sup = self.context.supervisor
        dead = [n for n in _names(self) if sup.health(n) is Health.DEAD]
        self.set_output("dead", dead)
        return SUCCESS if dead else FAILURE


class RequestRestarts(SyncActionNode):
    """Ask the supervisor to restart every failed, restartable component (non-blocking; a
    restart already under way is joined, not repeated; a component whose dependency is down
    waits for that one). SUCCESS; ``restarting`` lists what is being restarted."""

    @classmethod
    def provided_ports(cls):
        return [input_port("components", NAMES, "", "names separated by ';' (empty: all)"),
                output_port("restarting", NAMES, "{restarting}")]

    def tick(self):
        sup = self.context.supervisor
        restarting = []
        for name in _names(self):
            health = sup.health(name)
            if health is Health.RESTARTING or sup.restarting(name):
                restarting.append(name)  # already under way: join it
            elif health is Health.FAILED and not sup.failed_dependencies(name):
                if sup.request_restart(name) is not None:
                    restarting.append(name)
        self.set_output("restarting", restarting)
        return SUCCESS


class RestartComponent(AsyncActionNode):
    """Restart ``component`` and wait until its data flows again: SUCCESS, or FAILURE if the
    restart failed (after two failures the supervisor declares it dead). A restart already
    under way (e.g. asked for by ``RequestRestarts``) is joined, not repeated."""

    @classmethod
    def provided_ports(cls):
        return [input_port("component", str)]

    async def run(self):
        return SUCCESS if await restart_and_wait(self.context.supervisor, self.get_input("component")) else FAILURE


async def restart_and_wait(sup, name: str) -> bool:
    """Restart ``name`` through the supervisor's restart policy (joining one under way)."""
    task = sup.request_restart(name)
    if task is None:
        return sup.health(name) is Health.OK
    return bool(await asyncio.shield(task))


class RestartServerAfterError(AsyncActionNode):
    """Restart the navigation server a Nav2 error code blames, when a restart can cure it (a
    server that is down, timed out, or fails every request): 100/106/107 -> controller_server,
    200/207/208 -> planner_server, 700/701 -> behavior_server. SUCCESS when restarted or when
    the code blames no server; FAILURE if the restart failed."""

    BLAME = {100: "controller_server", 106: "controller_server", 107: "controller_server",
             200: "planner_server", 207: "planner_server", 208: "planner_server",
             700: "behavior_server", 701: "behavior_server"}

    @classmethod
    def provided_ports(cls):
        return [input_port("error_code", ERROR_CODE, description="a Nav2 error code, e.g. {nav_error}")]

    async def run(self):
        code = self.get_input("error_code", 0) or 0
        server = self.BLAME.get(int(code))
        if server is None or server not in self.context.supervisor.components:
            return SUCCESS
        return SUCCESS if await restart_and_wait(self.context.supervisor, server) else FAILURE


class WaitForHealthy(StatefulActionNode):
    """RUNNING until the listed components are OK; FAILURE after ``timeout`` s (0: never) or if
    one is DEAD. A component not heard from yet (UNKNOWN) is not OK: a goal waits for
    localization and the planner to report instead of failing (and restarting the planner) at
    start-up."""

    @classmethod
    def provided_ports(cls):
        return [input_port("components", NAMES, "", "names separated by ';' (empty: all)"),
                input_port("timeout", float, 15.0, "seconds")]

    def on_start(self):
        timeout = self.get_input("timeout")
        self._deadline = self.context.clock() + timeout if timeout > 0 else float("inf")
        return self.on_running()

    def on_running(self):
        sup = self.context.supervisor
        states = [sup.health(n) for n in _names(self)]
        if all(s is Health.OK for s in states):
            return SUCCESS
        if any(s is Health.DEAD for s in states) or self.context.clock() > self._deadline:
            return FAILURE
        return RUNNING


class SetSpeedLimit(SyncActionNode):
    """Cap the robot's speed in the decision gate (and navigation), e.g. while a sensor is down."""

    @classmethod
    def provided_ports(cls):
        return [input_port("linear", float, 0.1, "m/s"), input_port("angular", float, 0.5, "rad/s"),
                input_port("reason", str, "degraded")]

    def tick(self):
        gate = self.context.gate
        limit = (abs(self.get_input("linear")), abs(self.get_input("angular")))
        if gate.speed_limit != limit:
            gate.set_speed_limit(*limit, reason=self.get_input("reason"))
        return SUCCESS


class RestoreSpeedLimit(SyncActionNode):
    """Lift the speed cap (no-op when none is set)."""

    def tick(self):
        if self.context.gate.speed_limit is not None:
            self.context.gate.set_speed_limit(None)
        return SUCCESS


class EmergencyStop(SyncActionNode):
    """Stop the robot through the gate (overrides every command) until released."""

    @classmethod
    def provided_ports(cls):
        return [input_port("reason", str, "behavior tree")]

    def tick(self):
        self.context.gate.emergency_stop(self.get_input("reason"))
        return SUCCESS


class ReleaseEmergencyStop(SyncActionNode):
    @classmethod
    def provided_ports(cls):
        return [input_port("reason", str, "behavior tree")]

    def tick(self):
        self.context.gate.release(self.get_input("reason"))
        return SUCCESS


class IsSafeToContinue(ConditionNode):
    """fn_req2: FAILURE when continuing is not safe: a listed component is dead, or an
    emergency stop is active."""

    @classmethod
    def provided_ports(cls):
        return [input_port("components", NAMES, "", "critical components (empty: all)")]

    def tick(self):
        ctx = self.context
        if ctx.gate.estop_active:
            return FAILURE
        return FAILURE if ctx.supervisor.any_dead(_listed(self)) else SUCCESS
