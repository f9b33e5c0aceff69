"""Ros2Driver: a ROS 2 robot behind the runtime's driver interface, over DDS (no ROS install).

Sensor topics are read by Cyclone DDS listeners on Cyclone's threads; each sample is stamped
there with the loop clock (its receive time) and handed to the event loop with
``call_soon_threadsafe`` (see ``dds.py``). On the loop it is checked, converted to the
runtime's message dataclasses and passed to the stream's subscribers. A message with a header
keeps its own time: the header stamp (ROS time) is mapped onto the loop clock by
``robot_clock`` (so republished old data looks old to the supervisor), and ``robot_time`` gives
log lines the robot's time. Malformed or absurd messages are dropped and counted per stream
(``dropped``); the header stamp of the last good message of each stream is kept in
``header_stamps`` (ROS time, seconds).

Only the decision gate calls ``send_velocity``; it writes the robot's ``cmd_vel``. Nav2's
controller must therefore publish elsewhere (``cmd_vel_nav`` by default), which this driver
reads as the ``nav_cmd_vel`` stream. See docs/ros2.md.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import time
from collections import defaultdict
from collections.abc import Callable
from typing import Any

import structlog

from ..bringup import BringupError, BringupPlan, transition
from ..messages import ComponentInfo, ComponentState, RobotInfo, Twist
from . import dds, idl, sensor_wire
from .cmd_encoder import twist_encoder
from .config import Qos, Ros2Config
from .convert import Converter, Drop
from .diagnostics_encoder import encode_diagnostic_array
from .navigation import Ros2Navigation
from .robot_clock import RobotClock

log = structlog.get_logger("bt_runtime.ros2")


def _qos(q: Qos) -> dds.QosProfile:
    return dds.QosProfile(reliable=q.reliability == "reliable", transient_local=q.durability == "transient_local",
                          depth=q.depth)


T = idl.Transition
RESTART_SEQUENCE = {  # from the current primary state back to active
    idl.State.PRIMARY_STATE_ACTIVE: (T.TRANSITION_DEACTIVATE, T.TRANSITION_CLEANUP, T.TRANSITION_CONFIGURE,
                                     T.TRANSITION_ACTIVATE),
    idl.State.PRIMARY_STATE_INACTIVE: (T.TRANSITION_CLEANUP, T.TRANSITION_CONFIGURE, T.TRANSITION_ACTIVATE),
    idl.State.PRIMARY_STATE_UNCONFIGURED: (T.TRANSITION_CONFIGURE, T.TRANSITION_ACTIVATE),
}
TRANSITION_LABELS = {T.TRANSITION_CONFIGURE: "configure", T.TRANSITION_CLEANUP: "cleanup",
                     T.TRANSITION_ACTIVATE: "activate", T.TRANSITION_DEACTIVATE: "deactivate"}
GET_STATE_RESEND = 0.5  # s: a get_state without reply is sent again (bring-up, restarts; not the polls)


class Ros2Driver:
    """A ROS 2 robot over DDS; implements ``RobotDriver``."""

    name = "ros2"

    def __init__(self, config: Ros2Config | None = None):
        self.config = config or Ros2Config()
        self.conv = Converter(self.config)
        self.navigation = Ros2Navigation(self)
        self.node: dds.DdsNode | None = None
        self.loop: asyncio.AbstractEventLoop | None = None
        self._subscribers: dict[str, list[Callable[[Any], None]]] = defaultdict(list)
        self.received: dict[str, int] = defaultdict(int)
        self.dropped: dict[str, int] = defaultdict(int)
        self.drop_reasons: dict[str, str] = {}
        self.header_stamps: dict[str, float] = {}
        self.robot_clock = RobotClock()  # header stamps (ROS time) -> loop-clock stamps
        self.latest: dict[str, Any] = {}
        self.last_seen: dict[str, float] = {}
        self._readers: dict[str, dds.Reader] = {}
        self._cmd_writer: Any = None
        self._cmd_type: type | None = None
        self._cmd_encode = twist_encoder()  # (linear, angular) -> the command's CDR bytes (set at start)
        self._lifecycle: dict[str, tuple[dds.ServiceClient, dds.ServiceClient]] = {}  # by component
        self._nodes: dict[str, tuple[dds.ServiceClient, dds.ServiceClient]] = {}  # by lifecycle node
        self.lifecycle_states: dict[str, int] = {}
        self._restarting: set[str] = set()
        self._poller: asyncio.Task | None = None
        self.sent = 0
        self.zeros_held = 0  # repeated zeros not written (config.topics.cmd_vel.zero_repeat_period)
        self._zero_written_at: float | None = None  # time.monotonic() of the last zero on the wire
        self._diagnostics_writer: Any = None
        self._zone_state_writer: Any = None
        self.send_errors = 0
        self.goal_server: Any = None  # action_server.GoalActionServer once serve_goals() ran
        self._mux_topics: tuple[list, list] = ([], [])  # the gate's extra inputs and locks
        self._hold = False  # hold_until_tick

    # -- lifecycle -------------------------------------------------------------------------------
    async def start(self) -> None:
        if self.node is not None:
            return
        cfg = self.config
        self.loop = asyncio.get_running_loop()
        uri = cfg.cyclonedds_uri or (dds.loopback_config() if cfg.loopback_only and
                                     not os.environ.get("CYCLONEDDS_URI") else None)
        self.node = node = dds.DdsNode(cfg.domain_id, loop=self.loop, namespace=cfg.namespace, cyclonedds_uri=uri,
                                       service_mapping=cfg.service_mapping)
        t = cfg.topics
        conv = self.conv
        specs: list[tuple[str, Any, type, Callable]] = [
            ("scan", t.scan, idl.LaserScan, conv.scan), ("imu", t.imu, idl.Imu, conv.imu),
            ("odom", t.odom, idl.Odometry, conv.odom), ("pose", t.pose, idl.PoseWithCovarianceStamped, conv.pose),
            ("battery", t.battery, idl.BatteryState, conv.battery)]
        if t.bumper is not None:
            specs.append(("bumper", t.bumper, idl.Bool if t.bumper.type == "bool" else idl.Vector3Stamped,
                          conv.bumper_bool if t.bumper.type == "bool" else conv.bumper_vector))
        if t.nav_cmd_vel is not None:
            nav_stamped = t.nav_cmd_vel.stamped
            specs.append(("nav_cmd_vel", t.nav_cmd_vel, idl.TwistStamped if nav_stamped else idl.Twist,
                          (lambda m, now: conv.twist(m.twist, now)) if nav_stamped else conv.twist))
        wire = {"imu": conv.imu_values, "odom": conv.odom_values, "scan": conv.scan_values}  # (sensor_wire.py)
        for stream, topic, msg_type, convert in specs:
            if topic is None:
                continue
            decode = sensor_wire.DECODERS[stream]() if stream in wire and dds.ddspy_take is not None else None
            handler = self._stream_handler(stream, wire[stream] if decode else convert, wire=decode is not None)
            self._readers[stream] = node.subscription(topic.name, msg_type, _qos(topic.qos), handler,
                                                      at_tick=stream in cfg.deliver_at_tick, decode=decode)
        node.set_hold(self._hold)
        self._open_mux_topics()
        cmd = t.cmd_vel
        self._cmd_type = idl.TwistStamped if cmd.stamped else idl.Twist
        self._cmd_writer = node.publisher(cmd.name, self._cmd_type, _qos(cmd.qos))
        self._cmd_encode = twist_encoder(cmd.stamped, cmd.frame_id)
        for name, comp in cfg.components.items():
            if comp.lifecycle_node:
                self._lifecycle[name] = self._node_clients(comp.lifecycle_node)
        self.navigation.attach(node)
        polled = [n for n, c in cfg.components.items() if c.heartbeat == "lifecycle"]
        if polled:
            self._poller = self.loop.create_task(self._poll_lifecycles(polled), name="ros2.lifecycle_poll")
        log.info("ros2_driver_started", domain_id=cfg.domain_id, namespace=cfg.namespace or "/",
                 streams=sorted(self._readers), cmd_vel=node.fq(cmd.name), stamped=cmd.stamped)

    async def stop(self) -> None:
        if self.node is None:
            return
        await self.navigation.close()
        if self.goal_server is not None:
            self.goal_server.close()
            self.goal_server = None
        if self._poller is not None:
            self._poller.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._poller
            self._poller = None
        node, self.node = self.node, None
        self._cmd_writer = None
        for stream in [s for s in self._readers if s.startswith(("cmd_vel_input/", "lock/"))]:
            del self._readers[stream]  # closed with the node; reopened by the next start
        self._nodes.clear()
        self._lifecycle.clear()
        node.close()
        log.info("ros2_driver_stopped", received=dict(self.received), dropped=self.dropped_counts())

    def serve_goals(self, intake: Any) -> None:
        """Serve NavigateToPose and the goal topic for the runtime's goal intake (config.goals)."""
        cfg = self.config.goals
        if self.node is None or not cfg.enabled or self.goal_server is not None:
            return
        from .action_server import GoalActionServer

        intake.feedback_period = 1.0 / cfg.feedback_hz
        self.goal_server = GoalActionServer(self.node, intake, action=cfg.action, topic=cfg.topic,
                                            map_frame=self.config.navigation.map_frame)

    # -- delivery at the tick (config.deliver_at_tick) --------------------------------------------
    def hold_until_tick(self, hold: bool) -> None:
        """While ``hold``: the ``deliver_at_tick`` streams wait for ``deliver_held()`` (the tick
        loop calls it before each tick) instead of waking the loop per message. The runtime
        holds while its real-time tick task runs."""
        self._hold = hold
        if self.node is not None:
            self.node.set_hold(hold)

    def deliver_held(self) -> None:
        """Deliver the messages waiting for the tick (on the loop, before the tree ticks)."""
        node = self.node
        if node is not None:
            node.deliver_held()

    # -- the gate's extra inputs and locks (twist_mux) --------------------------------------------
    def open_command_inputs(self, inputs: list, locks: list) -> None:
        """Read the gate's extra velocity inputs (geometry_msgs/Twist, or TwistStamped when the
        input says ``stamped``) and its locks (std_msgs/Bool) from their topics, as the streams
        ``cmd_vel_input/<name>`` (Twist; non-finite or absurd commands are dropped and counted)
        and ``lock/<name>`` (bool). Inputs: best-effort readers, so any publisher matches (a
        stream at joystick rate needs no retransmission). Locks: reliable readers, as twist_mux's
        (SystemDefaultsQoS), so a single ``true`` on a lossy link is not lost; a best-effort
        lock publisher does not match (``lock_publishers()`` shows it)."""
        self._mux_topics = (list(inputs), list(locks))
        if self.node is not None:
            self._open_mux_topics()

    def _open_mux_topics(self) -> None:
        from ..twist_mux import INPUT_STREAM, LOCK_STREAM

        node, conv = self.node, self.conv
        qos = dds.QosProfile(reliable=False, depth=10)
        inputs, locks = self._mux_topics
        for entry in inputs:
            stream = INPUT_STREAM + entry.name
            if stream in self._readers:
                continue
            convert = (lambda m, now: conv.twist(m.twist, now)) if entry.stamped else conv.twist
            self._readers[stream] = node.subscription(entry.topic, idl.TwistStamped if entry.stamped else idl.Twist,
                                                      qos, self._stream_handler(stream, convert))
        for lock in locks:
            stream = LOCK_STREAM + lock.name
            if stream not in self._readers:
                self._readers[stream] = node.subscription(lock.topic, idl.Bool, dds.DEFAULT,
                                                          self._stream_handler(stream, lambda m, now: bool(m.data)))
        if inputs or locks:
            log.info("ros2_gate_inputs", inputs={e.name: node.fq(e.topic) for e in inputs},
                     locks={lk.name: node.fq(lk.topic) for lk in locks})

    def lock_publishers(self) -> dict[str, int]:
        """Matched publishers per gate lock (0: nobody can lock it, e.g. a best-effort writer)."""
        from ..twist_mux import LOCK_STREAM

        return {s[len(LOCK_STREAM):]: r.matched_writers() for s, r in self._readers.items()
                if s.startswith(LOCK_STREAM)}

    # -- streams ---------------------------------------------------------------------------------
    def _stream_handler(self, stream: str, convert: Callable[[Any, float], Any], *,
                        wire: bool = False) -> Callable[[list, float], None]:
        """Check, convert and hand out one stream's samples. ``wire``: the samples are
        ``(sec, nanosec, values)`` read from the bytes (``sensor_wire.py``) and ``convert`` takes
        the values."""
        subscribers = self._subscribers

        robot_clock = self.robot_clock

        received, header_stamps, latest, last_seen = self.received, self.header_stamps, self.latest, self.last_seen
        to_loop = robot_clock.to_loop

        def on_samples(samples: list, now: float) -> None:
            for raw in samples:
                received[stream] += 1
                if wire:
                    sec, nanosec, raw = raw
                    header = True
                    header_stamp = sec + nanosec * 1e-9  # (idl.Time.to_sec)
                    stamp = to_loop(stream, header_stamp, now)
                else:
                    header = getattr(raw, "header", None)
                    stamp = now
                    if header is not None:
                        time_ = header.stamp
                        header_stamp = time_.sec + time_.nanosec * 1e-9  # (idl.Time.to_sec)
                        stamp = to_loop(stream, header_stamp, now)
                try:
                    msg = convert(raw, stamp)
                except Drop as why:
                    self.count_drop(stream, str(why))
                    continue
                except Exception as exc:  # anything odd in a message is the message's fault
                    self.count_drop(stream, repr(exc))
                    continue
                if header is not None:
                    header_stamps[stream] = header_stamp
                latest[stream] = msg
                last_seen[stream] = now
                callbacks = subscribers.get(stream)
                if callbacks:
                    for callback in tuple(callbacks):
                        callback(msg)

        return on_samples

    async def _poll_lifecycles(self, names: list[str]) -> None:
        """Heartbeats of servers without a data stream (Nav2's): their lifecycle node answers
        get_state with 'active' -> a ``ComponentState.ACTIVE`` message on ``lifecycle/<name>``."""
        period = 1.0 / self.config.lifecycle.poll_hz
        timeout = min(self.config.lifecycle.transition_timeout, 0.9 * period)
        loop = self.loop
        start = loop.time()
        k = 0

        async def poll(name: str) -> None:
            state = await self.get_lifecycle_state(name, timeout=timeout)
            if state == idl.State.PRIMARY_STATE_ACTIVE:
                stream = f"lifecycle/{name}"
                self.last_seen[stream] = loop.time()
                for callback in tuple(self._subscribers.get(stream, ())):
                    callback(ComponentState.ACTIVE)

        while True:
            await asyncio.gather(*(poll(n) for n in names), return_exceptions=True)
            k += 1
            await asyncio.sleep(max(0.0, start + k * period - loop.time()))

    def count_drop(self, stream: str, reason: str) -> None:
        """One dropped message of ``stream`` (the navigation client counts bad costmaps here too)."""
        self.dropped[stream] += 1
        if self.drop_reasons.get(stream) != reason:
            log.warning("ros2_message_dropped", stream=stream, reason=reason, count=self.dropped[stream])
        self.drop_reasons[stream] = reason

    def robot_time(self, loop_time: float) -> float:
        """The robot's ROS time at a loop-clock time: learned from header stamps, and before the
        first stamped message the system clock (ROS time unless the robot runs on sim time)."""
        robot = self.robot_clock.to_robot(loop_time)
        if robot is None:  # (from any thread: the recording's writer asks too; the loop's clock is monotonic)
            now = self.loop.time() if self.loop is not None else time.monotonic()
            robot = loop_time + (time.time() - now)
        return robot

    def dropped_counts(self) -> dict[str, int]:
        """Dropped messages per stream: failed validation + failed deserialisation."""
        counts = dict(self.dropped)
        for stream, reader in self._readers.items():
            if reader.malformed:
                counts[stream] = counts.get(stream, 0) + reader.malformed
        return counts

    def subscribe(self, stream: str, callback: Callable[[Any], None]) -> Callable[[], None]:
        self._subscribers[stream].append(callback)

        def unsubscribe() -> None:
            with contextlib.suppress(ValueError):
                self._subscribers[stream].remove(callback)

        return unsubscribe

    def send_velocity(self, linear: float, angular: float) -> None:
        """Write the command; a zero repeating the last one written within
        ``zero_repeat_period`` stays off the wire (a standing base needs no 100 Hz stream of
        zeros; writing them was the largest single cost of an idle runtime's event loop), but
        is still announced on ``cmd_vel_out``: the command in force is zero either way."""
        written = self._zero_written_at
        if (written is not None and linear == 0.0 and angular == 0.0
                and time.monotonic() - written < self.config.topics.cmd_vel.zero_repeat_period):
            self.zeros_held += 1
            out = Twist(0.0, 0.0)
        elif self._write_cmd(linear, angular):
            out = Twist(float(linear), float(angular))
        else:
            return
        callbacks = self._subscribers.get("cmd_vel_out")
        if callbacks:
            for callback in tuple(callbacks):
                callback(out)

    def publish_diagnostics(self, diagnostics: list, now: float) -> None:
        """Component health (``runtime.diagnostics.ComponentDiagnostic``) on the diagnostics topic."""
        topic = self.config.topics.diagnostics
        if topic is None or self.node is None:
            return
        if self._diagnostics_writer is None:
            self._diagnostics_writer = self.node.publisher(topic, idl.DiagnosticArray, dds.DEFAULT)
        data = encode_diagnostic_array(time.time(), "", ((d.level, d.name, d.message, d.hardware_id, d.values)
                                                         for d in diagnostics))
        if not dds.write_cdr(self._diagnostics_writer, data):  # (packed at once: diagnostics_encoder.py)
            self._diagnostics_writer.write(idl.DiagnosticArray(header=idl.Header(stamp=idl.Time.now(), frame_id=""), status=[
                idl.DiagnosticStatus(level=d.level, name=d.name, message=d.message, hardware_id=d.hardware_id,
                                     values=[idl.KeyValue(key=k, value=v) for k, v in d.values])
                for d in diagnostics]))

    def publish_collision_monitor_state(self, action: str, zone: str) -> None:
        """The gate's safety-zone state as collision_monitor publishes it (on every change)."""
        topic = self.config.topics.collision_monitor_state
        if topic is None or self.node is None:
            return
        if self._zone_state_writer is None:
            self._zone_state_writer = self.node.publisher(topic, idl.CollisionMonitorState, dds.DEFAULT)
        code = {"stop": 1, "slowdown": 2, "approach": 3, "limit": 4}.get(action, 0)
        self._zone_state_writer.write(idl.CollisionMonitorState(action_type=code, polygon_name=zone))

    def emergency_zero(self) -> None:
        """Write a zero ``cmd_vel`` from any thread (Cyclone's writers are thread-safe); the
        ``cmd_vel_out`` subscribers hear of it on the loop."""
        if self._write_cmd(0.0, 0.0):
            loop = self.loop
            if loop is not None and not loop.is_closed():
                with contextlib.suppress(RuntimeError):  # the loop closed meanwhile
                    loop.call_soon_threadsafe(self._announce_zero)

    def _announce_zero(self) -> None:
        for callback in tuple(self._subscribers.get("cmd_vel_out", ())):
            callback(Twist(0.0, 0.0))

    def _write_cmd(self, linear: float, angular: float) -> bool:
        writer = self._cmd_writer
        if writer is None:
            return False
        try:  # the bytes packed at once (cmd_encoder.py); objects for a writer that is not Cyclone's
            if not dds.write_cdr(writer, self._cmd_encode(float(linear), float(angular))):
                twist = idl.Twist(linear=idl.Vector3(float(linear), 0.0, 0.0),
                                  angular=idl.Vector3(0.0, 0.0, float(angular)))
                if self._cmd_type is idl.TwistStamped:
                    twist = idl.TwistStamped(header=idl.Header(stamp=idl.Time.now(),
                                                               frame_id=self.config.topics.cmd_vel.frame_id),
                                             twist=twist)
                writer.write(twist)
            self.sent += 1
            self._zero_written_at = time.monotonic() if linear == 0.0 and angular == 0.0 else None
        except Exception as exc:
            self.send_errors += 1
            if self.send_errors == 1 or self.send_errors % 1000 == 0:
                log.error("ros2_cmd_vel_failed", error=repr(exc), errors=self.send_errors)
            return False
        return True

    # -- components ------------------------------------------------------------------------------
    def _timeout(self, name: str) -> float:
        rate = self.config.components[name].rate_hz
        return max(1.0, 2.5 / rate) if rate > 0 else 1.0

    def components(self) -> list[ComponentInfo]:
        infos = []
        for name, comp in self.config.components.items():
            streams = tuple(s for s in comp.streams
                            if s in self._readers or s.startswith("lifecycle/") or self.node is None)
            infos.append(ComponentInfo(name=name, kind=comp.kind, streams=streams,
                                       restartable=comp.lifecycle_node is not None,
                                       expected_rate_hz=comp.rate_hz, state=self.component_state(name),
                                       extra={"lifecycle_node": comp.lifecycle_node,
                                              "depends_on": tuple(comp.depends_on)}))
        return infos

    def robot_info(self) -> RobotInfo:
        """The robot's size, limits and power model, from the config's ``robot`` section."""
        robot = self.config.robot
        return RobotInfo(**robot.model_dump()) if robot is not None else RobotInfo()

    def component_state(self, name: str) -> ComponentState:
        comp = self.config.components.get(name)
        if comp is None:
            return ComponentState.UNKNOWN
        if name in self._restarting:
            return ComponentState.STARTING
        seen = [self.last_seen[s] for s in comp.streams if s in self.last_seen]
        if not seen:
            return ComponentState.UNKNOWN
        now = self.loop.time() if self.loop is not None else 0.0
        return ComponentState.ACTIVE if now - max(seen) <= self._timeout(name) else ComponentState.INACTIVE

    # -- lifecycle nodes (bring-up and restarts; see runtime/bringup.py) -------------------------
    def _node_clients(self, node_name: str) -> tuple[dds.ServiceClient, dds.ServiceClient]:
        """get_state / change_state clients of one lifecycle node (one pair per node)."""
        key = node_name.rstrip("/")
        clients = self._nodes.get(key)
        if clients is None:
            clients = self._nodes[key] = (
                dds.ServiceClient(self.node, key + "/get_state", idl.GetState_Request, idl.GetState_Response),
                dds.ServiceClient(self.node, key + "/change_state", idl.ChangeState_Request,
                                  idl.ChangeState_Response))
        return clients

    def bringup_plan(self) -> BringupPlan | None:
        """Nav2's servers to configure and activate at start (``lifecycle.bringup``)."""
        cfg = self.config.lifecycle
        if self.node is None or not cfg.bringup.enabled or not cfg.bringup.node_names:
            return None
        by_node = {c.lifecycle_node.rstrip("/"): name for name, c in self.config.components.items()
                   if c.lifecycle_node}
        nodes = tuple(n.rstrip("/") for n in cfg.bringup.node_names)
        return BringupPlan(nodes, {n: by_node[n] for n in nodes if n in by_node},
                           cfg.bringup.service_timeout, cfg.transition_timeout)

    async def node_state(self, node: str, timeout: float) -> int | None:
        if self.node is None:
            return None
        try:  # re-sent while unanswered: a reply the node dropped does not cost the whole timeout
            response = await self._node_clients(node)[0].call(idl.GetState_Request(), timeout,
                                                              resend=GET_STATE_RESEND)
        except dds.ServiceError:
            return None
        return int(response.current_state.id)

    def node_found(self, node: str) -> bool:
        """The node's get_state service is discovered (both directions matched), answered or not."""
        return self.node is not None and self._node_clients(node)[0].ready()

    async def change_node_state(self, node: str, transition: int, timeout: float) -> bool | None:
        if self.node is None:
            return None
        request = idl.ChangeState_Request(transition=T(transition, TRANSITION_LABELS.get(transition, "")))
        try:
            response = await self._node_clients(node)[1].call(request, timeout)
        except dds.ServiceError:
            return None
        return bool(response.success)

    async def get_lifecycle_state(self, name: str, timeout: float | None = None) -> int | None:
        """The component's lifecycle state id (None: no answer or no lifecycle node)."""
        clients = self._lifecycle.get(name)
        if clients is None:
            return None
        try:
            response = await clients[0].call(idl.GetState_Request(), timeout or self.config.lifecycle.transition_timeout)
        except dds.ServiceError:
            return None
        self.lifecycle_states[name] = int(response.current_state.id)
        return self.lifecycle_states[name]

    async def restart(self, name: str) -> bool:
        """deactivate -> cleanup -> configure -> activate (from whatever primary state it is
        in) through the component's lifecycle services, each transition checked with get_state
        as nav2_lifecycle_manager does; False without lifecycle node, if a service does not
        answer or a transition fails."""
        comp = self.config.components.get(name)
        if name not in self._lifecycle or comp is None:
            log.warning("ros2_restart_unsupported", component=name, reason="no lifecycle node configured")
            return False
        node = comp.lifecycle_node.rstrip("/")
        timeout = self.config.lifecycle.transition_timeout
        self._restarting.add(name)
        try:
            state = await self.get_lifecycle_state(name)
            if state is not None and state > idl.State.PRIMARY_STATE_FINALIZED:  # mid-transition: let it settle
                await asyncio.sleep(min(timeout, 0.5))
                state = await self.get_lifecycle_state(name)
            sequence = RESTART_SEQUENCE.get(state) if state is not None else None
            if sequence is None:
                log.warning("ros2_restart_failed", component=name, reason=f"lifecycle state {state}")
                return False
            for step in sequence:
                try:
                    await transition(self, node, step, timeout, self.loop.time)
                except BringupError as exc:
                    log.warning("ros2_restart_failed", component=name, transition=TRANSITION_LABELS[step],
                                reason=str(exc))
                    return False
            self.lifecycle_states[name] = idl.State.PRIMARY_STATE_ACTIVE
            log.info("ros2_component_restarted", component=name)
            return True
        finally:
            self._restarting.discard(name)
