"""Off the tick path: a bounded queue filled on the event loop, drained by one writer thread.

``put`` is all the loop pays per message: a length check and a deque append (no conversion,
no serialization, no I/O). When the queue is full the message is dropped and counted per
topic, never waited for. The thread converts (``convert``: CDR bytes for the high-rate types,
rosbags messages serialized once by ``types`` for the others) and logs the same bytes on the
topic's channel of each sink: the bag (every message, into its open segment) and the live
server (its own channels: only topics a client subscribed to, and the high-rate streams at
``live_rate_hz``, a viewing rate); every ``flush_interval_s`` wall seconds it closes the bag's
segment. A bag alone is written through ``bag_writer.py`` (one function per stream, counted
per batch), a live view item by item (``_write_one``). It works in slices of at most
``slice_s`` (0.5 ms) and then releases the GIL; in real time it also keeps out of the
millisecond before each tick deadline (``tick_guard``), so the tick finds the GIL free. It runs
at the loop's own OS priority (``writer_nice``): a lower one let the OS deschedule it while it
held the GIL.

On virtual time there is no thread (``start(on_loop=True)``): the recorder's task calls
``drain`` every few robot seconds (``recorder.DRAIN_PERIOD_S``), between ticks. Work on the
loop takes no robot time there (the virtual clock stands still while the loop runs), so no tick
is delayed, and it spares what a second thread costs a CPU-bound loop: every hand-over of the
GIL between the loop and the writer (measured: the writer's own CPU 2-3x a plain drain of the
same queue, and the loop's thread slower too).

Nor is there one for a live view alone in real time: the recorder drains right after a tick,
every viewing period, for at most ``recorder.LIVE_DRAIN_BUDGET_S`` (the rest waits for the next
period), so no tick waits for it. A thread cost twice the work itself there, in wake-ups and GIL
hand-overs (the writer 35-58 ms per 10 s with a client subscribed to everything, 19-30 ms on the
loop).
"""

from __future__ import annotations

import contextlib
import os
import threading
import time
from collections import deque
from typing import TYPE_CHECKING, Any

import structlog

from .bag_writer import BagWriter
from .convert import CONVERTERS, ConvertState
from .types import serialize

if TYPE_CHECKING:
    from .bag import Rosbag2Bag
    from .channels import ChannelSet
    from .live import FoxgloveLive

log = structlog.get_logger("bt_runtime.recording")

LATCHED_TYPES = {"nav_msgs/msg/OccupancyGrid"}
# kinds whose conversion has one output (on the item's topic) and keeps no state
SKIPPABLE = {"scan", "pose", "imu", "battery", "plan", "command", "tree_log", "diagnostics", "supervisor_event",
             "gate_event", "event"}
# the continuous streams the live view sends at a viewing rate, each ending on its latest message
# (the bag keeps every message): odometry and its /tf, map -> odom, imu, commands, ground truth
VIEWING_RATE_KINDS = ("odom", "pose", "imu", "command", "odometry")


