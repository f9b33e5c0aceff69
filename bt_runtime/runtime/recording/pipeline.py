"""Off the tick path: a bounded queue filled on the event loop, drained by one writer thread.

``put`` is all the loop pays per message: a length check and a deque append (no conversion,
no serialization, no I/O). When the queue is full the message is dropped and counted per
topic, never waited for. The thread converts (``convert``: CDR bytes for the high-rate types,
rosbags messages serialized once by ``types`` for the others) and logs the bytes on the topic's channel, which feeds the bag's open segment and the live server;
every ``flush_interval_s`` wall seconds it closes the bag's segment. It works in slices of at
most ``slice_s`` (0.5 ms) and then releases the GIL; in real time it also keeps out of the
millisecond before each tick deadline (``tick_guard``), so the tick finds the GIL free.
"""

from __future__ import annotations

import contextlib
import os
import threading
import time
from collections import deque
from typing import TYPE_CHECKING, Any

import structlog

from .convert import CONVERTERS, ConvertState
from .types import serialize

if TYPE_CHECKING:
    from .bag import Rosbag2Bag
    from .channels import ChannelSet
    from .live import FoxgloveLive

log = structlog.get_logger("bt_runtime.recording")

LATCHED_TYPES = {"nav_msgs/msg/OccupancyGrid"}
# kinds whose conversion has one output (on the item's topic) and keeps no state
SKIPPABLE = {"scan", "imu", "battery", "plan", "command", "tree_log", "diagnostics", "supervisor_event",
             "gate_event", "event"}


class RecordPipeline:
    def __init__(self, channels: ChannelSet, *, bag: Rosbag2Bag | None = None, live: FoxgloveLive | None = None,
                 state: ConvertState | None = None, queue_size: int = 20_000, flush_interval_s: float = 5.0,
                 latched_topics: tuple[str, ...] = (), slice_s: float = 0.0005):
        self.channels = channels
        self.bag = bag
        self.live = live
        self.state = state or ConvertState()
        self.queue_size = queue_size
        self.flush_interval_s = flush_interval_s
        self.latched_topics = set(latched_topics)
        self.slice_s = slice_s
        self.queue: deque[tuple[str, str, float, Any]] = deque()
        self.dropped: dict[str, int] = {}
        self.written: dict[str, int] = {}
        self.errors = 0
        self.max_queued = 0
        self.cpu_s = 0.0  # the writer thread's CPU time
        # (first tick's monotonic time, tick period) in real time: the writer works between ticks
        self.tick_guard: tuple[float, float] | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    # -- the loop's side ---------------------------------------------------------------------------
    def put(self, kind: str, topic: str, t: float, payload: Any) -> None:
        queue = self.queue
        if len(queue) >= self.queue_size:
            self.dropped[topic] = self.dropped.get(topic, 0) + 1
            return
        queue.append((kind, topic, t, payload))

    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name="recording-writer", daemon=True)
        self._thread.start()

    def stop(self, timeout: float = 60.0) -> None:
        """Write what is queued, close the bag and the server. Blocks (call it when the run is over)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout)
            if self._thread.is_alive():
                log.error("recording_writer_stuck", queued=len(self.queue))
                return
        for closer in (self.bag, self.live):
            if closer is None:
                continue
            try:
                closer.close()
            except Exception as exc:
                log.error("recording_close_failed", sink=type(closer).__name__, error=repr(exc))

    # -- the writer thread -------------------------------------------------------------------------
    def _run(self) -> None:
        with contextlib.suppress(AttributeError, OSError):  # lower priority than the loop's thread
            os.setpriority(os.PRIO_PROCESS, threading.get_native_id(), 10)
        queue = self.queue
        clock = time.perf_counter
        slice_s = self.slice_s
        next_flush = time.monotonic() + self.flush_interval_s
        while True:
            stopping = self._stop.is_set()
            n = len(queue)
            if n > self.max_queued:
                self.max_queued = n
            while queue:
                guard = self.tick_guard
                if guard is not None:  # real time: keep out of the way of the next tick
                    origin, period = guard
                    to_next = period - (time.monotonic() - origin) % period
                    if to_next < slice_s + 0.0005:
                        time.sleep(to_next + 0.0015)  # past the deadline and the tick itself
                        continue
                end = clock() + slice_s
                while queue and clock() < end:
                    self._write_one(*queue.popleft())
                time.sleep(0)  # hand the GIL to the event loop if it is waiting
            self.cpu_s = time.thread_time()
            if stopping:
                return
            now = time.monotonic()
            if now >= next_flush and self.bag is not None:
                try:
                    self.bag.flush()
                except Exception as exc:
                    self.errors += 1
                    log.error("recording_flush_failed", error=repr(exc))
                next_flush = now + self.flush_interval_s
            self._stop.wait(0.02)

    def _write_one(self, kind: str, topic: str, t: float, payload: Any) -> None:
        bag = self.bag
        try:
            if kind == "advertise":  # a channel made before its first message (payload: its type)
                if topic not in self.channels.channels:
                    self._add_channel(topic, payload)
                return
            if bag is None:
                if kind in SKIPPABLE and self._unwatched(topic):
                    return  # live view only: nothing to convert for a topic nobody watches
                if kind == "odom" and self._unwatched(topic) and self._unwatched(self.state.tf_topic):
                    self.state.odom_pose = (payload.pose.x, payload.pose.y, payload.pose.yaw)  # for map -> odom
                    return
            elif bag.idle:
                bag.open_segment()
            t_ns = max(0, int(round(self.state.robot(t) * 1e9)))  # log time: robot time
            loggers, written = self.channels.loggers, self.written
            for name, typename, msg in CONVERTERS[kind](self.state, topic, t, payload):
                logger = loggers.get(name)
                if logger is None:
                    self._add_channel(name, typename)
                    logger = loggers[name]
                if bag is None and self._unwatched(name):
                    continue  # live view only, and nobody subscribed to this topic
                data = msg if type(msg) is bytes else serialize(msg, typename)
                if bag is not None:
                    bag.count(name, t_ns)
                logger(data, t_ns, None)
                if self.live is not None:
                    self.live.sent(name, t_ns, data)
                written[name] = written.get(name, 0) + 1
        except Exception as exc:
            self.errors += 1
            if self.errors <= 5:
                log.error("recording_message_failed", kind=kind, topic=topic, error=repr(exc))

    def _add_channel(self, topic: str, typename: str) -> None:
        latched = topic in self.latched_topics or typename in LATCHED_TYPES
        self.channels.add(topic, typename, latched=latched)

    def _unwatched(self, topic: str) -> bool:
        """Live view only: a topic with a channel, no subscriber, and nothing to keep for later ones."""
        channel = self.channels.channels.get(topic)
        return channel is not None and not channel.has_sinks() and topic not in self.channels.latched
