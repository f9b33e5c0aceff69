"""The robot's clock (ROS time in message headers) seen from the event loop's monotonic clock.

The runtime times everything on its loop clock (monotonic: it never jumps, so timeouts stay
safe). A ROS 2 robot stamps its messages with ROS time: the system clock, or ``/clock`` in a
simulation. Throwing the header stamps away and stamping messages on receipt (as the driver did)
hid a driver that republishes old data, and made log lines impossible to line up with a bag or
with the robot's own logs. ``RobotClock`` estimates the offset ``robot time - loop time`` from
the headers it sees, so a header stamp becomes a loop-clock stamp (``to_loop``) and a loop time
becomes robot time (``to_robot``, used for the ``sim_time`` of log lines).

The estimate is the largest ``header - receipt`` seen recently: transport delay only makes a
stamp older, so the freshest sample is the best one, and a stream that republishes old stamps
cannot drag it back. The maximum is kept over two rotating windows, so when the robot's clock
steps back (a simulation restarted) the estimate follows within two windows. A sample more than
``jump`` seconds ahead of the estimate is taken only when a second stream confirms it (or the
same stream keeps it up for a window), so one message with a broken stamp cannot move
everybody's time. Zero stamps (a driver that never fills
its header) are not stamps: such messages keep their receipt time.
"""

from __future__ import annotations

import math


class RobotClock:
    """Offset between the robot's header stamps and the loop clock, learned from messages."""

    __slots__ = ("window", "jump", "offset", "_current", "_previous", "_window_start", "_pending",
                 "unstamped")

    def __init__(self, window: float = 1.0, jump: float = 1.0):
        self.window = window
        self.jump = jump
        self.offset: float | None = None  # robot time - loop time
        self._current = -math.inf  # largest sample of the running window
        self._previous = -math.inf  # ... and of the window before it
        self._window_start = -math.inf
        self._pending: tuple[str, float, float] | None = None  # unconfirmed jump: (stream, offset, since)
        self.unstamped: set[str] = set()  # streams seen with zero stamps

    def to_loop(self, stream: str, stamp: float, received: float) -> float:
        """The loop-clock time of a header ``stamp`` received at loop time ``received``.

        Never later than the receipt; a zero stamp gives the receipt time."""
        if stamp <= 0.0 or not math.isfinite(stamp):
            self.unstamped.add(stream)
            return received
        self._observe(stream, stamp - received, received)
        offset = self.offset
        return received if offset is None else min(received, stamp - offset)

    def to_robot(self, loop_time: float) -> float | None:
        """Robot time at a loop time, or None before the first stamped message."""
        return None if self.offset is None else loop_time + self.offset

    def _observe(self, stream: str, sample: float, now: float) -> None:
        offset = self.offset
        if offset is not None and sample > offset + self.jump:
            pending = self._pending
            if pending is None or abs(pending[1] - sample) > self.jump:
                self._pending = (stream, sample, now)
                return
            if pending[0] == stream and now - pending[2] < self.window:
                return
            self._pending = None  # a second stream agrees: the robot's clock did jump ahead
            self._current = self._previous = sample
            self._window_start = now
            self.offset = sample
            return
        self._pending = None
        if now - self._window_start >= self.window:
            self._previous, self._current = self._current, -math.inf
            self._window_start = now
        if sample > self._current:
            self._current = sample
        self.offset = max(self._current, self._previous)
