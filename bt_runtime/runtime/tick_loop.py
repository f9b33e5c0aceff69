"""The tick task: ticks the tree at 100 Hz on absolute deadlines, and never dies.

Deadlines are ``t0 + k * period`` (no drift). In real time each deadline is one timer on a
loop with microsecond timers (``clock.new_realtime_loop``) whose callback ticks the tree
(``pacing.py``); with ``pacing: precise`` the timer fires just before the deadline and the
callback yields until it is reached, for the lowest lateness at the cost of a busy core share.
On a virtual-time loop the task sleeps to each deadline. A tick that raises
is logged with the node's path; the tree is halted, the gate stops the robot, and ticking
resumes on the next period. Lateness and tick cost (CPU of the ticking thread, and wall) are
recorded for ``bench/loop.py`` and the run summary.
"""

from __future__ import annotations

import asyncio
import math
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
import structlog

from ..errors import NodeExecutionError
from ..status import FAILURE, IDLE, SUCCESS, NodeStatus
from .clock import is_virtual, sleep_until
from .config import TickConfig
from .pacing import TimerPacer

if TYPE_CHECKING:
    from ..tree import Tree
    from .gate import DecisionGate
    from .supervisor import SystemSupervisor

log = structlog.get_logger("bt_runtime.tick")
_thread_time = time.thread_time

TICK_ERROR = "tick error"
LATENCY_BINS_US = (0, 10, 50, 100, 250, 500, 1000, 2500, 5000, math.inf)


class TickStats:
    """Bounded record of tick lateness and cost (the last ``keep`` ticks, plus totals)."""

    def __init__(self, keep: int = 200_000):
        self.keep = keep
        self.lateness = np.zeros(keep, dtype=np.float64)  # seconds
        # seconds of CPU the ticking thread spent in tick() (time.thread_time): what the tree
        # costs, whatever else the machine runs; the wall time of the same ticks, which includes
        # being descheduled on a busy machine, is kept apart (wall_total)
        self.cost = np.zeros(keep, dtype=np.float64)
        self.count = 0
        self.errors = 0
        self.overruns = 0  # deadlines skipped because a tick ran past the next one
        self.cost_total = 0.0
        self.cost_max = 0.0
        self.wall_total = 0.0

    def add(self, lateness: float, cost: float, wall: float | None = None) -> None:
        i = self.count % self.keep
        self.lateness[i] = lateness
        self.cost[i] = cost
        self.count += 1
        self.cost_total += cost
        self.wall_total += cost if wall is None else wall
        if cost > self.cost_max:
            self.cost_max = cost

    def _window(self, array: np.ndarray) -> np.ndarray:
        return array[: min(self.count, self.keep)]

    def lateness_percentiles(self, qs=(50, 90, 99, 99.9)) -> dict[str, float]:
        data = self._window(self.lateness)
        if not len(data):
            return {}
        return {f"p{q:g}": float(np.percentile(data, q)) for q in qs}

    def cost_percentiles(self, qs=(50, 99)) -> dict[str, float]:
        data = self._window(self.cost)
        if not len(data):
            return {}
        return {f"p{q:g}": float(np.percentile(data, q)) for q in qs}

    @property
    def cost_mean(self) -> float:
        """Mean CPU seconds of a tick."""
        return self.cost_total / self.count if self.count else 0.0

    @property
    def wall_mean(self) -> float:
        """Mean wall seconds of a tick (CPU plus time descheduled)."""
        return self.wall_total / self.count if self.count else 0.0

    def histogram(self) -> list[tuple[str, int]]:
        data = self._window(self.lateness) * 1e6
        counts, _ = np.histogram(data, bins=np.array(LATENCY_BINS_US[:-1] + (1e12,)))
        labels = [f"{lo:g}-{hi:g} us" if math.isfinite(hi) else f">{lo:g} us"
                  for lo, hi in zip(LATENCY_BINS_US[:-1], LATENCY_BINS_US[1:])]
        return list(zip(labels, counts.tolist()))


