"""Nav2's control nodes: PipelineSequence, RecoveryNode, RoundRobin (nav2_behavior_tree/plugins/control)."""

from __future__ import annotations

from bt_runtime.errors import BehaviorTreeException, LogicError
from bt_runtime.node import ControlNode, NodeConfig, tick_child
from bt_runtime.ports import BOOL, INT, input_port
from bt_runtime.status import FAILURE, IDLE, RUNNING, SKIPPED, SUCCESS, NodeStatus


class PipelineSequence(ControlNode):
    """Ticks *every* child from the first on each tick, like a pipeline of stages.

    A child FAILURE halts all children and fails. A RUNNING child stops the sweep only if it is
    the furthest child reached so far; an earlier child that returns RUNNING (a RateController
    between its windows) is passed over, so earlier stages keep being re-run while a later one
    (FollowPath) runs: this is how Nav2 replans while following. SUCCESS when the last child
    succeeds (then all children are halted); SKIPPED if every child skipped.
    """

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.last_child_ticked = 0
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        skipped = 0
        children = self.children
        for i, child in enumerate(children):
            status = tick_child(child)
            if status is FAILURE:
                self.reset_children()
                self.last_child_ticked = 0
                return FAILURE
            if status is SKIPPED:
                skipped += 1
            elif status is RUNNING:
                if i >= self.last_child_ticked:
                    self.last_child_ticked = i
                    return RUNNING
            elif status is not SUCCESS:
                raise LogicError(f"Invalid node status. Received status {status.name} from child {child.name}")
        self.reset_children()
        self.last_child_ticked = 0
        return SKIPPED if skipped == len(children) else SUCCESS

    def halt(self) -> None:
        ControlNode.halt(self)
        self.last_child_ticked = 0


class RecoveryNode(ControlNode):
    """Exactly two children: the action, and the recovery that makes it worth retrying.

    Child 0 SUCCESS -> SUCCESS. Child 0 FAILURE: while fewer than ``number_of_retries``
    recoveries have succeeded, halt it and tick child 1; otherwise FAILURE. Child 1 SUCCESS
    counts a retry and goes back to child 0 (in the same tick); child 1 FAILURE -> FAILURE;
    child 1 SKIPPED -> FAILURE (not counted). The counter resets when the node finishes or is
    halted, so ``number_of_retries`` is the number of successful recovery passes allowed.
    """

    @classmethod
    def provided_ports(cls):
        return [input_port("number_of_retries", INT, 1, "Number of retries")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.current_child_idx = 0
        self.retry_count = 0
        self.number_of_retries = 1
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        self.number_of_retries = int(self.get_input("number_of_retries", self.number_of_retries))
        children = self.children
        if len(children) != 2:
            raise BehaviorTreeException(f"Recovery Node '{self.name}' must only have 2 children.")
        self.set_status(RUNNING)
        while self.current_child_idx < 2 and self.retry_count <= self.number_of_retries:
            status = tick_child(children[self.current_child_idx])
            if self.current_child_idx == 0:
                if status is SKIPPED:
                    self.halt()
                    return SKIPPED
                if status is SUCCESS:
                    self.halt_child(1)
                    self.halt()
                    return SUCCESS
                if status is RUNNING:
                    return RUNNING
                if status is FAILURE:
                    if self.retry_count < self.number_of_retries:
                        self.halt_child(0)
                        self.current_child_idx += 1
                        continue
                    self.halt()
                    return FAILURE
                raise LogicError("A child node must never return IDLE")
            if status is SKIPPED:
                self.current_child_idx = 0
                self.halt_child(1)
                return FAILURE
            if status is RUNNING:
                return RUNNING
            if status is SUCCESS:
                self.halt_child(1)
                self.retry_count += 1
                self.current_child_idx = 0
                continue
            if status is FAILURE:
                self.halt()
                return FAILURE
            raise LogicError("A child node must never return IDLE")
        self.halt()
        return FAILURE

    def halt(self) -> None:
        # BT.CPP ControlNode::halt: reset the children, then the status (the caller stores the
        # returned status afterwards, as BT.CPP's executeTick does).
        self.reset_children()
        self.reset_status()
        self.retry_count = 0
        self.current_child_idx = 0


class RoundRobin(ControlNode):
    """One child per activation, in turn: each recovery episode runs the next recovery.

    Ticks the current child: RUNNING -> RUNNING; SUCCESS -> advance, SUCCESS; FAILURE ->
    advance and try the next child in the same tick. The index survives between activations
    (a finished node is only status-reset), and is reset to the first child by ``halt()``
    (e.g. at the end of each navigation goal, when the whole tree is halted).

    ``wrap_around`` (Nav2 main, PR #5308) chooses the version: ``true`` (the default here,
    Nav2 Humble/Jazzy/Kilted behaviour) wraps to the first child and fails only after every
    child failed in a row; ``false`` (main's default) fails as soon as the last child has been
    attempted, even if it succeeded.
    """

    @classmethod
    def provided_ports(cls):
        return [input_port("wrap_around", BOOL, True,
                           "Enable wrap-around to first child after last child fails (Jazzy behaviour: "
                           "true; Nav2 main defaults to false)")]

    def __init__(self, name: str, config: NodeConfig | None = None):
        self.current_child_idx = 0
        self.num_failed_children = 0
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        wrap_around = bool(self.get_input("wrap_around", True))
        children = self.children
        n = len(children)
        self.set_status(RUNNING)
        num_skipped = 0
        while self.num_failed_children + num_skipped < n:
            status = tick_child(children[self.current_child_idx])
            if status is not RUNNING:
                self.current_child_idx += 1
                if self.current_child_idx == n:
                    if wrap_around:
                        self.current_child_idx = 0
                    else:
                        if status is SKIPPED:
                            num_skipped += 1
                        elif status is FAILURE:
                            self.num_failed_children += 1
                        break
            if status is SUCCESS:
                self.num_failed_children = 0
                self.reset_children()
                return SUCCESS
            if status is FAILURE:
                self.num_failed_children += 1
            elif status is SKIPPED:
                num_skipped += 1
            elif status is RUNNING:
                return RUNNING
            elif status is IDLE:
                raise LogicError("Invalid status return from BT node")
        all_skipped = num_skipped == n
        self.halt()
        return SKIPPED if all_skipped else FAILURE

    def halt(self) -> None:
        self.reset_children()
        self.reset_status()
        self.current_child_idx = 0
        self.num_failed_children = 0
