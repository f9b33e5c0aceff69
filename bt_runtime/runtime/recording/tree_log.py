"""What goes on ``/behavior_tree_log``: the tree's status changes, in one of three modes.

* ``states`` (default): after every tick, the nodes whose status differs from their status
  after the previous tick, as ``previous -> current`` events. One pass over the nodes' status
  cells per tick, no callback on the tick path: ~3.5 us a tick for the autonomy tree's 137
  nodes (7.5 us with ``map(attrgetter)``). What it does not show: a node that ran and went back to IDLE within one tick (a condition checked
  and reset by its parent in the same tick), exactly as Groot2's sampled monitor.
* ``changes``: every status transition, as Nav2's ``RosTopicLogger`` publishes them, through a
  status observer on every node; a tick whose transitions repeat the previous tick's exactly is
  not logged again. Exact, but the observer costs a Python call per transition (the autonomy
  tree makes ~4 800 a robot second: +30-40 % of a run's CPU).
* ``all``: as ``changes``, every tick logged (Nav2's behaviour).

Each produces, per logged tick, ``[(t, node, previous, current)]`` for the ``tree_log`` converter.
"""

from __future__ import annotations

from collections.abc import Callable
from operator import attrgetter
from typing import Any

from ...status import IDLE

Events = list[tuple[float, Any, Any, Any]]
_cell = attrgetter("_cell")  # the node's status cell (node.py): a slot read, where node.status is a property


class TreeStateLog:
    """``states`` mode: compare the status of every node after each tick with the last one."""

    def __init__(self, tree: Any, clock: Callable[[], float], emit: Callable[[Events], None]):
        self.nodes = list(tree.nodes())
        self.cells = list(map(_cell, self.nodes))
        self.last = [IDLE] * len(self.nodes)
        self.clock = clock
        self.emit = emit

    def after_tick(self, _root: Any = None) -> None:
        """Also the tick loop's ``on_tick`` callback itself (its argument, the root's status, unused)."""
        # a comprehension: CPython 3.11 specializes the slot read, ~2x faster than map(attrgetter)
        now = [cell.status for cell in self.cells]
        if now == self.last:
            return
        last, nodes = self.last, self.nodes
        t = self.clock()
        self.last = now
        self.emit([(t, nodes[i], last[i], cur) for i, cur in enumerate(now) if cur is not last[i]])

    flush = after_tick  # changes outside ticks (a halt at stop) show on the next pass

    def close(self) -> None:
        self.after_tick()


class TreeTransitionLog:
    """``changes`` and ``all`` modes: a status observer on every node."""

    def __init__(self, tree: Any, clock: Callable[[], float], emit: Callable[[Events], None], *, every_tick: bool):
        self.clock = clock
        self.emit = emit
        self.every_tick = every_tick
        self.events: Events = []
        self.last_keys: list[tuple[Any, Any, Any]] | None = None
        self.repeated_ticks = 0
        self.remove = tree.add_status_observer(self._on_status)

    def _on_status(self, stamp: float, node: Any, previous: Any, new: Any) -> None:
        self.events.append((stamp, node, previous, new))  # names are looked up off the loop

    def after_tick(self, _root: Any = None) -> None:
        if self.events:
            self.flush()

    def flush(self) -> None:
        events = self.events
        if not events:
            return
        self.events = []
        if not self.every_tick:
            keys = [e[1:] for e in events]  # (node, previous, new): the same objects tick after tick
            if keys == self.last_keys:
                self.repeated_ticks += 1
                return
            self.last_keys = keys
        self.emit(events)

    def close(self) -> None:
        self.remove()
        self.flush()


def tree_log(mode: str, tree: Any, clock: Callable[[], float], emit: Callable[[Events], None]) -> Any:
    if mode == "states":
        return TreeStateLog(tree, clock, emit)
    return TreeTransitionLog(tree, clock, emit, every_tick=mode == "all")