class TickLoop:
    """Ticks one tree; reports to the gate (heartbeat) and the supervisor ("tree")."""

    def __init__(self, tree: Tree, config: TickConfig | None = None, *, gate: DecisionGate | None = None,
                 supervisor: SystemSupervisor | None = None, realtime: bool | None = None):
        self.tree = tree
        self.config = config or TickConfig()
        self.gate = gate
        self.supervisor = supervisor
        self.realtime = realtime
        self.stats = TickStats()
        self.status: NodeStatus = NodeStatus.IDLE
        self.done: asyncio.Future | None = None
        self.last_error: BaseException | None = None
        self.on_tick: list[Callable[[NodeStatus], Any]] = []
        # called first in every tick: the driver delivers the messages held for the tick
        # (Ros2Driver.deliver_held), so the tree and the gate see them in this tick
        self.before_tick: list[Callable[[], Any]] = []
        self._error_latched = False
        self._last_error_key: tuple | None = None
        self.pacer: TimerPacer | None = None  # the real-time pacing of the current run

    @property
    def period(self) -> float:
        return 1.0 / self.config.rate_hz

    async def run(self, start_at: float | None = None) -> NodeStatus:
        """Tick until the root completes (when ``stop_on_completion``) or the task is cancelled.

        The first deadline is ``start_at + period`` (default: now + period); later ones follow
        on the same grid, skipping deadlines a slow tick has already passed.
        """
        loop = asyncio.get_running_loop()
        # a virtual-time loop always takes the task path (its time only moves when the loop is
        # idle, so precise pacing's yields would never reach the deadline)
        timer_paced = not is_virtual(loop) and (self.realtime is None or self.realtime)
        precise = timer_paced and self.config.pacing == "precise"
        self.tree.set_clock(loop.time)
        self.done = loop.create_future()
        period = self.period
        t0 = loop.time() if start_at is None else start_at
        k = max(0, int((loop.time() - t0) // period))
        try:
            if timer_paced:  # one loop timer per tick (pacing.py)
                self.pacer = TimerPacer(self, loop, t0, k, precise=precise, spin_window=self.config.spin_window_s)
                await self.pacer.run()
            else:
                await self._run_virtual(loop, t0, k)
        finally:
            if not self.done.done():
                self.done.set_result(self.status)
        return self.status

    async def _run_virtual(self, loop: asyncio.AbstractEventLoop, t0: float, k: int) -> None:
        """The task path: virtual-time loops (a run's event order is part of its trace), and
        ``realtime=False``."""
        period = self.period
        while True:
            k += 1
            deadline = t0 + k * period
            await sleep_until(deadline)
            # timers due during the pause fire now; the pause answered their wake-up (and
            # any other), as BT.CPP's Tree::sleep does, so this tick is not doubled
            self.tree.timers.fire_due()
            self.tree.wake_up.check_and_clear()
            now = loop.time()
            status = self._tick_once(now - deadline)
            if self.config.stop_on_completion and (status is SUCCESS or status is FAILURE):
                return
            behind = loop.time() - (t0 + (k + 1) * period)
            if behind > 0:  # this tick ran past the next deadline: skip the missed ones
                missed = int(behind // period) + 1
                self.stats.overruns += missed
                k += missed

    def _tick_once(self, lateness: float) -> NodeStatus:
        for callback in self.before_tick:
            try:
                callback()
            except Exception as exc:  # a delivery hook must not stop the ticks
                log.error("before_tick_failed", error=repr(exc))
        gate = self.gate
        if gate is not None:
            gate.heartbeat()
        if self.supervisor is not None and "tree" in self.supervisor.components:
            self.supervisor.heartbeat("tree")
        w0, t0 = time.perf_counter(), _thread_time()
        try:
            status = self.tree.tick_once(self.config.max_reticks)
        except Exception as exc:  # the loop never dies: log, halt, stop the robot, go on
            self.stats.add(lateness, _thread_time() - t0, time.perf_counter() - w0)
            self._on_error(exc)
            if gate is not None:
                gate.after_tick()
            return self.status
        except BaseException as exc:  # KeyboardInterrupt/SystemExit from a node: stop the robot, let it through
            log.error("tick_interrupted", error_type=type(exc).__name__, error=str(exc))
            if gate is not None:
                gate.emergency_stop(f"tick interrupted ({type(exc).__name__})")
            raise
        self.stats.add(lateness, _thread_time() - t0, time.perf_counter() - w0)
        if gate is not None:
            gate.after_tick()
        if self._error_latched:
            self._error_latched = False
            if gate is not None:
                gate.release(TICK_ERROR)
        self.status = status
        for callback in self.on_tick:
            callback(status)
        return status

    def _on_error(self, exc: Exception) -> None:
        self.stats.errors += 1
        self.last_error = exc
        node = exc.node_path if isinstance(exc, NodeExecutionError) else None
        # the traceback once per distinct error: a tree that raises on every tick must not flood the log
        key = (node, type(exc).__name__, str(exc))
        repeated = key == self._last_error_key
        self._last_error_key = key
        log.error("tick_error", node=node, error=str(exc), error_type=type(exc).__name__,
                  sim_time=round(self.tree.clock(), 3), repeated=repeated, exc_info=None if repeated else exc)
        if self.gate is not None:
            self.gate.emergency_stop(TICK_ERROR)
            self._error_latched = True
        try:
            self.tree.halt_tree()
        except Exception as halt_exc:  # a node that also fails to halt must not kill the loop
            log.error("halt_error", error=str(halt_exc), error_type=type(halt_exc).__name__)
        self.status = IDLE
