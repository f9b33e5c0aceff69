"""Sequence, AsyncSequence, SequenceWithMemory, Fallback, AsyncFallback (spec 4.2).

Non-reactive: the current child index is remembered across ticks. The async variants and
SequenceWithMemory return RUNNING after a child that finished synchronously (it was IDLE
before this tick) and emit the wake-up signal, so ``tick_once`` keeps going and
``tick_exactly_once`` steps one child at a time (spec 3.5).
"""

from __future__ import annotations

from collections.abc import Callable

from ..errors import LogicError, NodeExecutionError
from ..node import ControlNode, NodeConfig, TreeNode, _is_execute_tick, _wrap_error
from ..status import FAILURE, IDLE, RUNNING, SKIPPED, SUCCESS, NodeStatus


def _idle_child(node: ControlNode) -> LogicError:
    return LogicError(f"[{node.name}]: A children should not return IDLE")


# (fallback, asynch) -> (_advance_on, _stop_on, _all_done, kind)
_VARIANTS = {(False, False): (SUCCESS, FAILURE, SUCCESS, "Sequence"),
             (False, True): (SUCCESS, FAILURE, SUCCESS, "AsyncSequence"),
             (True, False): (FAILURE, SUCCESS, FAILURE, "Fallback"),
             (True, True): (FAILURE, SUCCESS, FAILURE, "AsyncFallback")}


