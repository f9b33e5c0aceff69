"""Sequence, AsyncSequence, SequenceWithMemory, Fallback, AsyncFallback (spec 4.2).

Non-reactive: the current child index is remembered across ticks. The async variants and
SequenceWithMemory return RUNNING after a child that finished synchronously (it was IDLE
before this tick) and emit the wake-up signal, so ``tick_once`` keeps going and
``tick_exactly_once`` steps one child at a time (spec 3.5).
"""

from __future__ import annotations

from ..errors import LogicError, NodeExecutionError
from ..node import ControlNode, NodeConfig
from ..status import FAILURE, IDLE, RUNNING, SKIPPED, SUCCESS, NodeStatus


def _idle_child(node: ControlNode) -> LogicError:
    return LogicError(f"[{node.name}]: A children should not return IDLE")


class _SequentialNode(ControlNode):
    """Sequence and Fallback are mirror images: tick children in order, remembering the
    current index; ``_advance_on`` moves to the next child, ``_stop_on`` ends the node."""

    # Hot attributes live in slots: CPython 3.11 reads slots much faster than class
    # constants looked up through an instance that also has a __dict__.
    __slots__ = ("_idx", "_skipped", "_advance_on", "_stop_on", "_all_done", "_asynch")
    asynch = False
    advance_on: NodeStatus = SUCCESS
    stop_on: NodeStatus = FAILURE
    all_done: NodeStatus = SUCCESS

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._idx = 0
        self._skipped = 0
        cls = type(self)
        self._advance_on, self._stop_on, self._all_done = cls.advance_on, cls.stop_on, cls.all_done
        self._asynch = cls.asynch
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        current = self._status
        if current is not RUNNING:
            if current is IDLE:
                self._skipped = 0
            if self._subscribers:
                self.set_status(RUNNING)
            else:
                self._status = RUNNING
        children = self.children
        n = len(children)
        idx = self._idx
        advance_on = self._advance_on
        while idx < n:
            child = children[idx]
            prev = child._status
            # -- tick the child and store its status (node.tick_child, inlined for speed) --
            try:
                status = child._fast()
            except NodeExecutionError:
                raise
            except Exception as exc:
                raise NodeExecutionError(child.config.path, child.config.registration_id, exc) from exc
            if status is not prev:
                if status is not SKIPPED:
                    if status is IDLE or child._subscribers:
                        child.set_status(status)
                    else:
                        child._status = status
            elif status is IDLE:
                child.set_status(status)
            # ---------------------------------------------------------------------------------
            if status is advance_on:
                idx += 1
                if self._asynch and prev is IDLE and idx < n:
                    self._idx = idx
                    self.config.wake_up.emit()
                    return RUNNING
            elif status is RUNNING:
                self._idx = idx
                return RUNNING
            elif status is self._stop_on:
                self.reset_children()
                self._idx = 0
                return status
            elif status is SKIPPED:
                idx += 1
                self._skipped += 1
            else:
                raise _idle_child(self)
        all_skipped = self._skipped == n
        self.reset_children()
        self._idx = 0
        self._skipped = 0
        return SKIPPED if all_skipped else self._all_done

    def halt(self) -> None:
        self._idx = 0
        self._skipped = 0
        ControlNode.halt(self)


class SequenceNode(_SequentialNode):
    """Tick children in order; FAILURE stops and restarts from the first child next time."""


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


class FallbackNode(_SequentialNode):
    """Tick children in order until one succeeds; FAILURE moves on to the next child."""

    advance_on = FAILURE
    stop_on = SUCCESS
    all_done = FAILURE


class AsyncFallbackNode(FallbackNode):
    asynch = True
