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


class SequentialNode(ControlNode):
    """Sequence, Fallback and their Async variants are one algorithm: tick children in
    order, remembering the current index; ``_advance_on`` moves to the next child,
    ``_stop_on`` ends the node. One class (configured per instance) keeps the attribute
    sites in this hot loop monomorphic, which CPython's specializer rewards."""

    # Hot attributes live in slots: CPython 3.11 reads slots much faster than class
    # constants looked up through an instance that also has a __dict__.
    __slots__ = ("_idx", "_skipped", "_advance_on", "_stop_on", "_all_done", "_asynch", "kind")

    def __init__(self, name: str, config: NodeConfig | None = None, *, fallback: bool = False,
                 asynch: bool = False):
        self._idx = 0
        self._skipped = 0
        if fallback:
            self._advance_on, self._stop_on, self._all_done = FAILURE, SUCCESS, FAILURE
        else:
            self._advance_on, self._stop_on, self._all_done = SUCCESS, FAILURE, SUCCESS
        self._asynch = asynch
        self.kind = ("Async" if asynch else "") + ("Fallback" if fallback else "Sequence")
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        current = self._status
        if current is not RUNNING:
            if current is IDLE and self._skipped:
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
                if idx:
                    self._idx = 0
                break
            elif status is SKIPPED:
                idx += 1
                self._skipped += 1
            else:
                raise _idle_child(self)
        else:
            skipped = self._skipped
            if skipped:
                status = SKIPPED if skipped == n else self._all_done
                self._skipped = 0
            else:
                status = self._all_done
            if idx:
                self._idx = 0
        for child in children:  # reset_children(), inlined for speed
            child_status = child._status
            if child_status is not IDLE:
                if child_status is RUNNING:
                    child.halt_node()
                if child._subscribers:
                    child.reset_status()
                else:
                    child._status = IDLE
        return status

    def halt(self) -> None:
        self._idx = 0
        self._skipped = 0
        ControlNode.halt(self)


def SequenceNode(name: str, config: NodeConfig | None = None) -> SequentialNode:  # noqa: N802
    """Tick children in order; FAILURE stops and restarts from the first child next time."""
    return SequentialNode(name, config)


def AsyncSequenceNode(name: str, config: NodeConfig | None = None) -> SequentialNode:  # noqa: N802
    """Like Sequence, but yields (RUNNING + wake-up) after each synchronous child success."""
    return SequentialNode(name, config, asynch=True)


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


def FallbackNode(name: str, config: NodeConfig | None = None) -> SequentialNode:  # noqa: N802
    """Tick children in order until one succeeds; FAILURE moves on to the next child."""
    return SequentialNode(name, config, fallback=True)


def AsyncFallbackNode(name: str, config: NodeConfig | None = None) -> SequentialNode:  # noqa: N802
    """Like Fallback, but yields (RUNNING + wake-up) after each synchronous child failure."""
    return SequentialNode(name, config, fallback=True, asynch=True)