class SequentialNode(ControlNode):
    """Sequence, Fallback and their Async variants are one algorithm: tick children in
    order, remembering the current index; ``_advance_on`` moves to the next child,
    ``_stop_on`` ends the node. ``tick()`` is the reference implementation (and the async
    variants' fast path); parents of a plain Sequence/Fallback call ``_tick_sequence`` /
    ``_tick_fallback`` (the same loop, constants, no yield rule) or, for a single child,
    ``_tick_single``. The hot loops read the children's cells only (node.NodeCell)."""

    # Hot attributes live in slots: CPython 3.11 reads slots much faster than class
    # constants looked up through an instance that also has a __dict__.
    __slots__ = ("_idx", "_skipped", "_advance_on", "_stop_on", "_all_done", "_asynch", "kind")

    def __init__(self, name: str, config: NodeConfig | None = None, *, fallback: bool = False,
                 asynch: bool = False):
        self._idx = 0
        self._skipped = 0
        self._advance_on, self._stop_on, self._all_done, self.kind = _VARIANTS[fallback, asynch]
        self._asynch = asynch
        if self._linear_mro:  # super().__init__(...) without its cost (TreeNode._linear_mro)
            ControlNode.__init__(self, name, config)
        else:
            super().__init__(name, config)

    def tick(self) -> NodeStatus:
        cell = self._cell
        current = cell.status
        if current is not RUNNING:
            if current is IDLE and self._skipped:
                self._skipped = 0
            cell.status = RUNNING  # notifies if observed
        cells = self._cells
        n = len(cells)
        idx = start = self._idx  # self._idx is only written when returning
        advance_on = self._advance_on
        stop_on = self._stop_on
        while idx < n:
            child = cells[idx]
            prev = child.status
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
            if status is advance_on:
                child.status = status
                idx += 1
                if self._asynch and prev is IDLE and idx < n:
                    self._idx = idx
                    self.config.wake_up.emit()
                    return RUNNING
            elif status is stop_on:
                child.status = status
                if start:
                    self._idx = 0
                break
            elif status is RUNNING:
                child.status = status
                self._idx = idx
                return RUNNING
            elif status is SKIPPED:
                idx += 1
                self._skipped += 1
            else:
                if status is IDLE:
                    child.node.set_status(status)  # raises
                child.status = status
                raise _idle_child(self)
        else:
            skipped = self._skipped
            if skipped:
                status = SKIPPED if skipped == n else self._all_done
                self._skipped = 0
            else:
                status = self._all_done
            if start:
                self._idx = 0
        for child in cells:  # reset_children(), inlined for speed
            child_status = child.status
            if child_status is not IDLE:
                if child_status is RUNNING:
                    child.node.halt_node()
                child.status = IDLE  # notifies if observed
        return status

    def _tick_sequence(self) -> NodeStatus:
        """``tick()`` for a Sequence (not async): the same loop without the yield rule, so it
        need not read the child's previous status, and with the outcomes as constants. What
        parents call (``_cell.fast``). (Few local variables on purpose: a smaller frame is a
        cheaper call.)"""
        cell = self._cell
        status = cell.status
        if status is IDLE:
            if self._skipped:
                self._skipped = 0
            cell.status = RUNNING  # notifies if observed
        elif status is not RUNNING:
            cell.status = RUNNING
        cells = self._cells
        idx = self._idx  # only written when returning
        for cell in cells[idx:] if idx else cells:
            # -- tick the child and store its status (node.tick_cell, inlined for speed) --
            fast = cell.fast
            try:
                status = fast(cell.node)
            except NodeExecutionError:
                raise
            except Exception as exc:
                raise _wrap_error(cell, exc) from exc
            # ---------------------------------------------------------------------------------
            if status is SUCCESS:
                cell.status = status
            elif status is FAILURE:
                cell.status = status
                if self._idx:
                    self._idx = 0
                break
            elif status is RUNNING:
                cell.status = status
                self._idx = cells.index(cell)  # (cells are compared by identity)
                return RUNNING
            elif status is SKIPPED:
                self._skipped += 1
            else:
                if status is IDLE:
                    cell.node.set_status(status)  # raises
                cell.status = status
                raise _idle_child(self)
        else:
            status = SUCCESS
            if self._skipped:
                if self._skipped == len(cells):
                    status = SKIPPED
                self._skipped = 0
            if self._idx:
                self._idx = 0
        for cell in cells:  # reset_children(), inlined for speed
            if cell.status is RUNNING:
                cell.node.halt_node()
            cell.status = IDLE  # notifies if observed (and changed)
        return status

    def _tick_fallback(self) -> NodeStatus:
        """``_tick_sequence`` for a Fallback: the same code with SUCCESS and FAILURE swapped."""
        cell = self._cell
        status = cell.status
        if status is IDLE:
            if self._skipped:
                self._skipped = 0
            cell.status = RUNNING  # notifies if observed
        elif status is not RUNNING:
            cell.status = RUNNING
        cells = self._cells
        idx = self._idx  # only written when returning
        for cell in cells[idx:] if idx else cells:
            # -- tick the child and store its status (node.tick_cell, inlined for speed) --
            fast = cell.fast
            try:
                status = fast(cell.node)
            except NodeExecutionError:
                raise
            except Exception as exc:
                raise _wrap_error(cell, exc) from exc
            # ---------------------------------------------------------------------------------
            if status is FAILURE:
                cell.status = status
            elif status is SUCCESS:
                cell.status = status
                if self._idx:
                    self._idx = 0
                break
            elif status is RUNNING:
                cell.status = status
                self._idx = cells.index(cell)  # (cells are compared by identity)
                return RUNNING
            elif status is SKIPPED:
                self._skipped += 1
            else:
                if status is IDLE:
                    cell.node.set_status(status)  # raises
                cell.status = status
                raise _idle_child(self)
        else:
            status = FAILURE
            if self._skipped:
                if self._skipped == len(cells):
                    status = SKIPPED
                self._skipped = 0
            if self._idx:
                self._idx = 0
        for cell in cells:  # reset_children(), inlined for speed
            if cell.status is RUNNING:
                cell.node.halt_node()
            cell.status = IDLE  # notifies if observed (and changed)
        return status

    def _tick_single(self) -> NodeStatus:
        """``_tick_sequence``/``_tick_fallback`` for a node with a single child (common as a
        wrapper, e.g. for pre/post-conditions): the loop and the reset unrolled, with the same
        outcomes in the same order. With other than one child it hands over to the loop (and
        makes the loop what parents call from then on)."""
        try:
            (cell,) = self._cells  # the child's cell (unpacking is cheaper than a len() test)
        except ValueError:
            cell = None
        if cell is None or self._idx:
            cls = type(self)
            loop = cls._tick_sequence if self._advance_on is SUCCESS else cls._tick_fallback
            if cell is None:
                self._cell.fast = loop  # children were added after the node was built
            return loop(self)
        own = self._cell
        status = own.status
        if status is IDLE:
            if self._skipped:
                self._skipped = 0
            own.status = RUNNING  # notifies if observed
        elif status is not RUNNING:
            own.status = RUNNING
        # -- tick the child (node.tick_cell, inlined for speed) ---------------------------------
        fast = cell.fast
        try:
            status = fast(cell.node)
        except NodeExecutionError:
            raise
        except Exception as exc:
            raise _wrap_error(cell, exc) from exc
        # -----------------------------------------------------------------------------------------
        if status is self._stop_on:
            cell.status = status
        elif status is self._advance_on or status is SKIPPED:  # the loop completes
            if status is SKIPPED:
                self._skipped += 1
            else:
                cell.status = status
            status = self._all_done
            if self._skipped:
                if self._skipped == 1:
                    status = SKIPPED
                self._skipped = 0
        elif status is RUNNING:
            cell.status = status
            self._idx = 0
            return RUNNING
        else:
            if status is IDLE:
                cell.node.set_status(status)  # raises
            cell.status = status
            raise _idle_child(self)
        if cell.status is RUNNING:  # reset_children()
            cell.node.halt_node()
        cell.status = IDLE
        return status

    def _bare_tick(self) -> Callable[[SequentialNode], NodeStatus]:
        cls = type(self)
        if self._asynch:
            return cls.tick
        if len(self._cells) <= 1:  # (while it is being built, too: see _tick_single)
            return cls._tick_single
        return cls._tick_sequence if self._advance_on is SUCCESS else cls._tick_fallback

    def halt(self) -> None:
        self._idx = 0
        self._skipped = 0
        ControlNode.halt(self)


