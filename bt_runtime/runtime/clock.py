"""Time for the whole process: the event loop's clock, virtual or real.

Every component reads time from ``loop.time()`` and never from ``time.time()``. In simulation
the loop runs on **virtual time**: when nothing is ready to run, instead of sleeping until the
next timer the loop jumps its clock straight to it. Every task (tick, supervisor, gate,
simulator) therefore sees one consistent clock, runs as fast as the CPU allows, and a run is
bit-for-bit reproducible: timers fire in the same order every time.

Real I/O still works on a virtual loop (a socket that is ready is served first), but time does
not wait for it; use a real-time loop when talking to processes outside the simulation.
"""

from __future__ import annotations

import asyncio
import selectors
from collections.abc import Awaitable, Callable
from typing import Any, TypeVar

T = TypeVar("T")


class _VirtualSelector(selectors.BaseSelector):
    """Wraps a real selector; a blocking select() advances virtual time instead of sleeping."""

    def __init__(self, loop: VirtualTimeLoop):
        self._real = selectors.DefaultSelector()
        self._loop = loop

    def register(self, fileobj, events, data=None):
        return self._real.register(fileobj, events, data)

    def unregister(self, fileobj):
        return self._real.unregister(fileobj)

    def modify(self, fileobj, events, data=None):
        return self._real.modify(fileobj, events, data)

    def get_key(self, fileobj):
        return self._real.get_key(fileobj)

    def get_map(self):
        return self._real.get_map()

    def close(self):
        self._real.close()

    def select(self, timeout=None):
        ready = self._real.select(0)
        if ready or timeout == 0:
            return ready
        if timeout is None:
            # Nothing scheduled: only outside I/O (or another thread) can wake us up.
            return self._real.select(None)
        self._loop._advance(timeout)
        return []


class VirtualTimeLoop(asyncio.SelectorEventLoop):
    """An asyncio loop whose clock jumps to the next timer when idle (fast-forward)."""

    def __init__(self, start: float = 0.0):
        self._virtual_now = float(start)
        super().__init__(_VirtualSelector(self))
        # asyncio pops timers due before now + resolution; keep that window tight and exact.
        self._clock_resolution = 1e-9

    def time(self) -> float:
        return self._virtual_now

    def _advance(self, dt: float) -> None:
        scheduled = self._scheduled  # CPython's timer heap: jump exactly to the next deadline
        if scheduled:
            target = scheduled[0]._when
            if target > self._virtual_now:
                self._virtual_now = target
                return
        self._virtual_now += dt

    @property
    def is_virtual(self) -> bool:
        return True


def is_virtual(loop: asyncio.AbstractEventLoop | None = None) -> bool:
    loop = loop or asyncio.get_running_loop()
    return isinstance(loop, VirtualTimeLoop)


def new_realtime_loop() -> asyncio.AbstractEventLoop:
    """A real-time loop whose timers fire within microseconds of their deadline.

    The default selector (epoll) rounds every timeout up to a whole millisecond, so a 100 Hz
    task wakes 0-1 ms late unless it spins before each deadline (a third of a core). select()
    takes microsecond timeouts: the same punctuality at the cost of a plain sleep. Its limit of
    1 024 file descriptors is far above what the runtime opens."""
    if hasattr(selectors, "SelectSelector"):
        return asyncio.SelectorEventLoop(selectors.SelectSelector())
    return asyncio.new_event_loop()


def new_loop(virtual: bool) -> asyncio.AbstractEventLoop:
    return VirtualTimeLoop() if virtual else new_realtime_loop()


def run(main: Awaitable[T] | Callable[[], Awaitable[T]], *, virtual: bool = True,
        debug: bool | None = None, signals: bool = False) -> T:
    """Run a coroutine on a fresh loop, virtual (default) or real-time. With ``signals``,
    SIGTERM/SIGINT/SIGHUP end it through its own cleanup (``shutdown.run_main``); leftover
    tasks never block the exit."""
    from .shutdown import run_main

    factory: Callable[[], Any] = VirtualTimeLoop if virtual else new_realtime_loop
    return run_main(main, loop_factory=factory, signals=signals, debug=debug)


class VirtualTimePolicy(asyncio.DefaultEventLoopPolicy):
    """Event-loop policy that hands out virtual-time loops (for pytest-asyncio fixtures)."""

    def new_event_loop(self) -> asyncio.AbstractEventLoop:
        return VirtualTimeLoop()


async def sleep_until(deadline: float, *, precise: bool = False, spin_window: float = 0.0015) -> None:
    """Sleep until ``loop.time() >= deadline``.

    With ``precise`` on a real-time loop, sleep to just before the deadline and then yield to
    the loop until it is reached: stock asyncio wakes ~1 ms late because of how it rounds
    timeouts, the final short yield brings that to microseconds. On a virtual loop time is
    exact and this is a plain sleep.
    """
    loop = asyncio.get_running_loop()
    now = loop.time()
    if deadline <= now:
        await asyncio.sleep(0)
        return
    if not precise or isinstance(loop, VirtualTimeLoop):
        await asyncio.sleep(deadline - now)
        return
    coarse = deadline - now - spin_window
    if coarse > 0:
        await asyncio.sleep(coarse)
    while loop.time() < deadline:
        await asyncio.sleep(0)
