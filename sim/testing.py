"""Small helpers for tests and scenarios: run on virtual time, record topics."""

from __future__ import annotations

from collections.abc import Awaitable, Callable, Iterable
from typing import Any, TypeVar

from bt_runtime.runtime.clock import run

from .simulator import Simulator

T = TypeVar("T")


def run_virtual(main: Callable[[], Awaitable[T]]) -> T:
    """Run a coroutine function on a fresh VirtualTimeLoop (clock starts at 0)."""
    return run(main, virtual=True)


class Recorder:
    """Keeps every message of some topics: ``rec["scan"]`` is the list of scans."""

    def __init__(self, sim: Simulator, topics: Iterable[str]) -> None:
        self.messages: dict[str, list[Any]] = {}
        self._unsubs = []
        for topic in topics:
            box: list[Any] = []
            self.messages[topic] = box
            self._unsubs.append(sim.subscribe(topic, box.append))

    def __getitem__(self, topic: str) -> list[Any]:
        return self.messages[topic]

    def stamps(self, topic: str) -> list[float]:
        return [m.stamp for m in self.messages[topic]]

    def between(self, topic: str, t0: float, t1: float) -> list[Any]:
        return [m for m in self.messages[topic] if t0 <= m.stamp < t1]

    def close(self) -> None:
        for u in self._unsubs:
            u()
