"""Real-time pacing of the tick loop: one loop timer per tick, the tick runs in its callback.

``await asyncio.sleep(...)`` costs two passes of the event loop per tick: the timer resolves a
future, and the task waiting on it runs in the next pass (a second ``select()``), with a new
future, timer handle and coroutine frame each time. At 100 Hz that is most of what an idle
loop spends on pacing. Here each deadline is one ``loop.call_at`` whose callback ticks the tree
and schedules the next deadline: one pass, one handle. The tick task only awaits ``finished``;
cancelling it cancels the pending timer, and an exception escaping a tick (only
``BaseException``: ``TickLoop._tick_once`` catches the rest) ends the task with it, as before.

With ``precise`` the timer fires ``spin_window`` before the deadline and the callback yields
to the loop (``call_soon``) until the deadline is reached. Virtual-time loops keep the task
path (``TickLoop._run_virtual``): their event order is part of a run's reproducible trace.
"""

from __future__ import annotations

import asyncio
import contextvars
from typing import TYPE_CHECKING

from ..status import FAILURE, SUCCESS

if TYPE_CHECKING:
    from .tick_loop import TickLoop


class TimerPacer:
    """Ticks ``owner`` on ``t0 + k * period`` (k > ``k``) until ``finished`` is done."""

    def __init__(self, owner: TickLoop, loop: asyncio.AbstractEventLoop, t0: float, k: int, *,
                 precise: bool, spin_window: float):
        self.owner = owner
        self.loop = loop
        self.t0 = t0
        self.k = k
        self.period = owner.period
        self.precise = precise
        self.spin_window = spin_window if precise else 0.0
        self.finished: asyncio.Future = loop.create_future()
        self.deadline = t0
        self.yields = 0  # precise: passes through the loop spent waiting for a deadline
        self._handle: asyncio.Handle | None = None
        self._context = contextvars.copy_context()  # every tick runs in the tick task's context

    async def run(self):
        self._schedule()
        try:
            return await self.finished
        finally:
            self.cancel()

    def cancel(self) -> None:
        handle, self._handle = self._handle, None
        if handle is not None:
            handle.cancel()
        if not self.finished.done():
            self.finished.cancel()

    def _schedule(self) -> None:
        if self.finished.done():  # cancelled from inside the tick (e.g. the tree was restarted)
            return
        self.k += 1
        self.deadline = self.t0 + self.k * self.period
        self._handle = self.loop.call_at(self.deadline - self.spin_window, self._on_timer, context=self._context)

    def _on_timer(self) -> None:
        self._handle = None
        if self.finished.done():
            return
        loop = self.loop
        if self.precise and loop.time() < self.deadline:
            self.yields += 1
            self._handle = loop.call_soon(self._on_timer, context=self._context)
            return
        try:
            self._tick(loop)
        except BaseException as exc:  # a node let KeyboardInterrupt/SystemExit/CancelledError through
            if not self.finished.done():
                if isinstance(exc, asyncio.CancelledError):
                    self.finished.cancel()
                else:
                    self.finished.set_exception(exc)
            if isinstance(exc, (KeyboardInterrupt, SystemExit)):
                raise

    def _tick(self, loop: asyncio.AbstractEventLoop) -> None:
        owner = self.owner
        tree = owner.tree
        # timers due during the pause fire now; the pause answered their wake-up (and any
        # other), as BT.CPP's Tree::sleep does, so this tick is not doubled
        tree.timers.fire_due()
        tree.wake_up.check_and_clear()
        status = owner._tick_once(loop.time() - self.deadline)
        if owner.config.stop_on_completion and (status is SUCCESS or status is FAILURE):
            if not self.finished.done():
                self.finished.set_result(status)
            return
        period = self.period
        behind = loop.time() - (self.t0 + (self.k + 1) * period)
        if behind > 0:  # this tick ran past the next deadline: skip the missed ones
            missed = int(behind // period) + 1
            owner.stats.overruns += missed
            self.k += missed
        self._schedule()
