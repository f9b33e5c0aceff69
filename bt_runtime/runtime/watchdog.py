"""The dead-man that does not need the event loop: an OS thread that zeroes the base.

The decision gate's own dead-man runs on the event loop, so a node that blocks the loop
(``time.sleep`` in a tick, a long computation) would silence it too and leave the last
command standing. This watchdog lives on its own thread: the tick loop refreshes it before
every tick (through ``DecisionGate.heartbeat``); when the base was last told to move and no
refresh came within the dead-man timeout, it calls the driver's thread-safe
``emergency_zero()``. It fires once per stall and re-arms on the next refresh.

Sends are serialised with the gate's through ``lock``: once the watchdog has sent zero, a
command from the loop can only follow it after a fresh refresh. Limits: the thread needs the
GIL, which a running Python thread hands over every ``sys.getswitchinterval()`` (5 ms); C code
holding the GIL for longer delays the zero by as much. Real-time loops only: on a virtual-time
loop a real-time stall stops simulated time too, and a zero from another thread would break
reproducibility.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

import structlog

log = structlog.get_logger("bt_runtime.watchdog")


@dataclass(slots=True, frozen=True)
class WatchdogTrip:
    refreshed: float  # time.monotonic() of the last refresh before the stall
    fired: float  # time.monotonic() when the zero was handed to the driver

    @property
    def latency(self) -> float:
        """Seconds from the last refresh to the zero (dead-man timeout + wake-up delay)."""
        return self.fired - self.refreshed


class LoopWatchdog:
    """See the module docstring. ``zero`` must be safe to call from any thread."""

    def __init__(self, zero: Callable[[], None], timeout: float, *, clock: Callable[[], float] = time.monotonic):
        if not timeout > 0:
            raise ValueError(f"watchdog timeout must be > 0 s, got {timeout!r}")
        self._zero = zero
        self.timeout = float(timeout)
        self._clock = clock
        self.lock = threading.Lock()  # held while anyone sends to the base
        self._wake = threading.Condition(threading.Lock())
        self._refreshed = clock()
        self._moving = False
        self._stopping = False
        self._thread: threading.Thread | None = None
        self.trips: list[WatchdogTrip] = []
        self.errors = 0

    def start(self) -> None:
        if self._thread is not None:
            return
        self._stopping = False
        self._refreshed = self._clock()
        self._thread = threading.Thread(target=self._run, name="bt_runtime.watchdog", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        thread, self._thread = self._thread, None
        if thread is None:
            return
        with self._wake:
            self._stopping = True
            self._wake.notify()
        thread.join(timeout=1.0)

    @property
    def running(self) -> bool:
        return self._thread is not None

    def refresh(self) -> None:
        """The event loop is alive (called before every tick; a float store, no lock)."""
        self._refreshed = self._clock()

    def note_sent(self, moving: bool) -> None:
        """The loop just sent a command (call with ``lock`` held)."""
        self._moving = moving

    def _run(self) -> None:
        while True:
            with self._wake:
                if self._stopping:
                    return
                now = self._clock()
                deadline = self._refreshed + self.timeout
                if now >= deadline:
                    self._trip(now)
                    wait = self.timeout  # any later refresh has its deadline after this wake-up
                else:
                    wait = deadline - now
                self._wake.wait(wait)

    def _trip(self, now: float) -> None:
        with self.lock:
            if not self._moving or self._clock() < self._refreshed + self.timeout:
                return
            try:
                self._zero()
            except Exception as exc:  # keep watching; a driver that cannot send is logged
                self.errors += 1
                log.error("watchdog_zero_failed", error=repr(exc))
                return
            self._moving = False
            fired = self._clock()
        trip = WatchdogTrip(self._refreshed, fired)
        self.trips.append(trip)
        log.warning("watchdog_zero", stalled_s=round(now - trip.refreshed, 4), latency_s=round(trip.latency, 4))