_new_node = object.__new__
_tree_node_init = TreeNode.__init__


def _sequential(name: str, config: NodeConfig | None, variant: tuple, asynch: bool) -> SequentialNode:
    """``SequentialNode(name, config, fallback=..., asynch=...)``: the same stores as its
    ``__init__`` and ControlNode's, in one frame. What the registered builders call, once per
    node built: the type call through three ``__init__``s with keyword arguments costs about
    as much as the rest of the node."""
    self = _new_node(SequentialNode)
    self._idx = 0
    self._skipped = 0
    self._advance_on, self._stop_on, self._all_done, self.kind = variant
    self._asynch = asynch
    self._cells = []
    self._children = None
    _tree_node_init(self, name, config)
    return self


_SEQUENCE, _ASYNC_SEQUENCE = _VARIANTS[False, False], _VARIANTS[False, True]
_FALLBACK, _ASYNC_FALLBACK = _VARIANTS[True, False], _VARIANTS[True, True]


def SequenceNode(name: str, config: NodeConfig | None = None) -> SequentialNode:  # noqa: N802
    """Tick children in order; FAILURE stops and restarts from the first child next time."""
    return _sequential(name, config, _SEQUENCE, False)


def AsyncSequenceNode(name: str, config: NodeConfig | None = None) -> SequentialNode:  # noqa: N802
    """Like Sequence, but yields (RUNNING + wake-up) after each synchronous child success."""
    return _sequential(name, config, _ASYNC_SEQUENCE, True)


class SequenceWithMemoryNode(ControlNode):
    """Like Sequence, but a FAILURE keeps the index (resume at the failed child), it always
    yields after a synchronous success, and halting does not reset the index."""

    __slots__ = ("_idx", "_skipped")

    def __init__(self, name: str, config: NodeConfig | None = None):
        self._idx = 0
        self._skipped = 0
        super().__init__(name, config)

    def tick(self) -> NodeStatus:
        cells = self._cells  # the children's cells (what ``children`` would give, unbuilt)
        n = len(cells)
        own = self._cell
        current = own.status
        if current is not RUNNING:
            if current is IDLE:
                self._skipped = 0
            own.status = RUNNING  # set_status(RUNNING); notifies if observed
        idx = self._idx
        while idx < n:
            cell = cells[idx]
            prev = cell.status
            # -- status = tick_cell(cell) (child.execute_tick()), inlined for speed ---------------
            fast = cell.fast
            try:
                status = fast(cell.node)
            except NodeExecutionError:
                raise
            except Exception as exc:
                if _is_execute_tick(fast, cell.node):  # execute_tick's own error
                    raise
                raise _wrap_error(cell, exc) from exc
            if status is not SKIPPED:
                if status is IDLE:
                    cell.node.set_status(status)  # raises, as BT.CPP's setStatus(IDLE) does
                cell.status = status
            # -------------------------------------------------------------------------------------
            if status is RUNNING:
                return RUNNING
            if status is FAILURE:
                for cell in cells[idx:]:  # halt_child(i) for i in idx..n-1, inlined
                    if cell.status is RUNNING:
                        cell.node.halt_node()
                    cell.status = IDLE
                return FAILURE
            if status is SUCCESS:
                self._idx = idx = idx + 1
                if prev is IDLE and idx < n:
                    self.config.wake_up.emit()
                    return RUNNING
            elif status is SKIPPED:
                self._idx = idx = idx + 1
                self._skipped += 1
            else:
                raise _idle_child(self)
        all_skipped = self._skipped == n
        for cell in cells:  # reset_children(), inlined for speed
            child_status = cell.status
            if child_status is not IDLE:
                if child_status is RUNNING:
                    cell.node.halt_node()
                cell.status = IDLE  # notifies if observed
        self._idx = 0
        self._skipped = 0
        return SKIPPED if all_skipped else SUCCESS

    def halt(self) -> None:
        ControlNode.halt(self)  # the index is kept on purpose (BT.CPP behaviour)


def FallbackNode(name: str, config: NodeConfig | None = None) -> SequentialNode:  # noqa: N802
    """Tick children in order until one succeeds; FAILURE moves on to the next child."""
    return _sequential(name, config, _FALLBACK, False)


def AsyncFallbackNode(name: str, config: NodeConfig | None = None) -> SequentialNode:  # noqa: N802
    """Like Fallback, but yields (RUNNING + wake-up) after each synchronous child failure."""
    return _sequential(name, config, _ASYNC_FALLBACK, True)