class RecordPipeline:
    # the writer thread's OS niceness in real time: 0, the loop's own. At +10 a loaded machine
    # descheduled the writer in the middle of a segment close, which holds the GIL, and the loop's
    # thread waited for it (the longest close step 17-98 ms at nice +10, 2.5-5 ms at 0, with two
    # busy processes beside; bench/recording.py --realtime-configs baseline,record,record-nice10)
    writer_nice = 0

    def __init__(self, *, bag: Rosbag2Bag | None = None, live: FoxgloveLive | None = None,
                 state: ConvertState | None = None, queue_size: int = 20_000, flush_interval_s: float = 5.0,
                 latched_topics: tuple[str, ...] = (), slice_s: float = 0.0005, live_rate_hz: float = 0.0):
        self.bag = bag
        self.live = live
        # each sink's channels (a separate foxglove context each, so the live view can skip what the bag keeps)
        self.sinks: list[ChannelSet] = [x.channels for x in (bag, live) if x is not None]
        period_ns = int(round(1e9 / live_rate_hz)) if live_rate_hz > 0 else 0
        # the viewing rate: with a bag, applied by the writer to the converted messages (ns of robot
        # time); live view only, applied by ``put`` (loop seconds), so the writer never sees the rest
        live_only = bag is None and live is not None
        self.live_period_ns = dict.fromkeys(VIEWING_RATE_KINDS, period_ns) if period_ns and not live_only else {}
        self.live_period_s = (dict.fromkeys(VIEWING_RATE_KINDS, 1.0 / live_rate_hz)
                              if period_ns and live_only else {})
        self._put_next: dict[tuple[str, str], float] = {}
        self._put_now = -1e18  # the latest loop time put saw (live view only)
        if self.live_period_s:
            self.put = self._put_viewing  # type: ignore[method-assign]
        self._live_next: dict[tuple[str, str], int] = {}  # (kind, topic) -> earliest log time of the next live send
        self._live_now = 0  # the latest log time seen (robot time, ns)
        # (kind, topic) -> the latest message the viewing rate held back (live only: the queued item; with a
        # bag: its outputs' bytes)
        self._held: dict[tuple[str, str], Any] = {}
        self._outbox: list[tuple[str, bytes, int]] = []  # (topic, data, log time) for the live view, sent in batches
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
        self._flush_step_s = 0.002  # the room a step of a segment close is given between ticks (real time)
        self.max_flush_step_s = 0.0  # the longest step seen (wall): what a tick could have waited without the guard
        # real time: wall seconds the writer thread sleeps when the queue is empty; with a live view, the
        # viewing period (at most 0.1 s), also the period of the drains of a live view alone, on the loop:
        # each wake-up of the writer and of foxglove-sdk's sending thread costs more than the few messages
        # it carries (per 10 s with a client: writer 90 -> 48 ms, SDK threads 46 -> 28 ms against 0.02 s),
        # and a viewer at 10 Hz waits at most one period more
        self.idle_wait_s = min(0.1, 1.0 / live_rate_hz) if live is not None and live_rate_hz > 0 else 0.02
        # a bag alone: written by one function per stream (bag_writer.py), not item by item through _write_one
        self._bag_writer = BagWriter(bag, self.state, self._add_channel, self.written) \
            if bag is not None and live is None else None

    # -- the loop's side ---------------------------------------------------------------------------
    def put(self, kind: str, topic: str, t: float, payload: Any) -> None:
        queue = self.queue
        if len(queue) >= self.queue_size:
            self.dropped[topic] = self.dropped.get(topic, 0) + 1
            return
        queue.append((kind, topic, t, payload))

    def _put_viewing(self, kind: str, topic: str, t: float, payload: Any) -> None:
        """``put`` of a live view without a bag: a message of a continuous stream within the
        viewing period of the last one queued is held back (the latest only, sent by the writer
        when the period passes with nothing newer) instead of queued. Cheaper than queueing it:
        the writer's handling of an item costs several times this check."""
        period = self.live_period_s.get(kind)
        if period is not None:
            if t > self._put_now:
                self._put_now = t
            key = (kind, topic)
            nxt = self._put_next
            if t < nxt.get(key, -1e18):
                self._held[key] = (kind, topic, t, payload)
                return
            nxt[key] = t + period - 1e-6  # a microsecond's slack: 0.1 + 0.2 > 0.3 in floats
            self._held.pop(key, None)
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

    def drain(self, budget_s: float = 0.0) -> None:
        """Write everything queued, here and now (on the loop, between ticks), and close the bag's
        segment when one is due. ``budget_s``: stop after that much wall time and leave the rest
        for the next drain (a live view alone in real time, right after a tick)."""
        started = time.thread_time()
        queue = self.queue
        if len(queue) > self.max_queued:
            self.max_queued = len(queue)
        if self._bag_writer is not None:
            self._write_bag(queue)
        elif budget_s > 0:
            write, clock = self._write_one, time.perf_counter
            end = clock() + budget_s
            while queue and clock() < end:
                write(*queue.popleft())
        else:
            write = self._write_one
            while queue:
                write(*queue.popleft())
        if self.live is not None:
            self.flush_live()
        self._flush_when_due()
        self.cpu_s += time.thread_time() - started

    def _flush_when_due(self) -> None:
        now = time.monotonic()
        if now < self._next_flush or self.bag is None:
            return
        self._next_flush = now + self.flush_interval_s
        try:  # the close holds the GIL (foxglove-sdk's MCAP close, then the metadata): in real time each
            self._clear_of_tick()  # step starts just after a tick when it would not fit before the next
            started = time.perf_counter()
            wrote = self.bag.close_segment()
            self._took(time.perf_counter() - started)
            if wrote:
                self._clear_of_tick()
                started = time.perf_counter()
                self.bag.write_metadata()
                self._took(time.perf_counter() - started)
        except Exception as exc:
            self.errors += 1
            log.error("recording_flush_failed", error=repr(exc))

    def _took(self, seconds: float) -> None:
        """A step of a segment close took ``seconds`` (wall): the estimate the next one is given
        room for (the longest recent step, decaying)."""
        self.max_flush_step_s = max(self.max_flush_step_s, seconds)
        self._flush_step_s = max(seconds, 0.8 * self._flush_step_s)

    def _clear_of_tick(self) -> None:
        """Real time (a writer thread): wait for the next tick to pass when the time left before
        its deadline is less than a close step needs (``_flush_step_s``, plus a millisecond)."""
        guard = self.tick_guard
        if guard is None or self._thread is None:
            return
        origin, period = guard
        need = self._flush_step_s + 0.001
        if need >= period - 0.002:  # never fits between ticks: waiting would not help
            return
        to_next = period - (time.monotonic() - origin) % period
        if to_next < need:
            time.sleep(to_next + 0.0015)  # past the deadline and the tick itself

    # -- the writer thread -------------------------------------------------------------------------
    def _run(self) -> None:
        if self.writer_nice:
            with contextlib.suppress(AttributeError, OSError):  # a lower priority than the loop's thread
                os.setpriority(os.PRIO_PROCESS, threading.get_native_id(), self.writer_nice)
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
                if self._bag_writer is not None:
                    self._write_bag(queue, end, clock)
                else:
                    while queue and clock() < end:
                        self._write_one(*queue.popleft())
                if self._outbox:
                    self.flush_live()
                time.sleep(0)  # hand the GIL to the event loop if it is waiting
            if self.live is not None:
                self.flush_live()
            self.cpu_s = time.thread_time()
            if stopping:
                return
            self._flush_when_due()
            self._stop.wait(self.idle_wait_s)

    def _write_bag(self, queue: deque, deadline: float = 0.0, clock: Any = None) -> None:
        writer = self._bag_writer
        before = writer.errors
        writer.write(queue, deadline, clock)
        self.errors += writer.errors - before

    def _write_one(self, kind: str, topic: str, t: float, payload: Any, held: bool = False) -> None:
        """Convert one queued item and log its outputs to the bag and (when due) the live view.
        ``held``: an item the viewing rate held back, sent now (live view only)."""
        bag, live = self.bag, self.live
        try:
            if kind == "advertise":  # a channel made before its first message (payload: its type)
                self._add_channel(topic, payload)
                return
            t_ns = max(0, int(round(self.state.robot(t) * 1e9)))  # log time: robot time
            due = True  # the live view may have this item's outputs (the viewing rate says no to most)
            if self.live_period_ns and not held:  # with a bag (live only: put applied the rate)
                if t_ns > self._live_now:
                    self._live_now = t_ns
                period = self.live_period_ns.get(kind)
                if period:
                    key = (kind, topic)
                    if t_ns < self._live_next.get(key, -1):
                        due = False
                    else:
                        self._live_next[key] = t_ns + period
                        self._held.pop(key, None)
            if bag is None:  # live view only: convert nothing a client will not get
                if not self._wanted(kind, topic):
                    if kind == "odom":
                        self.state.odom_pose = (payload.pose.x, payload.pose.y, payload.pose.yaw)  # for map -> odom
                    return
            elif bag.idle:
                bag.open_segment()
            kept: list[tuple[str, bytes, int]] | None = None if due or live is None else []
            written = self.written
            for name, typename, msg in CONVERTERS[kind](self.state, topic, t, payload):
                if name not in self.sinks[0].loggers:
                    self._add_channel(name, typename)
                to_live = due and live is not None and self._live_wants(name)
                if bag is None and not to_live:
                    continue
                data = msg if type(msg) is bytes else serialize(msg, typename)
                if bag is not None:
                    bag.count(name, t_ns)
                    bag.channels.loggers[name](data, t_ns, None)
                if to_live:
                    self._outbox.append((name, data, t_ns))
                elif kept is not None:
                    kept.append((name, data, t_ns))
                written[name] = written.get(name, 0) + 1
            if kept is not None:  # with a bag: the bytes are made, keep them for a later live send
                self._held[(kind, topic)] = kept
        except Exception as exc:
            self.errors += 1
            if self.errors <= 5:
                log.error("recording_message_failed", kind=kind, topic=topic, error=repr(exc))

    def _send_held(self) -> None:
        """The viewing rate's trailing edge: a held-back message whose period has passed with
        nothing newer on its stream goes live now, so a stream that stops shows its last value."""
        held = self._held
        if not held:
            return
        if self.live_period_s:  # live only: items held by put (loop seconds), converted now
            now_s, nxt_s = self._put_now, self._put_next
            for key in list(held):  # the loop may add to it meanwhile (real time)
                if nxt_s.get(key, 0.0) > now_s:
                    continue
                item = held.pop(key, None)
                if item is not None:
                    nxt_s[key] = now_s + self.live_period_s[key[0]]
                    self._write_one(*item, held=True)
            return
        now, nxt = self._live_now, self._live_next
        for key in [k for k in held if nxt[k] <= now]:
            value = held.pop(key)
            nxt[key] = now + self.live_period_ns[key[0]]
            self._outbox.extend(m for m in value if self._live_wants(m[0]))

    def flush_live(self) -> None:
        """Send what the live view has waiting: the held-back latest messages now due, and the
        outbox. Back to back, so the server's sending thread wakes once for the lot: one message
        at a time between conversions woke it for each (measured: ~45 us of CPU in each thread
        per message alone, ~1-2 us in a burst of 20)."""
        if self._held:
            self._send_held()
        out = self._outbox
        if not out:
            return
        self._outbox = []
        live = self.live
        loggers = live.channels.loggers
        for name, data, t_ns in out:
            loggers[name](data, t_ns, None)
        live.sent(out)

    def _live_wants(self, topic: str) -> bool:
        """A latched topic always (kept for later subscribers), others when a client subscribed."""
        channels = self.live.channels
        return topic in channels.latched or channels.channels[topic].has_sinks()

    def _wanted(self, kind: str, topic: str) -> bool:
        """Live view only: may a client get any output of this item (else it is not converted)?"""
        if kind in SKIPPABLE:
            return not self._unwatched(topic)
        if kind == "odom":
            return not (self._unwatched(topic) and self._unwatched(self.state.tf_topic))
        if kind == "odometry":
            pose_topic = self.state.pose_topics.get(topic)
            return not (self._unwatched(topic) and (not pose_topic or self._unwatched(pose_topic)))
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
