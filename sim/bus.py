"""A synchronous in-process publish/subscribe bus for the simulator's topics.

Publishing calls every subscriber immediately, in subscription order, on the event loop's
thread: cheap, and deterministic (no queues to reorder messages). The last message of each
topic is kept for late joiners and for ``latest``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any


class Bus:
    def __init__(self) -> None:
        # topic -> subscribers, a tuple replaced on (un)subscribe: publishing (~20 000 times per
        # simulated minute) iterates it without copying, and a callback that (un)subscribes
        # during a publish changes the next publish, not this one
        self._subscribers: dict[str, tuple[Callable[[Any], None], ...]] = {}
        self._latest: dict[str, Any] = {}
        self.counts: dict[str, int] = {}

    def subscribe(self, topic: str, callback: Callable[[Any], None]) -> Callable[[], None]:
        self._subscribers[topic] = (*self._subscribers.get(topic, ()), callback)

        def unsubscribe() -> None:
            subs = list(self._subscribers.get(topic, ()))
            if callback in subs:
                subs.remove(callback)
                self._subscribers[topic] = tuple(subs)

        return unsubscribe

    def publish(self, topic: str, message: Any) -> None:
        self._latest[topic] = message
        counts = self.counts
        counts[topic] = counts.get(topic, 0) + 1
        for callback in self._subscribers.get(topic, ()):
            callback(message)

    def latest(self, topic: str, default: Any = None) -> Any:
        return self._latest.get(topic, default)
