"""Off the tick path: a bounded queue filled on the event loop, drained by one writer thread.

``put`` is all the loop pays per message: a length check and a deque append (no conversion,
no serialization, no I/O). When the queue is full the message is dropped and counted per
topic, never waited for. The thread converts (``convert``: CDR bytes for the high-rate types,
rosbags messages serialized once by ``types`` for the others) and logs the same bytes on the
topic's channel of each sink: the bag (every message, into its open segment) and the live
server (its own channels: only topics a client subscribed to, and the high-rate streams at
``live_rate_hz``, a viewing rate); every ``flush_interval_s`` wall seconds it closes the bag's
segment. It works in slices of at
most ``slice_s`` (0.5 ms) and then releases the GIL; in real time it also keeps out of the
millisecond before each tick deadline (``tick_guard``), so the tick finds the GIL free.

On virtual time there is no thread (``start(on_loop=True)``): the recorder's task calls
``drain`` every few robot tenths of a second, between ticks. Work on the loop takes no robot
time there (the virtual clock stands still while the loop runs), so no tick is delayed, and it
spares what a second thread costs a CPU-bound loop: every hand-over of the GIL between the
loop and the writer (measured: the writer's own CPU 2-3x a plain drain of the same queue, and
the loop's thread slower too).
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
# the high-rate streams the live view sends at a viewing rate (the bag keeps every message)
VIEWING_RATE_KINDS = ("odom", "imu", "odometry")


class RecordPipeline:
    def __init__(self, *, bag: Rosbag2Bag | None = None, live: FoxgloveLive | None = None,
                 state: ConvertState | None = None, queue_size: int = 20_000, flush_interval_s: float = 5.0,
                 latched_topics: tuple[str, ...] = (), slice_s: float = 0.0005, live_rate_hz: float = 0.0):
        self.bag = bag
        self.live = live
        # each sink's channels (a separate foxglove context each, so the live view can skip what the bag keeps)
        self.sinks: list[ChannelSet] = [x.channels for x in (bag, live) if x is not None]
        period_ns = int(round(1e9 / live_rate_hz)) if live_rate_hz > 0 else 0
        self.live_period_ns = dict.fromkeys(VIEWING_RATE_KINDS, period_ns) if period_ns else {}
        self._live_next: dict[tuple[str, str], int] = {}  # (kind, topic) -> earliest log time of the next live send
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
        self.on_loop = False  # virtual time: drained by the owner on the loop, no thread
        self._next_flush = 0.0

    # -- the loop's side ---------------------------------------------------------------------------
    def put(self, kind: str, topic: str, t: float, payload: Any) -> None:
        queue = self.queue
        if len(queue) >= self.queue_size:
            self.dropped[topic] = self.dropped.get(topic, 0) + 1
            return
        queue.append((kind, topic, t, payload))

    def start(self, *, on_loop: bool = False) -> None:
        """A writer thread, or (``on_loop``, for virtual time) none: the owner calls ``drain``."""
        self.on_loop = on_loop
        self._next_flush = time.monotonic() + self.flush_interval_s
        if on_loop:
            return
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
        elif self.on_loop:
            self.drain()
        for closer in (self.bag, self.live):
            if closer is None:
                continue
            try:
                closer.close()
            except Exception as exc:
                log.error("recording_close_failed", sink=type(closer).__name__, error=repr(exc))

    def drain(self) -> None:
        """Write everything queued, here and now (virtual time: called on the loop between ticks),
        and close the bag's segment when one is due."""
        started = time.thread_time()
        queue = self.queue
        if len(queue) > self.max_queued:
            self.max_queued = len(queue)
        write = self._write_one
        while queue:
            write(*queue.popleft())
        self._flush_when_due()
        self.cpu_s += time.thread_time() - started

    def _flush_when_due(self) -> None:
        now = time.monotonic()
        if now < self._next_flush or self.bag is None:
            return
        self._next_flush = now + self.flush_interval_s
        try:
            self.bag.flush()
        except Exception as exc:
            self.errors += 1
            log.error("recording_flush_failed", error=repr(exc))

    # -- the writer thread -------------------------------------------------------------------------
    def _run(self) -> None:
        with contextlib.suppress(AttributeError, OSError):  # lower priority than the loop's thread
            os.setpriority(os.PRIO_PROCESS, threading.get_native_id(), 10)
        queue = self.queue
        clock = time.perf_counter
        slice_s = self.slice_s
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
            self._flush_when_due()
            self._stop.wait(0.02)

    def _write_one(self, kind: str, topic: str, t: float, payload: Any) -> None:
        bag, live = self.bag, self.live
        try:
            if kind == "advertise":  # a channel made before its first message (payload: its type)
                self._add_channel(topic, payload)
                return
            t_ns = max(0, int(round(self.state.robot(t) * 1e9)))  # log time: robot time
            checked = False  # _live_due already said yes (for the only output)
            if bag is None:  # live view only: convert nothing a client will not get
                if kind in SKIPPABLE and topic in live.channels.channels:
                    if not self._live_due(kind, topic, t_ns):
                        return
                    checked = True
                if kind == "odom" and self._unwatched(topic) and self._unwatched(self.state.tf_topic):
                    self.state.odom_pose = (payload.pose.x, payload.pose.y, payload.pose.yaw)  # for map -> odom
                    return
            elif bag.idle:
                bag.open_segment()
            written = self.written
            for name, typename, msg in CONVERTERS[kind](self.state, topic, t, payload):
                if name not in self.sinks[0].loggers:
                    self._add_channel(name, typename)
                to_live = live is not None and (checked or self._live_due(kind, name, t_ns))
                if bag is None and not to_live:
                    continue
                data = msg if type(msg) is bytes else serialize(msg, typename)
                if bag is not None:
                    bag.count(name, t_ns)
                    bag.channels.loggers[name](data, t_ns, None)
                if to_live:
                    live.channels.loggers[name](data, t_ns, None)
                    live.sent(name, t_ns, data)
                written[name] = written.get(name, 0) + 1
        except Exception as exc:
            self.errors += 1
            if self.errors <= 5:
                log.error("recording_message_failed", kind=kind, topic=topic, error=repr(exc))

    def _live_due(self, kind: str, topic: str, t_ns: int) -> bool:
        """Send this message to the live view: a latched topic always (kept for later
        subscribers), others when a client subscribed, the high-rate kinds at most at the viewing rate."""
        channels = self.live.channels
        if topic in channels.latched:
            return True
        if not channels.channels[topic].has_sinks():
            return False
        period = self.live_period_ns.get(kind)
        if period:
            key = (kind, topic)
            if t_ns < self._live_next.get(key, -1):
                return False
            self._live_next[key] = t_ns + period
        return True

    def _add_channel(self, topic: str, typename: str) -> None:
        latched = topic in self.latched_topics or typename in LATCHED_TYPES
        for channels in self.sinks:
            channels.add(topic, typename, latched=latched)

    def _unwatched(self, topic: str) -> bool:
        """Live view only: a topic with a channel, no subscriber, and nothing to keep for later ones."""
        channels = self.live.channels
        channel = channels.channels.get(topic)
        return channel is not None and not channel.has_sinks() and topic not in channels.latched
