"""``run``'s live progress line, and a console stream that log lines share with it.

The progress line is redrawn in place (carriage return, no newline). A log line written while
it is shown would be glued to its end and then overwritten; ``SharedConsole`` erases the
progress line before any other text and lets the next refresh draw it again below.
"""

from __future__ import annotations

import asyncio
import sys
import time
from typing import IO, Any

WIDTH = 160


class SharedConsole:
    """A text stream (stderr) shared by log lines and one in-place status line."""

    def __init__(self, stream: IO[str] = sys.stderr):
        self.stream = stream
        self.status_shown = False

    def write(self, text: str) -> int:
        if self.status_shown:
            self.stream.write("\r" + " " * WIDTH + "\r")
            self.status_shown = False
        return self.stream.write(text)

    def show_status(self, line: str) -> None:
        self.stream.write("\r" + line[:WIDTH].ljust(WIDTH))
        self.stream.flush()
        self.status_shown = True

    def end_status(self) -> None:
        """Keep the last status line on screen and move below it."""
        if self.status_shown:
            self.stream.write("\n")
            self.stream.flush()
            self.status_shown = False

    def flush(self) -> None:
        self.stream.flush()

    def isatty(self) -> bool:
        return hasattr(self.stream, "isatty") and self.stream.isatty()


class ProgressLine:
    """One status line, refreshed at most every ``interval`` wall seconds. Angles in radians."""

    def __init__(self, runtime: Any, console: SharedConsole, interval: float = 0.25):
        self.runtime = runtime
        self.console = console
        self.interval = interval
        self._last = 0.0
        self._wall0 = time.perf_counter()
        self._sim0 = runtime.clock()
        self.printed = False

    def line(self) -> str:
        rt = self.runtime
        sim_t = rt.clock() - self._sim0
        wall = time.perf_counter() - self._wall0
        rtf = sim_t / wall if wall > 0 else 0.0
        pose = rt.backup.latest("pose")
        pose_txt = (f"({pose.pose.x:+.2f} m, {pose.pose.y:+.2f} m, {pose.pose.yaw:+.2f} rad)"
                    if pose is not None else "(no pose)")
        bad = rt.supervisor.unhealthy()
        health = "OK" if not bad else "! " + ",".join(f"{n}:{rt.supervisor.health(n).value}" for n in bad)
        status = rt.tick_loop.status.name if rt.tick_loop else "-"
        return (f"t={sim_t:7.2f}s  x{rtf:6.1f}  pose={pose_txt}  tree={status:<8} gate={rt.gate.source:<7} "
                f"health={health}")

    def maybe_print(self) -> None:
        now = time.perf_counter()
        if now - self._last < self.interval:
            return
        self._last = now
        self.console.show_status(self.line())
        self.printed = True

    async def run(self) -> None:
        while True:
            await asyncio.sleep(0.05)  # loop time: cheap when idle, frequent enough in real time
            self.maybe_print()

    def finish(self) -> None:
        self.console.end_status()
