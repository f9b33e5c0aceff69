"""A built tree: its nodes, blackboards and the tick loop (spec 2.12, 3.3, 3.4).

``subtrees`` holds one record per expanded BehaviorTree in creation order (main tree first),
each with its nodes in creation order; node uids start at 1 in depth-first pre-order. Groot2
and the .btlog format depend on this order.
"""

from __future__ import annotations

import asyncio
import contextlib
import fnmatch
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from .errors import BTRuntimeError
from .node import tick_cell
from .status import FAILURE, IDLE, RUNNING, SUCCESS, NodeStatus
from .timers import TimerQueue, WakeUpSignal

if TYPE_CHECKING:
    from .blackboard import Blackboard
    from .node import StatusCallback, TreeNode, TreeNodeManifest

_ONCE, _EXACTLY_ONCE, _WHILE_RUNNING = 0, 1, 2


class HaltError(BTRuntimeError):
    """Some nodes raised while being halted; every node was halted nonetheless."""

    def __init__(self, errors: list[tuple[str, BaseException]]):
        self.errors = errors
        detail = "; ".join(f"{path}: {type(exc).__name__}: {exc}" for path, exc in errors)
        super().__init__(f"{len(errors)} node(s) failed to halt: {detail}")


@dataclass(slots=True)
class SubtreeRecord:
    """One expanded BehaviorTree: its nodes (creation order), blackboard and instance path."""

    tree_id: str
    instance_name: str  # the subtree path; "" for the main tree
    blackboard: Blackboard
    nodes: list[TreeNode] = field(default_factory=list)


