"""Sequence, AsyncSequence, SequenceWithMemory, Fallback, AsyncFallback (spec 4.2).

Non-reactive: the current child index is remembered across ticks. The async variants and
SequenceWithMemory return RUNNING after a child that finished synchronously (it was IDLE
before this tick) and emit the wake-up signal, so ``tick_once`` keeps going and
``tick_exactly_once`` steps one child at a time (spec 3.5).
"""

from __future__ import annotations

from ..errors import LogicError
from ..node import ControlNode, NodeConfig
from ..status import FAILURE, IDLE, RUNNING, SKIPPED, SUCCESS, NodeStatus


def _idle_child(node: ControlNode) -> LogicError:
    return LogicError(f"[{node.name}]: A children should not return IDLE")


class SequenceNode(ControlNode):
    """Tick children in order; FAILURE stops and restarts from the first child."""

    asynch = False

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._idx = 0
        self._skipped = 0
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        children = self.children
        n = len(children)
        current = self._status
        if current is not RUNNING:
            if current is IDLE:
                self._skipped = 0
            self.set_status(RUNNING)
        while self._idx < n:
            child = children[self._idx]
            prev = child._status
            status = child.execute_tick()
            if status is RUNNING:
                return RUNNING
            if status is SUCCESS:
                self._idx += 1
                if self.asynch and prev is IDLE and self._idx < n:
                    self.config.wake_up.emit()
                    return RUNNING
            elif status is FAILURE:
                self.reset_children()
                self._idx = 0
                return FAILURE
            elif status is SKIPPED:
                self._idx += 1
                self._skipped += 1
            else:
                raise _idle_child(self)
        all_skipped = self._skipped == n
        self.reset_children()
        self._idx = 0
        self._skipped = 0
        return SKIPPED if all_skipped else SUCCESS

    def halt(self) -> None:
        self._idx = 0
        self._skipped = 0
        ControlNode.halt(self)


class AsyncSequenceNode(SequenceNode):
    asynch = True


class SequenceWithMemoryNode(ControlNode):
    """Like Sequence, but a FAILURE keeps the index (resume at the failed child), it always
    yields after a synchronous success, and halting does not reset the index."""

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._idx = 0
        self._skipped = 0
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        children = self.children
        n = len(children)
        current = self._status
        if current is not RUNNING:
            if current is IDLE:
                self._skipped = 0
            self.set_status(RUNNING)
        while self._idx < n:
            child = children[self._idx]
            prev = child._status
            status = child.execute_tick()
            if status is RUNNING:
                return RUNNING
            if status is FAILURE:
                for i in range(self._idx, n):
                    self.halt_child(i)
                return FAILURE
            if status is SUCCESS:
                self._idx += 1
                if prev is IDLE and self._idx < n:
                    self.config.wake_up.emit()
                    return RUNNING
            elif status is SKIPPED:
                self._idx += 1
                self._skipped += 1
            else:
                raise _idle_child(self)
        all_skipped = self._skipped == n
        self.reset_children()
        self._idx = 0
        self._skipped = 0
        return SKIPPED if all_skipped else SUCCESS

    def halt(self) -> None:
        ControlNode.halt(self)  # the index is kept on purpose (BT.CPP behaviour)


class FallbackNode(ControlNode):
    """Tick children in order until one succeeds; FAILURE moves to the next child."""

    asynch = False

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._idx = 0
        self._skipped = 0
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        children = self.children
        n = len(children)
        current = self._status
        if current is not RUNNING:
            if current is IDLE:
                self._skipped = 0
            self.set_status(RUNNING)
        while self._idx < n:
            child = children[self._idx]
            prev = child._status
            status = child.execute_tick()
            if status is RUNNING:
                return RUNNING
            if status is FAILURE:
                self._idx += 1
                if self.asynch and prev is IDLE and self._idx < n:
                    self.config.wake_up.emit()
                    return RUNNING
            elif status is SUCCESS:
                self.reset_children()
                self._idx = 0
                return SUCCESS
            elif status is SKIPPED:
                self._idx += 1
                self._skipped += 1
            else:
                raise _idle_child(self)
        all_skipped = self._skipped == n
        self.reset_children()
        self._idx = 0
        self._skipped = 0
        return SKIPPED if all_skipped else FAILURE

    def halt(self) -> None:
        self._idx = 0
        self._skipped = 0
        ControlNode.halt(self)


class AsyncFallbackNode(FallbackNode):
    asynch = True
