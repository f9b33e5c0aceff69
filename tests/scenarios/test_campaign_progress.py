"""The progress line every backend shows: bar, runs, ok, elapsed, ETA, runs/min and CPUs."""

from __future__ import annotations

import io

from sim.scenarios.progress import Progress


class _Clock:
    def __init__(self):
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def test_progress_shows_rate_eta_and_the_cpus():
    clock, out = _Clock(), io.StringIO()
    progress = Progress(4, out, cpus=16, clock=clock)
    clock.now += 30.0
    progress.update(True)
    clock.now += 30.0
    progress.update(False)
    line = out.getvalue().splitlines()[-1]
    assert "2/4 runs" in line and "1 ok" in line
    assert "2.0 runs/min" in line  # 2 runs in 60 s
    assert "eta  60.0 s" in line
    assert line.endswith("on 16 CPUs")
