"""The goal hand-off between whoever sends goals (CLI, scenario runner, an operator) and a
tree that runs continuously: the sender writes ``{goal}`` and ``{goal_status} = 'PENDING'``;
the tree marks it ``ACTIVE``, then ``SUCCEEDED``, ``ABORTED`` or ``REFUSED``."""

from __future__ import annotations

import structlog

from bt_runtime import ConditionNode, ControlNode, NodeStatus, SyncActionNode
from bt_runtime.errors import BehaviorTreeException
from bt_runtime.node import NodeConfig, tick_child
from bt_runtime.ports import bidirectional_port, input_port, output_port
from bt_runtime.runtime.messages import Pose2D
from bt_runtime.runtime.supervisor import Health

from .types import ERROR_CODE, NAMES, POSE

log = structlog.get_logger("nodes.goals")
SUCCESS, FAILURE, RUNNING, SKIPPED = NodeStatus.SUCCESS, NodeStatus.FAILURE, NodeStatus.RUNNING, NodeStatus.SKIPPED
OPEN = ("PENDING", "ACTIVE")
ATTEMPT, RECOVER, WAIT = "attempt", "recover", "wait"


class GoalPending(ConditionNode):
    """SUCCESS while there is a goal to work on (status PENDING or ACTIVE)."""

    @classmethod
    def provided_ports(cls):
        return [input_port("status", str, "{goal_status}")]

    def tick(self):
        return SUCCESS if self.get_input("status", "") in OPEN else FAILURE


class SetGoalStatus(SyncActionNode):
    """Write the goal status; with ``only_if_open`` it only overwrites PENDING/ACTIVE (so an
    abort does not hide a refusal). A non-empty ``reason`` goes to ``{goal_reason}``."""

    @classmethod
    def provided_ports(cls):
        return [input_port("status", str, description="ACTIVE | SUCCEEDED | ABORTED | REFUSED"),
                input_port("only_if_open", bool, False),
                input_port("reason", str, "", "why (written to goal_reason when given)"),
                bidirectional_port("goal_status", str, "{goal_status}"),
                output_port("goal_reason", str, "{goal_reason}")]

    def tick(self):
        if self.get_input("only_if_open") and self.get_input("goal_status", "") not in OPEN:
            return SUCCESS
        self.set_output("goal_status", self.get_input("status"))
        reason = self.get_input("reason", "")
        if reason:
            self.set_output("goal_reason", reason)
        return SUCCESS


class RetryGoal(ControlNode):
    """Retries that follow health and time, not a burst (Nav2's RecoveryNode, with a clock).

    Two children: the attempt (plan and drive) and the recovery run between attempts (clear,
    spin, back up, wait). Before each attempt it waits until ``components`` are healthy and
    a back-off delay has passed (``backoff`` s after the first failure, doubling up to
    ``max_backoff``). It gives the goal up only when ``budget`` s have passed since the goal
    was first tried, writing why to ``reason``; or at once when the attempt itself closed the
    goal (``status`` no longer PENDING/ACTIVE, e.g. REFUSED). The budget belongs to the goal:
    a halt (a sensor outage holding the mission, the runtime restarting the tree after a tick
    error) resumes the same goal with the time it has left.
    """

    @classmethod
    def provided_ports(cls):
        return [input_port("goal", POSE, "{goal}", "the goal the budget belongs to"),
                input_port("budget", float, 120.0, "s from the first attempt before the goal is aborted"),
                input_port("components", NAMES, "", "components an attempt needs (';' separated)"),
                input_port("backoff", float, 0.5, "s to wait after the first failure (doubles)"),
                input_port("max_backoff", float, 4.0, "s, longest wait between attempts"),
                input_port("status", str, "{goal_status}"),
                input_port("error_code", ERROR_CODE, description="last Nav2 error code, for the reason"),
                output_port("reason", str, "{goal_reason}", "why the goal was aborted"),
                output_port("attempts", int, "{goal_attempts}")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._key: Pose2D | None = None
        self._started = 0.0
        self._attempts = 0
        self._phase = WAIT
        self._wait_until = 0.0
        self._delay = 0.0
        self._budget = 0.0
        self._needs: list[str] | None = None
        super().__init__(name, config)

    def _now(self) -> float:
        return self.config.clock()

    def _forget(self) -> None:
        self._key = None
        self._phase = WAIT

    def tick(self) -> NodeStatus:
        children = self.children
        if len(children) not in (1, 2):
            raise BehaviorTreeException(f"RetryGoal '{self.name}' needs 1 or 2 children (attempt, recovery)")
        now = self._now()
        goal = self.get_input("goal", None)
        if goal != self._key:  # a new goal: a new budget
            self._key, self._started, self._attempts = goal, now, 0
            self._budget = self.get_input("budget")
            self._phase, self._wait_until, self._delay = WAIT, now, self.get_input("backoff")
        budget = self._budget
        self.set_status(RUNNING)
        while True:
            if self._phase is ATTEMPT:
                status = tick_child(children[0])
                if status is RUNNING:
                    return RUNNING
                self.halt_child(0)
                if status is SUCCESS or status is SKIPPED:
                    self._forget()
                    return SUCCESS
                self._attempts += 1
                self.set_output("attempts", self._attempts)
                if self.get_input("status", "ACTIVE") not in OPEN:
                    self._forget()  # the attempt closed the goal itself (refused, aborted)
                    return FAILURE
                if now - self._started >= budget:
                    return self._give_up(now, budget)
                self._phase = RECOVER if len(children) == 2 else WAIT
                self._wait_until = now + self._delay
                self._delay = min(self._delay * 2.0, self.get_input("max_backoff"))
                continue
            if self._phase is RECOVER:
                status = tick_child(children[1])
                if status is RUNNING and now - self._started < budget:
                    return RUNNING
                self.halt_child(1)
                self._phase = WAIT
                continue
            # WAIT: for the back-off delay and the components the attempt needs
            if now - self._started >= budget:
                return self._give_up(now, budget)
            if now < self._wait_until or not self._healthy():
                return RUNNING
            self._phase = ATTEMPT

    def _healthy(self) -> bool:
        if self._needs is None:
            self._needs = list(self.get_input("components", []))
        sup = self.context.supervisor
        return all(sup.health(n) is Health.OK for n in self._needs)

    def _give_up(self, now: float, budget: float) -> NodeStatus:
        code = self.get_input("error_code", 0) or 0
        names = self.get_input("components", [])
        waiting = [n for n in names if self.context.supervisor.health(n) is not Health.OK]
        why = (f"time budget of {budget:g} s used up after {self._attempts} attempt(s)"
               + (f", last error code {code}" if code else "")
               + (f", still waiting for {', '.join(waiting)}" if waiting else ""))
        self.set_output("reason", why)
        log.warning("goal_given_up", goal=str(self._key), reason=why, sim_time=round(now, 3))
        self.reset_children()
        self._forget()
        return FAILURE

    def halt(self) -> None:
        # the goal keeps its budget and attempt count; the next tick starts with a health check
        self.reset_children()
        self.reset_status()
        self._phase = WAIT
