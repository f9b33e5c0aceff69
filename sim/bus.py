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
        self._subscribers: dict[str, list[Callable[[Any], None]]] = {}
        self._latest: dict[str, Any] = {}
        self.counts: dict[str, int] = {}

    def subscribe(self, topic: str, callback: Callable[[Any], None]) -> Callable[[], None]:
        subs = self._subscribers.setdefault(topic, [])
        subs.append(callback)

        def unsubscribe() -> None:
            if callback in subs:
                subs.remove(callback)

        return unsubscribe

    def publish(self, topic: str, message: Any) -> None:
        self._latest[topic] = message
        self.counts[topic] = self.counts.get(topic, 0) + 1
        for callback in tuple(self._subscribers.get(topic, ())):
            callback(message)

    def latest(self, topic: str, default: Any = None) -> Any:
        return self._latest.get(topic, default)