class Tree:
    """A behavior tree ready to tick. Built by ``BehaviorTreeFactory.create_tree*``."""

    def __init__(self, subtrees: list[SubtreeRecord], manifests: dict[str, TreeNodeManifest],
                 wake_up: WakeUpSignal, timers: TimerQueue, source_xml: str = "",
                 clock_holder: list | None = None):
        self.subtrees = subtrees
        self.manifests = dict(manifests)
        self.wake_up = wake_up
        self.timers = timers
        self.source_xml = source_xml
        self._clock_holder = clock_holder if clock_holder is not None else [time.monotonic]
        self._observers: list[tuple[StatusCallback, list[Callable[[], None]]]] = []
        self.retick_cutoffs = 0  # tick_once calls that stopped at max_reticks

    def __del__(self) -> None:
        """Break the node <-> cell back-references when the tree is dropped, so its nodes are
        freed by reference counting at once instead of waiting for the cyclic collector
        (BT.CPP destroys a tree's nodes with the tree; a node kept past its tree is dead)."""
        for record in getattr(self, "subtrees", ()):
            for node in record.nodes:
                # (only these nodes can hold a bound execute_tick: asking any other node for its
                # __dict__ would create one, an allocation per node while the tree is freed)
                if node._bound_tick:
                    node.__dict__.pop("execute_tick", None)
                cell = node._cell
                cell.node = None
                cell.fast = None

    # -- structure -----------------------------------------------------------------------------
    @property
    def root_node(self) -> TreeNode:
        if not self.subtrees or not self.subtrees[0].nodes:
            raise BTRuntimeError("Empty Tree")
        return self.subtrees[0].nodes[0]

    @property
    def root_blackboard(self) -> Blackboard:
        return self.subtrees[0].blackboard

    def nodes(self) -> Iterator[TreeNode]:
        """Every node in uid order (the order of the subtree records is not uid order)."""
        return iter(sorted((n for rec in self.subtrees for n in rec.nodes), key=lambda n: n.uid))

    def apply_visitor(self, fn: Callable[[TreeNode], Any]) -> None:
        """Depth-first pre-order through subtrees, like BT.CPP's applyRecursiveVisitor."""
        def visit(node: TreeNode) -> None:
            fn(node)
            for child in node.children_nodes():
                visit(child)
        visit(self.root_node)

    def get_nodes_by_path(self, pattern: str) -> list[TreeNode]:
        """Nodes whose full path matches a wildcard pattern (``*`` and ``?``)."""
        return [n for n in self.nodes() if fnmatch.fnmatchcase(n.full_path, pattern)]

    def node_by_uid(self, uid: int) -> TreeNode | None:
        for rec in self.subtrees:
            for node in rec.nodes:
                if node.uid == uid:
                    return node
        return None

    # -- clock ---------------------------------------------------------------------------------
    @property
    def clock(self) -> Callable[[], float]:
        return self._clock_holder[0]

    def set_clock(self, clock: Callable[[], float]) -> None:
        """Use ``clock`` (seconds) for timers and status timestamps, e.g. ``loop.time``."""
        self._clock_holder[0] = clock
        self.timers.clock = clock
        for rec in self.subtrees:
            for node in rec.nodes:
                node.config.clock = clock

    # -- observers -----------------------------------------------------------------------------
    def add_status_observer(self, callback: StatusCallback, failures_only: bool = False,
                            nodes: Iterable[TreeNode] | None = None) -> Callable[[], None]:
        """Call ``callback(timestamp, node, previous, new)`` on every status change of every node,
        or of ``nodes`` only (with ``failures_only``: on every change to FAILURE). An observed
        node's status stores and reads cost more on every tick: observe only what you need."""
        watched = (node for rec in self.subtrees for node in rec.nodes) if nodes is None else nodes
        unsubs = [node.subscribe_to_status_change(callback, failures_only) for node in watched]
        entry = (callback, unsubs)
        self._observers.append(entry)

        def remove() -> None:
            for unsub in unsubs:
                unsub()
            if entry in self._observers:
                self._observers.remove(entry)

        return remove

    # -- ticking -------------------------------------------------------------------------------
    def tick_once(self, max_reticks: int | None = None) -> NodeStatus:
        """Tick the root; re-tick at once while RUNNING and a wake-up was emitted.

        As in BT.CPP the re-ticks are unbounded by default (so ``Repeat num_cycles="-1"`` of a
        synchronous child never returns). A host loop passes ``max_reticks`` to bound them: the
        root then returns RUNNING and the wake-up stays set for the next tick.
        """
        return self._tick_root(_ONCE, 0.0, max_reticks)

    def tick_exactly_once(self) -> NodeStatus:
        """Tick the root exactly once, ignoring wake-up signals (``_tick_root`` with one pass
        of its loop: the root's tick, then a completed root reset to IDLE)."""
        subtrees = self.subtrees
        if not subtrees or not subtrees[0].nodes:
            raise BTRuntimeError("Empty Tree")
        cell = subtrees[0].nodes[0]._cell  # root_node, inlined
        if self.timers._heap:
            self.timers.fire_due()
        status = tick_cell(cell)
        if status is SUCCESS or status is FAILURE:
            cell.status = IDLE  # root.reset_status()
        return status

    def tick_while_running(self, sleep: float = 0.01) -> NodeStatus:
        """Tick until the root is no longer RUNNING, sleeping ``sleep`` s between ticks
        (interrupted early by a wake-up signal or a due timer)."""
        return self._tick_root(_WHILE_RUNNING, sleep)

    def _tick_root(self, mode: int, sleep: float, max_reticks: int | None = None) -> NodeStatus:
        subtrees = self.subtrees
        if not subtrees or not subtrees[0].nodes:
            raise BTRuntimeError("Empty Tree")
        cell = subtrees[0].nodes[0]._cell  # root_node._cell; root.execute_tick() is tick_cell(cell)
        timers = self.timers
        wake_up = self.wake_up
        status = IDLE
        while status is IDLE or (mode == _WHILE_RUNNING and status is RUNNING):
            if timers._heap:
                timers.fire_due()
            status = tick_cell(cell)
            if mode != _EXACTLY_ONCE:
                reticks = 0
                while status is RUNNING and wake_up.is_set:
                    if max_reticks is not None and reticks >= max_reticks:
                        self.retick_cutoffs += 1  # left set: the host's next tick goes on
                        break
                    wake_up.check_and_clear()
                    reticks += 1
                    status = tick_cell(cell)
            if status is SUCCESS or status is FAILURE:
                cell.status = IDLE  # root.reset_status()
            if status is RUNNING and sleep > 0:
                self.sleep(sleep)
        return status

    def sleep(self, duration: float) -> bool:
        """Block up to ``duration`` s; return True early if a wake-up was emitted (a timer that
        fires emits one). Like BT.CPP's ``Tree::sleep`` the wake-up is consumed, so the next
        ``tick_once`` does not re-tick for a signal this sleep already answered."""
        clock = self.clock
        end = clock() + duration
        while True:
            self.timers.fire_due()
            if self.wake_up.check_and_clear():
                return True
            now = clock()
            if now >= end:
                return False
            nxt = self.timers.next_deadline()
            wait = end - now if nxt is None else min(end, nxt) - now
            time.sleep(max(0.0, min(wait, 0.001 if nxt is not None else wait)))

    async def tick_while_running_async(self, period: float = 0.01) -> NodeStatus:
        """Tick on the running event loop every ``period`` s until the root is not RUNNING.

        Uses the loop's clock (so virtual time works) and awaits between ticks; a wake-up
        signal (an async action finishing) cuts the wait short.
        """
        loop = asyncio.get_running_loop()
        self.set_clock(loop.time)
        woken = asyncio.Event()
        self.wake_up.add_listener(woken.set)
        try:
            status = self.tick_once()
            while status is RUNNING:
                woken.clear()
                nxt = self.timers.next_deadline()
                wait = period if nxt is None else max(0.0, min(period, nxt - loop.time()))
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(woken.wait(), wait)
                self.timers.fire_due()
                self.wake_up.check_and_clear()  # this wait answered it, as Tree::sleep does
                status = self.tick_once()
            return status
        except BaseException:
            self.halt_tree()
            raise
        finally:
            self.wake_up.remove_listener(woken.set)

    def halt_tree(self) -> None:
        """Halt the root, then halt every node (running ``_onHalted`` everywhere), reset the root.

        Halting is complete even when some node's halt raises: every node is still halted (a
        pass that walks the tree without recursion, children before parents, so each error is
        pinned on the node that raised it), and the errors are raised afterwards as one
        ``HaltError`` naming each node."""
        if not self.subtrees or not self.subtrees[0].nodes:
            return
        root = self.root_node
        errors: list[tuple[str, BaseException]] = []
        try:
            root.halt_node()
            order = self._pre_order(root)  # BT.CPP's applyRecursiveVisitor
        except Exception:  # halt what that did not reach, deepest first, and find who raised
            order = self._post_order(root)
        for node in order:
            try:
                node.halt_node()
            except Exception as exc:
                errors.append((node.full_path, exc))
                with contextlib.suppress(Exception):
                    node.reset_status()  # a node whose on_halted raised is halted all the same
        root.reset_status()
        if errors:
            raise HaltError(errors)

    @staticmethod
    def _pre_order(root: TreeNode) -> list[TreeNode]:
        out, stack = [], [root]
        while stack:
            node = stack.pop()
            out.append(node)
            stack.extend(reversed(tuple(node.children_nodes())))
        return out

    @classmethod
    def _post_order(cls, root: TreeNode) -> list[TreeNode]:
        return cls._pre_order_mirrored(root)[::-1]

    @staticmethod
    def _pre_order_mirrored(root: TreeNode) -> list[TreeNode]:
        """Node, then children right to left: reversed, children come before their parent."""
        out, stack = [], [root]
        while stack:
            node = stack.pop()
            out.append(node)
            stack.extend(node.children_nodes())
        return out

    # -- misc ----------------------------------------------------------------------------------
    def __repr__(self) -> str:
        n = sum(len(rec.nodes) for rec in self.subtrees)
        return f"<Tree {self.subtrees[0].tree_id if self.subtrees else '?'}: {n} nodes>"

    def __enter__(self) -> Tree:
        return self

    def __exit__(self, *exc: object) -> None:
        self.halt_tree()
