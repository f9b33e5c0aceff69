"""ReactiveSequence and ReactiveFallback: re-tick every child from the first on every tick.

When a child returns RUNNING every *other* child is halted/reset, so earlier conditions are
re-evaluated fresh next tick and a previously running sibling is stopped (spec 4.2).
"""

from __future__ import annotations

from ..errors import LogicError, NodeExecutionError
from ..node import ControlNode, NodeConfig, _wrap_error
from ..status import FAILURE, IDLE, RUNNING, SKIPPED, SUCCESS, NodeStatus


class ReactiveNode(ControlNode):
    """ReactiveSequence (stop on FAILURE) and ReactiveFallback (stop on SUCCESS): one class,
    configured per instance, so this hot loop stays monomorphic."""

    __slots__ = ("_running_child", "_stop_on", "_otherwise", "_label")
    throw_if_multiple_running = False  # BT.CPP's process-wide EnableException flag

    def __init__(self, name: str, config: NodeConfig | None = None, *, fallback: bool = False):
        self._running_child = -1
        self._stop_on, self._otherwise = (SUCCESS, FAILURE) if fallback else (FAILURE, SUCCESS)
        self._label = "ReactiveFallback" if fallback else "ReactiveSequence"
        if self._linear_mro:  # super().__init__(...) without its cost (TreeNode._linear_mro)
            ControlNode.__init__(self, name, config)
        else:
            super().__init__(name, config)

    @classmethod
    def enable_exception(cls, enable: bool) -> None:
        cls.throw_if_multiple_running = enable

    def tick(self) -> NodeStatus:
        cell = self._cell
        current = cell.status
        if current is not RUNNING:
            if current is IDLE:
                self._running_child = -1
            cell.status = RUNNING  # notifies if observed
        stop_on = self._stop_on
        all_skipped = True
        cells = self._cells
        for child in cells:
            # -- tick the child and store its status (node.tick_cell, inlined for speed) --
            fast = child.fast
            try:
                status = fast(child.node)
            except NodeExecutionError:
                raise
            except Exception as exc:
                raise _wrap_error(child, exc) from exc
            # (SKIPPED is never stored; IDLE raises through set_status)
            # ---------------------------------------------------------------------------------
            if status is stop_on:
                child.status = status
                for other in cells:  # reset_children(), inlined for speed
                    other_status = other.status
                    if other_status is not IDLE:
                        if other_status is RUNNING:
                            other.node.halt_node()
                        other.status = IDLE  # notifies if observed
                return stop_on
            if status is RUNNING:
                child.status = status
                for other in cells:  # halt/reset every other child (halt_child, inlined)
                    if other is not child:
                        other_status = other.status
                        if other_status is not IDLE:
                            if other_status is RUNNING:
                                other.node.halt_node()
                            other.status = IDLE  # notifies if observed
                index = cells.index(child)  # (cells are compared by identity)
                if self._running_child == -1:
                    self._running_child = index
                elif self.throw_if_multiple_running and self._running_child != index:
                    raise LogicError(f"[{self._label}]: only a single child can return RUNNING.\n"
                                     f"This throw can be disabled with {self._label}::EnableException(false)")
                return RUNNING
            if status is SKIPPED:
                if child.status is RUNNING:  # halt_child(), inlined
                    child.node.halt_node()
                child.status = IDLE
            else:
                if status is IDLE:
                    child.node.set_status(status)  # raises
                child.status = status
                all_skipped = False
        for child in cells:  # reset_children(), inlined for speed
            child_status = child.status
            if child_status is not IDLE:
                if child_status is RUNNING:
                    child.node.halt_node()
                child.status = IDLE  # notifies if observed
        return SKIPPED if all_skipped else self._otherwise

    def halt(self) -> None:
        self._running_child = -1
        ControlNode.halt(self)


def ReactiveSequenceNode(name: str, config: NodeConfig | None = None) -> ReactiveNode:  # noqa: N802
    """Re-tick every child each tick; a FAILURE halts the running child."""
    return ReactiveNode(name, config)


def ReactiveFallbackNode(name: str, config: NodeConfig | None = None) -> ReactiveNode:  # noqa: N802
    """Re-tick every child each tick; a SUCCESS halts the running child."""
    return ReactiveNode(name, config, fallback=True)
