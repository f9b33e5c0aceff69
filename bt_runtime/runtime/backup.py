"""The data backup: bounded histories of recent sensor data and commands, queried by the tree.

Messages are appended to fixed-size ring buffers as they arrive (O(1), no allocation beyond
the tuple), so memory does not grow over a long run and queries never block the tick. The
backup's own task keeps derived knowledge that needs judgement over time, such as the last
pose that was taken while localization was healthy and the robot was not in contact.
"""

from __future__ import annotations

import asyncio
import sys
from collections import deque
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any

from .config import BackupConfig
from .messages import Contact, LocalizedPose, Pose2D, Twist

if TYPE_CHECKING:
    from .driver import RobotDriver
    from .supervisor import SystemSupervisor

DEFAULT_SIZE = 100


class RingBuffer:
    """The last ``maxlen`` (stamp, message) pairs of one stream, oldest first."""

    __slots__ = ("_items", "maxlen", "total")

    def __init__(self, maxlen: int):
        self._items: deque[tuple[float, Any]] = deque(maxlen=maxlen)
        self.maxlen = maxlen
        self.total = 0  # messages ever appended

    def append(self, stamp: float, message: Any) -> None:
        self._items.append((stamp, message))
        self.total += 1

    def __len__(self) -> int:
        return len(self._items)

    def __iter__(self) -> Iterator[tuple[float, Any]]:
        return iter(self._items)

    def latest(self) -> Any | None:
        return self._items[-1][1] if self._items else None

    def latest_stamped(self) -> tuple[float, Any] | None:
        return self._items[-1] if self._items else None

    def last_n(self, n: int) -> list[Any]:
        """The last ``n`` messages, oldest first."""
        items = self._items
        n = min(n, len(items))
        return [items[-k][1] for k in range(n, 0, -1)]

    def since(self, t: float) -> list[Any]:
        """Messages stamped at or after ``t``, oldest first (scans back from the newest)."""
        out = []
        for stamp, message in reversed(self._items):
            if stamp < t:
                break
            out.append(message)
        out.reverse()
        return out

    def since_stamped(self, t: float) -> list[tuple[float, Any]]:
        out = []
        for item in reversed(self._items):
            if item[0] < t:
                break
            out.append(item)
        out.reverse()
        return out

    def window(self, t0: float, t1: float) -> list[Any]:
        """Messages with ``t0 <= stamp < t1``, oldest first."""
        return [m for s, m in self.since_stamped(t0) if s < t1]

    def clear(self) -> None:
        self._items.clear()


class DataBackup:
    """Ring buffers per stream plus derived knowledge ("last good pose")."""

    def __init__(self, driver: RobotDriver, config: BackupConfig | None = None, *,
                 clock: Callable[[], float], supervisor: SystemSupervisor | None = None):
        self.driver = driver
        self.config = config or BackupConfig()
        self.clock = clock
        self.supervisor = supervisor
        self.buffers: dict[str, RingBuffer] = {}
        self._unsubscribe: list[Callable[[], None]] = []
        self.last_good_pose: tuple[float, Pose2D] | None = None

    # -- setup ---------------------------------------------------------------------------------
    def attach(self) -> None:
        """Subscribe to every configured stream except ``cmd_vel`` (the gate records that)."""
        for stream in self.config.sizes:
            if stream == "cmd_vel":
                continue
            self._unsubscribe.append(self.driver.subscribe(stream, self._recorder(stream)))

    def detach(self) -> None:
        for unsubscribe in self._unsubscribe:
            unsubscribe()
        self._unsubscribe.clear()

    def _recorder(self, stream: str) -> Callable[[Any], None]:
        buffer = self.buffer(stream)
        clock = self.clock

        def record(message: Any) -> None:
            buffer.append(clock(), message)

        return record

    def buffer(self, stream: str) -> RingBuffer:
        buffer = self.buffers.get(stream)
        if buffer is None:
            buffer = RingBuffer(self.config.sizes.get(stream, DEFAULT_SIZE))
            self.buffers[stream] = buffer
        return buffer

    def record(self, stream: str, message: Any, stamp: float | None = None) -> None:
        """Append a message (stamped with the receive time unless given)."""
        self.buffer(stream).append(self.clock() if stamp is None else stamp, message)

    # -- queries (non-blocking) ----------------------------------------------------------------
    def latest(self, stream: str) -> Any | None:
        buffer = self.buffers.get(stream)
        return buffer.latest() if buffer else None

    def last_n(self, stream: str, n: int) -> list[Any]:
        buffer = self.buffers.get(stream)
        return buffer.last_n(n) if buffer else []

    def since(self, stream: str, t: float) -> list[Any]:
        buffer = self.buffers.get(stream)
        return buffer.since(t) if buffer else []

    def window(self, stream: str, t0: float, t1: float) -> list[Any]:
        buffer = self.buffers.get(stream)
        return buffer.window(t0, t1) if buffer else []

    def age(self, stream: str) -> float | None:
        buffer = self.buffers.get(stream)
        item = buffer.latest_stamped() if buffer else None
        return None if item is None else self.clock() - item[0]

    def commands_since(self, t: float) -> list[tuple[float, Twist]]:
        """The velocities the gate sent to the base since ``t``, as (stamp, Twist), oldest first."""
        buffer = self.buffers.get("cmd_vel")
        return buffer.since_stamped(t) if buffer else []

    def recent_motion(self, duration: float, *, min_speed: float = 0.01) -> list[tuple[float, Twist]]:
        """The non-zero commands of the last ``duration`` seconds (to retrace them backwards)."""
        t0 = self.clock() - duration
        return [(s, c) for s, c in self.commands_since(t0) if abs(c.linear) >= min_speed or abs(c.angular) >= min_speed]

    def memory_bytes(self) -> int:
        """A rough size of what is held (messages counted shallowly)."""
        total = 0
        for buffer in self.buffers.values():
            total += sys.getsizeof(buffer._items)
            for _, message in buffer:
                total += sys.getsizeof(message) + 56
                ranges = getattr(message, "ranges", None)
                if ranges is not None:
                    total += getattr(ranges, "nbytes", 0)
        return total

    # -- the backup's own task -----------------------------------------------------------------
    async def run(self) -> None:
        loop = asyncio.get_running_loop()
        period = self.config.period
        start = loop.time()
        k = 0
        while True:
            k += 1
            await asyncio.sleep(max(0.0, start + k * period - loop.time()))
            self.update_derived()

    def update_derived(self) -> None:
        """Remember the newest pose taken while localization was healthy and not in contact."""
        pose_msg = self.latest("pose")
        if not isinstance(pose_msg, LocalizedPose):
            return
        contact = self.latest("bumper")
        if isinstance(contact, Contact) and contact.in_contact:
            return
        sup = self.supervisor
        if sup is not None and "localization" in sup.components and not sup.is_healthy("localization"):
            return
        self.last_good_pose = (pose_msg.stamp, pose_msg.pose)
