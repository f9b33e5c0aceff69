"""The goal hand-off between whoever sends goals (CLI, scenario runner, an operator) and a
tree that runs continuously: the sender writes ``{goal}`` and ``{goal_status} = 'PENDING'``;
the tree marks it ``ACTIVE``, then ``SUCCEEDED``, ``ABORTED`` or ``REFUSED``."""

from __future__ import annotations

from bt_runtime import ConditionNode, NodeStatus, SyncActionNode
from bt_runtime.ports import bidirectional_port, input_port

SUCCESS, FAILURE = NodeStatus.SUCCESS, NodeStatus.FAILURE
OPEN = ("PENDING", "ACTIVE")


class GoalPending(ConditionNode):
    """SUCCESS while there is a goal to work on (status PENDING or ACTIVE)."""

    @classmethod
    def provided_ports(cls):
        return [input_port("status", str, "{goal_status}")]

    def tick(self):
        return SUCCESS if self.get_input("status", "") in OPEN else FAILURE


class SetGoalStatus(SyncActionNode):
    """Write the goal status; with ``only_if_open`` it only overwrites PENDING/ACTIVE (so an
    abort does not hide a refusal)."""

    @classmethod
    def provided_ports(cls):
        return [input_port("status", str, description="ACTIVE | SUCCEEDED | ABORTED | REFUSED"),
                input_port("only_if_open", bool, False),
                bidirectional_port("goal_status", str, "{goal_status}")]

    def tick(self):
        if self.get_input("only_if_open") and self.get_input("goal_status", "") not in OPEN:
            return SUCCESS
        self.set_output("goal_status", self.get_input("status"))
        return SUCCESS
