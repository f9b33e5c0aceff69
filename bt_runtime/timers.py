"""The tree's wake-up signal and timer queue.

BT.CPP runs timers on a separate thread that can halt a child at any instant. Here everything
runs on one thread: timers are due at a clock time and are fired by the tree at the start of
each tick and while the tree sleeps, so a timeout is observed at the first tick at or after its
deadline (with 100 Hz ticking: within 10 ms). The clock is the tree's clock (the event loop's
time under the runtime, so virtual time works), never ``time.time()``.
"""

from __future__ import annotations

import heapq
import itertools
import time
from collections.abc import Callable


class WakeUpSignal:
    """A latched flag any node can raise to make ``tick_once`` re-tick immediately."""

    __slots__ = ("_flag", "_listeners")

    def __init__(self) -> None:
        self._flag = False
        self._listeners: list[Callable[[], None]] = []

    def emit(self) -> None:
        self._flag = True
        for listener in self._listeners:
            listener()

    def check_and_clear(self) -> bool:
        flag = self._flag
        self._flag = False
        return flag

    @property
    def is_set(self) -> bool:
        return self._flag

    def add_listener(self, listener: Callable[[], None]) -> None:
        self._listeners.append(listener)

    def remove_listener(self, listener: Callable[[], None]) -> None:
        if listener in self._listeners:
            self._listeners.remove(listener)


class Timer:
    __slots__ = ("deadline", "callback", "cancelled")

    def __init__(self, deadline: float, callback: Callable[[], None]):
        self.deadline = deadline
        self.callback = callback
        self.cancelled = False

    def cancel(self) -> None:
        self.cancelled = True


class TimerQueue:
    """One-shot timers on a replaceable clock (seconds)."""

    __slots__ = ("clock", "_heap", "_counter")

    def __init__(self, clock: Callable[[], float] = time.monotonic):
        self.clock = clock
        self._heap: list[tuple[float, int, Timer]] = []
        self._counter = itertools.count()

    def add(self, delay_s: float, callback: Callable[[], None]) -> Timer:
        timer = Timer(self.clock() + delay_s, callback)
        heapq.heappush(self._heap, (timer.deadline, next(self._counter), timer))
        return timer

    def next_deadline(self) -> float | None:
        heap = self._heap
        while heap and heap[0][2].cancelled:
            heapq.heappop(heap)
        return heap[0][0] if heap else None

    def fire_due(self) -> int:
        """Run the callbacks of every timer whose deadline has passed; return how many ran."""
        heap = self._heap
        if not heap:
            return 0
        now = self.clock()
        fired = 0
        while heap and heap[0][0] <= now:
            _, _, timer = heapq.heappop(heap)
            if not timer.cancelled:
                timer.cancelled = True
                timer.callback()
                fired += 1
        return fired

    def __len__(self) -> int:
        return sum(1 for _, _, t in self._heap if not t.cancelled)
