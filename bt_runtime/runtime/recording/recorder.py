"""Wires a running ``AutonomyRuntime`` to a ``RecordPipeline``: what is recorded, and when.

Everything here runs on the event loop and only queues references (``pipeline.put``); the
messages are immutable once published, so the writer thread may convert them later. Sources:
the driver's sensor streams, the gate's output (``/cmd_vel``) and its source switches, the
navigation command and the tree's command (one topic per command source), the supervisor's
events and (every ``diagnostics_period_s``) every component's health, the tree's status
changes (``tree_log.py``), the static transforms, and
whatever the hooks add (the simulator's ground truth, faults and map).
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import structlog

from ..twist_mux import INPUT_STREAM
from .config import RecordingOptions
from .convert import KIND_TYPES, POSE_TYPE
from .hooks import RecordingHooks
from .pipeline import RecordPipeline
from .tree_log import tree_log

if TYPE_CHECKING:
    from ..app import AutonomyRuntime

log = structlog.get_logger("bt_runtime.recording")

# driver stream -> (converter kind, TopicNames field)
SENSOR_STREAMS = (("scan", "scan", "scan"), ("odom", "odom", "odom"), ("pose", "pose", "tf"),
                  ("imu", "imu", "imu"), ("battery", "battery", "battery"), ("plan", "plan", "plan"))
# virtual time: robot seconds between drains of the queue. With a live view 1 s (~180 messages): the
# writer's CPU ~10 % less than in drains of 0.25 s, each drain's set-up and cache misses spread over
# more messages, and a drain is one burst to foxglove-sdk's sending thread, whose cost is mostly per
# wake-up (~25 us) rather than per message (~1 us in a burst of 100), so its CPU halved; a virtual run
# goes ~40 robot seconds a wall second, so a viewer still sees it move ~40 times a second. A bag
# alone: 5 s (~900 items; its writer 25 -> 21 ms per 30 robot s against 1 s), or sooner when the
# queue holds a quarter of ``queue_size`` (looked at every DRAIN_CHECK_S)
LIVE_DRAIN_PERIOD_S = 1.0
# real time, a live view alone: wall seconds of writer work after a tick at most (a quarter of the tick
# period if that is less); drained every viewing period, ~10 items of ~20-40 us each, cold caches
LIVE_DRAIN_BUDGET_S = 0.002
DRAIN_PERIOD_S = 5.0
DRAIN_CHECK_S = 1.0
GATE_SOURCE_TOPIC = {"tree": "tree"}  # gate sources whose command the gate holds (no stream of their own)


class Recorder:
    def __init__(self, runtime: AutonomyRuntime, pipeline: RecordPipeline, options: RecordingOptions | None = None,
                 hooks: RecordingHooks | None = None):
        self.runtime = runtime
        self.pipeline = pipeline
        self.options = options or RecordingOptions()
        self.hooks = hooks or RecordingHooks()
        self.clock = runtime.clock
        self._unsubscribe: list[Callable[[], None]] = []
        self._task: asyncio.Task | None = None
        self._drain_task: asyncio.Task | None = None
        self._drain_next = -1e18  # a live view alone in real time: drained after a tick, every _drain_period
        self._drain_period = 0.1
        self._drain_budget = LIVE_DRAIN_BUDGET_S
        self.tree_log: Any = None  # tree_log.TreeStateLog or TreeTransitionLog
        # live view only ('states'): the tree's statuses sampled at the viewing rate, not after every tick
        self._tree_period = 0.0
        self._tree_next = -1e18
        self._tick_callback: Callable[[Any], None] | None = None
        self._last_output: tuple[float, float, str] | None = None
        self._repeat_s = self.options.cmd_vel_repeat_s
        self._last_output_t = -1e18
        self._switches_seen = 0
        self._map_version: int | None = None
        self._previous_on_output: Callable[..., Any] | None = None
        self.attached = False

    # -- wiring ------------------------------------------------------------------------------------
    def attach(self) -> None:
        """Subscribe to everything; call after ``load_tree`` and before ``runtime.start()``."""
        rt, topics, put, clock = self.runtime, self.options.topics, self.pipeline.put, self.clock
        if getattr(self.pipeline, "live", None) is not None:  # a live view: advertise every topic
            for topic, typename in self.topics().items():  # first in the queue: before any message
                put("advertise", topic, 0.0, typename)
        for stream, kind, field_name in SENSOR_STREAMS:
            topic = getattr(topics, field_name)
            if topic:
                self._subscribe(stream, kind, topic)
        nav_topic = self._source_topic("navigation")
        if nav_topic:
            self._subscribe("nav_cmd_vel", "command", nav_topic)
        for name in rt.gate.mux.inputs:  # twist_mux-style inputs (teleop...): every command each one sent
            topic = self._source_topic(name)
            if topic:
                self._subscribe(INPUT_STREAM + name, "command", topic)
        for spec in self.hooks.streams:
            if spec.pose_topic:
                self.pipeline.state.pose_topics[spec.topic] = spec.pose_topic
            self._subscribe(spec.stream, spec.kind, spec.topic, spec.select, spec.source)
        gate = rt.gate
        self._previous_on_output = gate.on_output
        self._switches_seen = len(gate.switches)
        gate.on_output = self._on_gate_output
        if topics.supervisor_events:
            rt.supervisor.add_listener(self._on_supervisor_event)
        if rt.tree is not None and topics.behavior_tree_log:
            self.tree_log = tree_log(self.options.tree_log, rt.tree, clock, self._put_tree_log)
            opts = self.options
            if getattr(self.pipeline, "bag", None) is None and opts.live_rate_hz > 0 and opts.tree_log == "states":
                self._tree_period = 1.0 / opts.live_rate_hz  # a pass over every node costs ~5-8 us a tick
            if rt.tick_loop is not None:  # one callback a tick, the cheapest that does the job
                self._tick_callback = self._on_tick_sampled if self._tree_period else self.tree_log.after_tick
                rt.tick_loop.on_tick.append(self._first_tick if rt.realtime else self._tick_callback)
        if topics.tf_static:
            put("tf_static", topics.tf_static, clock(), self.hooks.laser_offset)
        self._check_map()
        self._task = asyncio.get_running_loop().create_task(self._periodic(), name="recording")
        if getattr(self.pipeline, "on_loop", False):  # the writer's work is done here, between ticks
            self.pipeline.drain()  # now: the live view advertises every topic before the run starts
            if rt.realtime and rt.tick_loop is not None:  # a live view alone in real time: right after a tick
                self._drain_period = getattr(self.pipeline, "idle_wait_s", 0.1)
                self._drain_budget = min(LIVE_DRAIN_BUDGET_S, 0.25 / rt.config.tick.rate_hz)
                rt.tick_loop.on_tick.append(self._drain_after_tick)
            else:
                self._drain_task = asyncio.get_running_loop().create_task(self._drain(), name="recording.drain")
        self.attached = True

    def topics(self) -> dict[str, str]:
        """Every topic this recording may write, with its type (the live view advertises them at
        start, so a client can subscribe before the first message of each)."""
        t, rt = self.options.topics, self.runtime
        found = {getattr(t, field_name): KIND_TYPES[kind] for _s, kind, field_name in SENSOR_STREAMS}
        found[t.tf] = KIND_TYPES["tf_static"]
        sources = ["navigation", *GATE_SOURCE_TOPIC.values(), *rt.gate.mux.inputs]
        found.update({self._source_topic(name): KIND_TYPES["command"] for name in sources})
        found.update({t.cmd_vel: KIND_TYPES["command"], t.supervisor_events: KIND_TYPES["supervisor_event"],
                      t.gate_events: KIND_TYPES["gate_event"], t.diagnostics: KIND_TYPES["diagnostics"],
                      t.tf_static: KIND_TYPES["tf_static"]})
        if rt.tree is not None:
            found[t.behavior_tree_log] = KIND_TYPES["tree_log"]
        if self.hooks.map_source is not None:
            found[t.map] = KIND_TYPES["map"]
        found.update({spec.topic: KIND_TYPES[spec.kind] for spec in self.hooks.streams})
        found.update({spec.pose_topic: POSE_TYPE for spec in self.hooks.streams if spec.pose_topic})
        found.pop("", None)  # topics configured off
        return found

    def _subscribe(self, stream: str, kind: str, topic: str, select: Callable[[Any], bool] | None = None,
                   source: Callable[[str, Callable[[Any], None]], Callable[[], None]] | None = None) -> None:
        put, clock = self.pipeline.put, self.clock
        if select is None:
            def callback(msg: Any) -> None:
                put(kind, topic, clock(), msg)
        else:
            def callback(msg: Any) -> None:
                if select(msg):
                    put(kind, topic, clock(), msg)
        try:
            subscribe = source if source is not None else self.runtime.driver.subscribe
            self._unsubscribe.append(subscribe(stream, callback))
        except (KeyError, ValueError) as exc:  # a driver without this stream (e.g. no plan topic)
            log.info("recording_stream_unavailable", stream=stream, error=str(exc))

    def _source_topic(self, source: str) -> str:
        pattern = self.options.topics.cmd_vel_source
        return pattern.format(source=source) if pattern else ""

    def detach(self) -> None:
        if not self.attached:
            return
        self.attached = False
        for unsubscribe in self._unsubscribe:
            with contextlib.suppress(Exception):
                unsubscribe()
        self._unsubscribe.clear()
        rt = self.runtime
        if rt.gate.on_output == self._on_gate_output:
            rt.gate.on_output = self._previous_on_output
        if rt.tick_loop is not None:
            for callback in (self._first_tick, self._tick_callback, self._drain_after_tick):
                with contextlib.suppress(ValueError):
                    rt.tick_loop.on_tick.remove(callback)
        for task in (self._task, self._drain_task):
            if task is not None:
                task.cancel()
        if self.tree_log is not None:
            self.tree_log.close()
        self._diagnostics()

    # -- callbacks (event loop) --------------------------------------------------------------------
    def _on_gate_output(self, now: float, twist: Any, source: str) -> None:
        if self._previous_on_output is not None:
            self._previous_on_output(now, twist, source)
        key = (twist.linear, twist.angular, source)  # floats and a str: cheaper to compare than Twists
        if now - self._last_output_t < self._repeat_s and key == self._last_output:
            return  # the gate republishes its decision after every tick: keep changes and a heartbeat
        self._last_output, self._last_output_t = key, now
        put, topics = self.pipeline.put, self.options.topics
        if topics.cmd_vel:
            put("command", topics.cmd_vel, now, twist)
        own = GATE_SOURCE_TOPIC.get(source)  # gate inputs (teleop, joystick...) are recorded from their streams
        if own is not None:
            topic = self._source_topic(own)
            if topic:  # the source's own command, before the gate's limits
                put("command", topic, now, self.runtime.gate.decide(now)[1])
        switches = self.runtime.gate.switches
        if len(switches) > self._switches_seen and topics.gate_events:
            for switch in switches[self._switches_seen:]:
                put("gate_event", topics.gate_events, switch.t, switch)
        self._switches_seen = len(switches)

    def _on_supervisor_event(self, event: Any) -> None:
        if self.attached:  # the supervisor has no remove_listener: a detached recorder ignores it
            self.pipeline.put("supervisor_event", self.options.topics.supervisor_events, event.t, event)

    def _first_tick(self, status: Any) -> None:
        """Real time: the first tick gives the writer the ticks' phase (it keeps out of their
        way), then hands its place in ``on_tick`` to the tree log's callback."""
        rt = self.runtime  # the loop's clock is time.monotonic in real time
        self.pipeline.tick_guard = (rt.clock(), 1.0 / rt.config.tick.rate_hz)
        callbacks = rt.tick_loop.on_tick
        with contextlib.suppress(ValueError):
            callbacks[callbacks.index(self._first_tick)] = self._tick_callback
        self._tick_callback(status)

    def _drain_after_tick(self, _status: Any) -> None:
        """A live view alone in real time: the writer's work right after a tick, every viewing
        period, at most ``_drain_budget`` of it (the rest waits a period), so no tick waits."""
        now = self.clock()
        if now < self._drain_next:
            return
        self._drain_next = now + self._drain_period
        try:
            self.pipeline.drain(self._drain_budget)
        except Exception as exc:  # nothing the recording does may stop the ticks
            log.error("recording_drain_failed", error=repr(exc))

    def _on_tick_sampled(self, _status: Any) -> None:
        """Live view only: the tree's statuses at the viewing rate."""
        now = self.clock()
        if now >= self._tree_next:
            self._tree_next = now + self._tree_period
            self.tree_log.after_tick()

    def _put_tree_log(self, events: list[tuple[float, Any, Any, Any]]) -> None:
        self.pipeline.put("tree_log", self.options.topics.behavior_tree_log, self.clock(), events)

    # -- periodic (robot time) ---------------------------------------------------------------------
    async def _periodic(self) -> None:
        opts = self.options
        period = min(opts.diagnostics_period_s, opts.map_check_period_s)
        next_diag = self.clock()
        while True:
            now = self.clock()
            if now >= next_diag:
                self._diagnostics()
                next_diag = now + opts.diagnostics_period_s
            self._check_map()
            if self.tree_log is not None:
                self.tree_log.flush()  # status changes outside ticks (halts, restarts)
            await asyncio.sleep(period)

    async def _drain(self) -> None:
        """Virtual time only (the pipeline has no thread): write what is queued every
        ``LIVE_DRAIN_PERIOD_S`` robot seconds with a live view; a bag alone every ``DRAIN_PERIOD_S``,
        or sooner when a quarter of the queue is used. The loop's work takes no robot time there."""
        pipeline = self.pipeline
        if getattr(pipeline, "live", None) is not None:
            while True:
                await asyncio.sleep(LIVE_DRAIN_PERIOD_S)
                pipeline.drain()
        queue, early = pipeline.queue, pipeline.queue_size // 4
        checks = max(1, round(DRAIN_PERIOD_S / DRAIN_CHECK_S))
        k = 0
        while True:
            await asyncio.sleep(DRAIN_CHECK_S)
            k += 1
            if k >= checks or len(queue) >= early:
                k = 0
                pipeline.drain()

    def _diagnostics(self) -> None:
        topic = self.options.topics.diagnostics
        if not topic:
            return
        sup = self.runtime.supervisor
        rows = [(name, rec.kind, rec.state.value, sup.age(name), rec.restarts, rec.failures)
                for name, rec in sup.components.items()]
        self.pipeline.put("diagnostics", topic, self.clock(), rows)

    def _check_map(self) -> None:
        source, topic = self.hooks.map_source, self.options.topics.map
        if source is None or not topic:
            return
        version, snapshot = source()
        if version != self._map_version:
            self._map_version = version
            self.pipeline.put("map", topic, self.clock(), snapshot())
