"""A campaign's progress: bar, runs done, ok, elapsed, ETA, runs per minute and the CPUs the
runs are spread over (the cluster's, for Ray), the same for every backend."""

from __future__ import annotations

import sys
import time


class Progress:
    """A one-line progress bar on a terminal (a line every 10 % otherwise)."""

    def __init__(self, total: int, stream=None, *, cpus: int | None = None, clock=time.perf_counter):
        self.total = total
        stream = sys.stderr if stream is None else stream  # the current stderr, not the one at import
        self.stream = stream
        self.cpus = cpus
        self.done = 0
        self.ok = 0
        self._clock = clock
        self.t0 = clock()
        self.tty = hasattr(stream, "isatty") and stream.isatty()
        self._last_decile = -1

    def line(self) -> str:
        elapsed = self._clock() - self.t0
        eta = elapsed / self.done * (self.total - self.done) if self.done else float("nan")
        rate = 60.0 * self.done / elapsed if elapsed > 0 else 0.0
        width = 30
        filled = int(width * self.done / self.total) if self.total else width
        cpus = f"  on {self.cpus} CPUs" if self.cpus else ""
        return (f"[{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} runs  {self.ok} ok  "
                f"{elapsed:5.1f} s  eta {eta:5.1f} s  {rate:5.1f} runs/min{cpus}")

    def update(self, success: bool) -> None:
        self.done += 1
        self.ok += int(success)
        line = self.line()
        if self.tty:
            self.stream.write("\r" + line)
            if self.done == self.total:
                self.stream.write("\n")
            self.stream.flush()
        elif self.done * 10 // max(self.total, 1) != self._last_decile:
            self._last_decile = self.done * 10 // max(self.total, 1)
            self.stream.write(line + "\n")
            self.stream.flush()
