"""Status bookkeeping for Groot2's STATUS buffer, kept off the tick's hot path.

The STATUS buffer has one 3-byte record per node (``u16 uid``, ``u8 status``) in BT.CPP's
order: subtree record by subtree record, each in creation order. A node's byte is its current
status, or ``10 + the status it had before`` once it is back to IDLE (0 if it never ran).

The buffer is built **on request** from the nodes' current statuses plus, per node, the last
non-IDLE status seen. Only that "last seen" needs bookkeeping, and there are two ways to keep it:

* ``exact``: a status observer on every node, like BT.CPP's publisher. The buffer is then
  byte-identical to BT.CPP's after the same ticks, but every status change of every node
  costs a Python callback (measured: the tick gets ~3x slower on small-leaf trees).
* ``sampled`` (the default): no permanent observer. Every STATUS request scans the nodes
  (cheap, between ticks), and about once per ``observe_period`` seconds, while a client is
  connected, exactly one tick is observed with a temporary observer. Nodes that are active when
  sampled are exact; a node that ran and went back to IDLE between two samples shows the last
  result seen by a sample or by the last observed tick (at most ``observe_period`` old).
  With a 100 Hz tick and a 1 s period that costs ~1 observed tick in 100.
"""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING

from bt_runtime.status import IDLE, NodeStatus

if TYPE_CHECKING:
    from bt_runtime.node import TreeNode
    from bt_runtime.tree import Tree

EXACT, SAMPLED = "exact", "sampled"


def nodes_in_status_order(tree: Tree) -> list[TreeNode]:
    """BT.CPP's STATUS order: each subtree record in order, its nodes in creation order."""
    return [node for record in tree.subtrees for node in record.nodes]


class StatusTracker:
    def __init__(self, tree: Tree, mode: str = SAMPLED):
        if mode not in (EXACT, SAMPLED):
            raise ValueError(f"status mode must be 'exact' or 'sampled', got {mode!r}")
        self.tree = tree
        self.mode = mode
        self.nodes = nodes_in_status_order(tree)
        self.index = {node.uid: i for i, node in enumerate(self.nodes)}
        n = len(self.nodes)
        self._buf = bytearray(3 * n)
        for i, node in enumerate(self.nodes):
            self._buf[3 * i:3 * i + 2] = node.uid.to_bytes(2, "little")
        self._last = bytearray(n)  # last non-IDLE status seen, 0 = never
        self._codes = bytearray(n)
        self._remove = None
        self._window_open = False
        self._loop: asyncio.AbstractEventLoop | None = None
        self.observed_ticks = 0

    # -- lifecycle -------------------------------------------------------------------------------
    def start(self, loop: asyncio.AbstractEventLoop | None = None) -> None:
        self._loop = loop
        if self.mode == EXACT and self._remove is None:
            self._remove = self.tree.add_status_observer(self._on_change)

    def stop(self) -> None:
        if self._remove is not None:
            self._remove()
            self._remove = None
        self._window_open = False

    # -- observation -----------------------------------------------------------------------------
    def _on_change(self, stamp: float, node: TreeNode, prev: NodeStatus, new: NodeStatus) -> None:
        i = self.index.get(node.uid)
        if i is not None:
            self._last[i] = prev if new is IDLE else new

    def observe_next_tick(self) -> None:
        """Sampled mode: watch every status change until the current tick is over."""
        if self.mode != SAMPLED or self._remove is not None:
            return
        self._window_open = False
        self._remove = self.tree.add_status_observer(self._on_window_change)

    def _on_window_change(self, stamp: float, node: TreeNode, prev: NodeStatus, new: NodeStatus) -> None:
        i = self.index.get(node.uid)
        if i is not None:
            self._last[i] = prev if new is IDLE else new
        if not self._window_open:
            # The tick runs synchronously: a callback scheduled now runs right after it.
            self._window_open = True
            if self._loop is not None:
                self._loop.call_soon_threadsafe(self._close_window)

    def _close_window(self) -> None:
        if self.mode == SAMPLED and self._remove is not None:
            self._remove()
            self._remove = None
            self.observed_ticks += 1
        self._window_open = False

    # -- the buffer ------------------------------------------------------------------------------
    def buffer(self) -> bytes:
        last = self._last
        codes = self._codes
        for i, node in enumerate(self.nodes):
            status = node.status
            if status is not IDLE:
                last[i] = status
                codes[i] = status
            else:
                prev = last[i]
                codes[i] = 10 + prev if prev else 0
        buf = self._buf
        buf[2::3] = codes
        return bytes(buf)
