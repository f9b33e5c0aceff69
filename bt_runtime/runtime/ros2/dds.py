"""ROS 2 over plain DDS: topics, services and actions as rmw_cyclonedds and rcl_action lay them out.

* A ROS topic ``/a/b`` is the DDS topic ``rt/a/b``; a service ``/s`` is the pair
  ``rq/sRequest`` (client -> server) and ``rr/sReply``; an action ``/x`` is the services
  ``/x/_action/send_goal``, ``/x/_action/get_result``, ``/x/_action/cancel_goal`` and the
  topics ``/x/_action/feedback`` and ``/x/_action/status`` (transient local, depth 1).
* Service samples carry ``{uint64 guid, int64 seq}`` before the fields (``idl.service_wire``);
  the client puts its request writer's instance handle in ``guid`` and keeps only replies that
  carry it back. Client and server mark their endpoints with ``clientid=...;`` /
  ``serviceid=...;`` user data, as rmw_cyclonedds does: a ROS 2 service only answers once it
  has matched the reply reader of the client that wrote the request.

Threading: Cyclone calls the listeners on its own receive threads. A listener only takes the
samples (deserialising them with ``cdr.py``'s compiled decoders, several times faster than
Cyclone's own), stamps them with the loop clock and puts them in the node's inbox; the first
sample into an empty inbox wakes the loop (``loop.call_soon_threadsafe``), which delivers
everything that arrived meanwhile in one pass, in arrival order. A reader opened ``at_tick``
(high-rate streams nothing on the safety path reads: imu, odom) has no listener: it is read on
the loop by ``deliver_held()``, which the tick calls first thing while the node's ``hold`` is
set (the runtime sets it while its tick loop runs), and by a ``POLL_PERIOD`` timer otherwise;
a sample's receive time is then estimated from its source timestamp, clamped between the
previous read and this one. (With a Cyclone binding without ``ddspy_take`` such a reader keeps
its listener and wakes the loop as any other.) Everything else (user callbacks, futures) runs
on the loop.
The loop never blocks on DDS: writes are non-blocking for best-effort topics and bounded by
``max_blocking_time`` for reliable ones (which only blocks when a reader's history is full).
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import os
import time
import uuid as uuidlib
from collections import deque
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import Any

import structlog
from cyclonedds.core import DDSException, InstanceState, Listener, Policy, Qos, SampleState, ViewState
from cyclonedds.domain import DomainParticipant
from cyclonedds.internal import InvalidSample
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from . import cdr, idl

try:  # what DataReader.take() calls, without its per-field deserialisation (cdr.py does that)
    from cyclonedds._clayer import ddspy_take
except ImportError:  # another binding version: fall back to DataReader.take()
    ddspy_take = None
try:  # what DataWriter.write() calls with the serialised sample (write_cdr)
    from cyclonedds._clayer import ddspy_write
except ImportError:
    ddspy_write = None

log = structlog.get_logger("bt_runtime.ros2.dds")


# ---------------------------------------------------------------------------------------------
# names and QoS
# ---------------------------------------------------------------------------------------------

def fq_name(name: str, namespace: str = "") -> str:
    """A fully qualified ROS name: relative names go below ``namespace`` (default ``/``)."""
    if name.startswith("/"):
        return name.rstrip("/") or "/"
    ns = "/" + namespace.strip("/") if namespace.strip("/") else ""
    return f"{ns}/{name}".rstrip("/")


@dataclass(frozen=True)
class QosProfile:
    """The ROS QoS settings that matter on the wire."""

    reliable: bool = True
    transient_local: bool = False
    depth: int = 10

    def to_dds(self, *, user_data: str | None = None, writer: bool = False) -> Qos:
        policies: list[Any] = [
            (Policy.Reliability.Reliable(max_blocking_time=duration(milliseconds=5)) if self.reliable
             else Policy.Reliability.BestEffort),
            Policy.Durability.TransientLocal if self.transient_local else Policy.Durability.Volatile,
            Policy.History.KeepLast(self.depth),
            Policy.WriterDataLifecycle(autodispose=False),
        ]
        if writer and self.transient_local:
            policies.append(Policy.DurabilityService(cleanup_delay=0, history=Policy.History.KeepLast(self.depth),
                                                     max_samples=-1, max_instances=-1,
                                                     max_samples_per_instance=-1))
        if user_data:
            policies.append(Policy.Userdata(data=user_data.encode()))
        return Qos(*policies)


SENSOR_DATA = QosProfile(reliable=False, depth=5)        # rmw_qos_profile_sensor_data
DEFAULT = QosProfile(reliable=True, depth=10)            # rmw_qos_profile_default
SERVICES = QosProfile(reliable=True, depth=10)           # rmw_qos_profile_services_default
ACTION_STATUS = QosProfile(reliable=True, transient_local=True, depth=1)  # rcl_action status
LATCHED = QosProfile(reliable=True, transient_local=True, depth=1)


def loopback_config(domain_id: int | None = None, lease_duration: float = 2.0) -> str:
    """A Cyclone DDS configuration that keeps all traffic on 127.0.0.1 (unicast discovery).
    ``lease_duration``: how soon peers notice that this process died (Cyclone's default 10 s)."""
    dom = "any" if domain_id is None else str(domain_id)
    return ("<CycloneDDS><Domain id=\"" + dom + "\"><General><Interfaces>"
            "<NetworkInterface address=\"127.0.0.1\"/></Interfaces><AllowMulticast>false</AllowMulticast>"
            "</General><Discovery><ParticipantIndex>auto</ParticipantIndex>"
            "<MaxAutoParticipantIndex>40</MaxAutoParticipantIndex>"
            f"<LeaseDuration>{lease_duration:g} s</LeaseDuration>"
            "<Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery></Domain></CycloneDDS>")


def write_cdr(writer: Any, data: bytes) -> bool:
    """Write an already serialised sample (encapsulation header included, length a multiple
    of 4) as ``DataWriter.write`` does after serialising; False when ``writer`` is not a
    Cyclone writer or the binding lacks ``ddspy_write`` (the caller then writes the object)."""
    if ddspy_write is None or type(writer) is not DataWriter:
        return False
    ret = ddspy_write(writer._ref, data)
    if ret < 0:
        raise DDSException(ret, f"Occurred while writing sample in {writer!r}")
    return True


# ---------------------------------------------------------------------------------------------
# the node: one participant, readers and writers
# ---------------------------------------------------------------------------------------------

POLL_PERIOD = 0.01  # s: at_tick readers are read this often while the node does not hold


class DdsNode:
    """One DDS participant on one domain, delivering samples on one asyncio loop."""

    _ids = itertools.count(1)

    def __init__(self, domain_id: int = 0, *, loop: asyncio.AbstractEventLoop | None = None,
                 namespace: str = "", cyclonedds_uri: str | None = None, service_mapping: str = "cyclonedds"):
        if cyclonedds_uri:
            os.environ["CYCLONEDDS_URI"] = cyclonedds_uri  # read when the domain is first created
        self.loop = loop or asyncio.get_running_loop()
        self.domain_id = domain_id
        self.namespace = namespace
        if service_mapping not in idl.SERVICE_MAPPINGS:
            raise ValueError(f"service_mapping must be one of {idl.SERVICE_MAPPINGS}, got {service_mapping!r}")
        self.service_mapping = service_mapping  # where services carry the request id (idl.service_wire)
        self.participant = DomainParticipant(domain_id)
        self._topics: dict[str, Topic] = {}
        self._readers: list[Reader] = []
        self._writers: list[DataWriter] = []
        self._uid = uuidlib.uuid4().bytes
        self.closed = False
        self._inbox: deque[tuple[Reader, list, float]] = deque()  # filled by receive threads
        self._wake_pending = False
        self.wakeups = 0  # passes of the loop that delivered the inbox
        self.hold = False  # at_tick readers are read by deliver_held() (the tick), not by the poll timer
        self._polled: list[Reader] = []  # at_tick readers without listener (read by deliver_held)
        self._poll_handle: asyncio.TimerHandle | None = None
        self._last_poll = self.loop.time()

    def post(self, reader: Reader, samples: list, now: float) -> None:
        """From a receive thread: queue ``samples`` for the loop; wake it unless a wake-up is
        pending already (that one delivers these too). Raises RuntimeError if the loop is closed."""
        self._inbox.append((reader, samples, now))
        if self._wake_pending:
            return
        self._wake_pending = True
        try:
            self.loop.call_soon_threadsafe(self._deliver_inbox)
        except RuntimeError:
            self._wake_pending = False
            raise

    def _deliver_inbox(self) -> None:  # on the loop
        # clear the flag first: a sample posted from now on either is delivered below or wakes us again
        self._wake_pending = False
        self.wakeups += 1
        self._drain()

    def deliver_held(self) -> None:
        """On the loop: deliver what waits in the inbox now (samples whose wake-up is still
        pending; that wake-up then finds the rest or nothing), then read the at_tick readers."""
        if self._inbox:
            self._drain()
        if self._polled:
            now = self.loop.time()
            since, self._last_poll = self._last_poll, now
            wall = time.time()
            for reader in self._polled:
                reader.poll(now, since, wall)

    def set_hold(self, hold: bool) -> None:
        """On the loop: leave the at_tick readers to ``deliver_held()`` (the tick), or stop
        holding (they are read in the next pass of the loop, and by the poll timer from then on)."""
        self.hold = hold
        if hold:
            if self._poll_handle is not None:
                self._poll_handle.cancel()
                self._poll_handle = None
        elif not self.closed:
            self.loop.call_soon(self.deliver_held)
            self._arm_poll()

    def _arm_poll(self) -> None:
        if self._poll_handle is None and self._polled and not self.hold and not self.closed:
            self._poll_handle = self.loop.call_later(POLL_PERIOD, self._on_poll_timer)

    def _on_poll_timer(self) -> None:
        self._poll_handle = None
        if self.closed or self.hold:
            return
        self.deliver_held()
        self._arm_poll()

    def _drain(self) -> None:
        inbox = self._inbox
        for _ in range(len(inbox)):  # what is there now; later arrivals have their own wake-up
            reader, samples, now = inbox.popleft()
            reader._deliver(samples, now)

    # -- plumbing ------------------------------------------------------------------------------
    def topic(self, dds_name: str, data_type: type) -> Topic:
        topic = self._topics.get(dds_name)
        if topic is None:
            topic = Topic(self.participant, dds_name, data_type)
            self._topics[dds_name] = topic
        elif topic.data_type is not data_type:
            raise ValueError(f"DDS topic {dds_name} already has type {topic.data_type.__name__}")
        return topic

    def fq(self, name: str) -> str:
        return fq_name(name, self.namespace)

    def unique_id(self) -> str:
        """A client/service id in rmw_cyclonedds's style (16 bytes, dotted)."""
        raw = self._uid[:12] + next(self._ids).to_bytes(4, "big")
        return ".".join(f"{b:02x}" for b in raw)

    def reader(self, dds_name: str, data_type: type, qos: QosProfile,
               on_samples: Callable[[list, float], None], *, user_data: str | None = None,
               at_tick: bool = False, decode: Callable[[bytes], Any] | None = None) -> Reader:
        reader = Reader(self, dds_name, data_type, qos, on_samples, user_data=user_data, at_tick=at_tick,
                        decode=decode)
        self._readers.append(reader)
        if reader.polled:
            self._polled.append(reader)
            self._arm_poll()
        return reader

    def writer(self, dds_name: str, data_type: type, qos: QosProfile, *, user_data: str | None = None) -> DataWriter:
        writer = DataWriter(self.participant, self.topic(dds_name, data_type),
                            qos=qos.to_dds(user_data=user_data, writer=True))
        self._writers.append(writer)
        return writer

    # -- ROS-level helpers ------------------------------------------------------------------------
    def subscription(self, name: str, data_type: type, qos: QosProfile,
                     on_samples: Callable[[list, float], None], *, at_tick: bool = False,
                     decode: Callable[[bytes], Any] | None = None) -> Reader:
        return self.reader("rt" + self.fq(name), data_type, qos, on_samples, at_tick=at_tick, decode=decode)

    def publisher(self, name: str, data_type: type, qos: QosProfile = DEFAULT) -> DataWriter:
        return self.writer("rt" + self.fq(name), data_type, qos)

    def close(self) -> None:
        """Delete the participant (and with it every reader and writer)."""
        if self.closed:
            return
        self.closed = True
        if self._poll_handle is not None:
            self._poll_handle.cancel()
            self._poll_handle = None
        for reader in self._readers:
            reader.closed = True
        with contextlib.suppress(Exception):
            self.participant.__del__()


_MAX_TAKE_FAILURES = 64  # consecutive failed takes in one callback before it gives up
_TAKE_BATCH = 32
_ANY_STATE = SampleState.Any | ViewState.Any | InstanceState.Any


class Reader:
    """A DDS reader whose samples arrive on the loop as ``on_samples(samples, receive_time)``.

    ``receive_time`` is ``loop.time()`` read on the receiving thread. Samples that fail to
    deserialise are dropped and counted in ``malformed``. ``decode`` (bytes -> sample) replaces
    ``cdr.decoder(data_type)`` (e.g. ``sensor_wire.py``'s; not with a binding without
    ``ddspy_take``, whose ``take()`` decodes itself).
    """

    def __init__(self, node: DdsNode, dds_name: str, data_type: type, qos: QosProfile,
                 on_samples: Callable[[list, float], None], *, user_data: str | None = None,
                 at_tick: bool = False, decode: Callable[[bytes], Any] | None = None):
        self.node = node
        self.name = dds_name
        self.on_samples = on_samples
        self.received = 0
        self.malformed = 0
        self.closed = False
        self.polled = at_tick and ddspy_take is not None  # no listener: read by DdsNode.deliver_held
        loop = node.loop
        self._loop = loop
        self._decode = decode or cdr.decoder(data_type)
        self._listener = None if self.polled else Listener(on_data_available=self._on_data_available)
        self.reader = DataReader(node.participant, node.topic(dds_name, data_type),
                                 qos=qos.to_dds(user_data=user_data), listener=self._listener)

    def _on_data_available(self, reader: DataReader) -> None:  # a Cyclone thread
        if self.closed:
            return
        failures = 0
        while not self.closed:
            try:
                taken, samples = self._take(reader)
            except Exception:  # a sample that does not deserialise: drop it, count it
                self.malformed += 1
                failures += 1
                if failures >= _MAX_TAKE_FAILURES:
                    # take() that keeps failing is a reader being deleted, not bad data: leave,
                    # or the participant's deletion (which waits for this callback) never ends
                    return
                continue
            if not taken:
                return
            if samples:
                try:
                    self.node.post(self, samples, self._loop.time())
                except RuntimeError:  # the loop is closed
                    self.closed = True
                    return

    def _take(self, reader: DataReader) -> tuple[int, list]:
        """(samples taken, the valid ones decoded); a sample that does not decode is counted in
        ``malformed`` and dropped alone."""
        if ddspy_take is None:
            samples = reader.take(N=_TAKE_BATCH)
            return len(samples), [s for s in samples if not isinstance(s, InvalidSample)]
        taken = ddspy_take(reader._ref, _ANY_STATE, _TAKE_BATCH)
        if type(taken) is int:
            raise DDSException(taken, f"Occurred while taking data in {self.name}")
        decode = self._decode
        valid = []
        for data, info in taken:
            if info.valid_data:  # (invalid samples only tell of a disposed instance)
                try:
                    valid.append(decode(data))
                except Exception:
                    self.malformed += 1
        return len(taken), valid

    def poll(self, now: float, since: float, wall: float) -> None:  # on the loop
        """Take and deliver what waits (a polled reader), each sample stamped with its source
        timestamp on the loop clock (``wall``: ``time.time()`` at ``now``), clamped to
        [``since``, ``now``]: it arrived after the previous read and before this one."""
        if self.closed:
            return
        ref, decode = self.reader._ref, self._decode
        for _ in range(_MAX_TAKE_FAILURES):
            try:
                taken = ddspy_take(ref, _ANY_STATE, _TAKE_BATCH)
            except Exception:  # a sample that does not deserialise: drop it, count it
                self.malformed += 1
                continue
            if type(taken) is int or not taken:
                return
            for data, info in taken:
                if not info.valid_data:  # (only tells of a disposed instance)
                    continue
                try:
                    sample = decode(data)
                except Exception:
                    self.malformed += 1
                    continue
                stamp = now - (wall - info.source_timestamp * 1e-9)
                self._deliver([sample], since if stamp < since else (now if stamp > now else stamp))
            if len(taken) < _TAKE_BATCH:
                return

    def _deliver(self, samples: list, now: float) -> None:  # on the loop
        if self.closed:
            return
        self.received += len(samples)
        try:
            self.on_samples(samples, now)
        except Exception:
            log.exception("dds_callback_failed", topic=self.name)

    def matched_writers(self) -> int:
        try:
            return len(self.reader.get_matched_publications())
        except Exception:
            return 0


# ---------------------------------------------------------------------------------------------
# services
# ---------------------------------------------------------------------------------------------

class ServiceError(RuntimeError):
    """A service call that got no answer (server absent or too slow)."""


class ServiceClient:
    """A ROS 2 service client (``rq/<name>Request`` / ``rr/<name>Reply``)."""

    def __init__(self, node: DdsNode, name: str, request_type: type, response_type: type,
                 qos: QosProfile = SERVICES):
        self.node = node
        self.name = node.fq(name)
        self.mapping = mapping = node.service_mapping
        self.request_wire = idl.service_wire(request_type, mapping, "request")
        self.response_type = response_type
        user_data = f"clientid={node.unique_id()};"
        self.writer = node.writer(f"rq{self.name}Request", self.request_wire, qos, user_data=user_data)
        self.reader = node.reader(f"rr{self.name}Reply", idl.service_wire(response_type, mapping, "reply"), qos,
                                  self._on_replies, user_data=user_data)
        # the request id's writer part: rmw_cyclonedds uses the request writer's instance handle
        # (uint64); DDS-RPC's basic mapping the request writer's GUID (16 bytes)
        self.guid = (self.writer.get_instance_handle() & 0xFFFF_FFFF_FFFF_FFFF if mapping == "cyclonedds"
                     else self.writer.get_guid().bytes)
        self._seq = itertools.count(1)
        self._pending: dict[int, asyncio.Future] = {}
        self.resent = 0  # requests sent again for want of a reply (``call(resend=...)``)

    def ready(self) -> bool:
        """Both directions matched with a server."""
        try:
            return bool(self.writer.get_matched_subscriptions()) and self.reader.matched_writers() > 0
        except Exception:
            return False

    async def wait_ready(self, timeout: float) -> bool:
        deadline = self.node.loop.time() + timeout
        while not self.ready():
            if self.node.loop.time() >= deadline:
                return False
            await asyncio.sleep(0.01)
        return True

    def _on_replies(self, samples: list, _now: float) -> None:
        for sample in samples:
            guid, seq = idl.request_id(sample)
            if guid != self.guid:
                continue  # another client's reply
            fut = self._pending.pop(seq, None)
            if fut is not None and not fut.done():
                fut.set_result(idl.unwrap(sample))

    def write_request(self, seq: int, request: Any) -> None:
        """Send ``request`` (the body type) with request id (our guid, ``seq``)."""
        self.writer.write(idl.wrap(self.guid, seq, request, self.mapping, "request"))

    async def call(self, request: Any, timeout: float = 2.0, *, resend: float | None = None) -> Any:
        """Send ``request`` (the body type) and return the response body; ServiceError on
        time-out (including the time to discover the server).

        ``resend``: send the request again (same id; the first reply wins) every ``resend`` s
        while no reply came, for requests that may be repeated (get_state). A ROS 2 server drops
        its reply when it has not yet matched the client's reply reader (rmw_cyclonedds waits
        100 ms for it, rmw_send_response), which our ``ready()`` cannot see from this side: sent
        once, such a request costs the whole timeout."""
        loop = self.node.loop
        deadline = loop.time() + timeout
        if not self.ready() and not await self.wait_ready(timeout):
            raise ServiceError(f"service {self.name} not available")
        seq = next(self._seq)
        fut = loop.create_future()
        self._pending[seq] = fut
        try:
            while True:
                self.write_request(seq, request)
                left = deadline - loop.time()
                await asyncio.wait((fut,), timeout=max(0.0, left if resend is None else min(left, resend)))
                if fut.done():
                    return fut.result()
                if loop.time() >= deadline:
                    raise ServiceError(f"service {self.name}: no reply within {timeout:g} s")
                self.resent += 1
        finally:
            self._pending.pop(seq, None)


class ServiceServer:
    """A ROS 2 service server; ``handler(request) -> response`` may be a coroutine function
    (returning None sends no reply). Requests are served concurrently, each in its own task."""

    def __init__(self, node: DdsNode, name: str, request_type: type, response_type: type,
                 handler: Callable[[Any], Any], qos: QosProfile = SERVICES):
        self.node = node
        self.name = node.fq(name)
        self.handler = handler
        self.mapping = mapping = node.service_mapping
        self.response_wire = idl.service_wire(response_type, mapping, "reply")
        user_data = f"serviceid={node.unique_id()};"
        self.writer = node.writer(f"rr{self.name}Reply", self.response_wire, qos, user_data=user_data)
        self.reader = node.reader(f"rq{self.name}Request", idl.service_wire(request_type, mapping, "request"), qos,
                                  self._on_requests, user_data=user_data)
        self._tasks: set[asyncio.Task] = set()
        self.served = 0

    def _on_requests(self, samples: list, _now: float) -> None:
        for sample in samples:
            task = self.node.loop.create_task(self._serve(sample))
            self._tasks.add(task)
            task.add_done_callback(self._tasks.discard)

    async def _serve(self, sample: Any) -> None:
        try:
            response = self.handler(idl.unwrap(sample))
            if isinstance(response, Awaitable):
                response = await response
        except Exception:
            log.exception("service_handler_failed", service=self.name)
            return
        if self.node.closed or response is None:  # None: no reply (a hung server)
            return
        guid, seq = idl.request_id(sample)  # echoed: the client matches its reply by it
        self.writer.write(idl.wrap(guid, seq, response, self.mapping, "reply"))
        self.served += 1

    def close(self) -> None:
        for task in list(self._tasks):
            task.cancel()


# ---------------------------------------------------------------------------------------------
# actions
# ---------------------------------------------------------------------------------------------

S = idl.GoalStatus
TERMINAL = (S.STATUS_SUCCEEDED, S.STATUS_CANCELED, S.STATUS_ABORTED)


def new_goal_id() -> bytes:
    return uuidlib.uuid4().bytes


def action_names(name: str) -> dict[str, str]:
    base = name.rstrip("/") + "/_action/"
    return {k: base + k for k in ("send_goal", "get_result", "cancel_goal", "feedback", "status")}


class ActionClient:
    """A ROS 2 action client (rcl_action layout) for one action type."""

    def __init__(self, node: DdsNode, name: str, types: idl.ActionTypes):
        self.node = node
        self.name = node.fq(name)
        self.types = types
        n = action_names(self.name)
        self.send_goal_client = ServiceClient(node, n["send_goal"], types.SendGoal_Request, types.SendGoal_Response)
        self.result_client = ServiceClient(node, n["get_result"], types.GetResult_Request, types.GetResult_Response)
        self.cancel_client = ServiceClient(node, n["cancel_goal"], idl.CancelGoal_Request, idl.CancelGoal_Response)
        self._feedback_cbs: dict[bytes, Callable[[Any], None]] = {}
        self.statuses: dict[bytes, int] = {}
        self.feedback_reader = node.reader("rt" + n["feedback"], types.FeedbackMessage, DEFAULT, self._on_feedback)
        self.status_reader = node.reader("rt" + n["status"], idl.GoalStatusArray, ACTION_STATUS, self._on_status)

    def server_ready(self) -> bool:
        return self.send_goal_client.ready() and self.result_client.ready() and self.cancel_client.ready()

    def server_present(self) -> bool:
        """Any of the server's endpoints still matched (false once its process is gone)."""
        return self.status_reader.matched_writers() > 0 or self.result_client.reader.matched_writers() > 0

    async def wait_ready(self, timeout: float) -> bool:
        deadline = self.node.loop.time() + timeout
        while not self.server_ready():
            if self.node.loop.time() >= deadline:
                return False
            await asyncio.sleep(0.01)
        return True

    def _on_feedback(self, samples: list, _now: float) -> None:
        for sample in samples:
            cb = self._feedback_cbs.get(bytes(sample.goal_id.uuid))
            if cb is not None:
                cb(sample.feedback)

    def _on_status(self, samples: list, _now: float) -> None:
        for sample in samples:
            for st in sample.status_list:
                self.statuses[bytes(st.goal_info.goal_id.uuid)] = st.status

    async def send_goal(self, goal: Any, *, feedback: Callable[[Any], None] | None = None,
                        timeout: float = 2.0) -> tuple[bytes, bool]:
        goal_id = new_goal_id()
        if feedback is not None:
            self._feedback_cbs[goal_id] = feedback
        if not self.server_ready() and not await self.wait_ready(timeout):
            self._feedback_cbs.pop(goal_id, None)
            raise ServiceError(f"action server {self.name} not available")
        request = self.types.SendGoal_Request(goal_id=idl.UUID(uuid=goal_id), goal=goal)
        response = await self.send_goal_client.call(request, timeout)
        if not response.accepted:
            self._feedback_cbs.pop(goal_id, None)
        return goal_id, bool(response.accepted)

    async def get_result(self, goal_id: bytes, *, poll: float = 0.25, gone_after: float = 1.0) -> tuple[int, Any]:
        """Wait for the goal's result. If the server vanishes (no endpoint matched for
        ``gone_after`` s) the goal ends ABORTED with ``None`` as result."""
        loop = self.node.loop
        client = self.result_client
        if not client.ready():
            await client.wait_ready(gone_after)
        seq = next(client._seq)
        fut = loop.create_future()
        client._pending[seq] = fut
        absent_since: float | None = None
        try:
            client.write_request(seq, self.types.GetResult_Request(goal_id=idl.UUID(uuid=goal_id)))
            while True:
                done, _ = await asyncio.wait({fut}, timeout=poll)
                if done:
                    response = fut.result()
                    return int(response.status), response.result
                if self.server_present():
                    absent_since = None
                else:
                    absent_since = absent_since or loop.time()
                    if loop.time() - absent_since >= gone_after:
                        return S.STATUS_ABORTED, None
        finally:
            client._pending.pop(seq, None)
            self._feedback_cbs.pop(goal_id, None)

    async def cancel(self, goal_id: bytes | None = None, timeout: float = 2.0) -> int:
        """Cancel one goal, or (``None``) every goal of the server; returns the return code."""
        info = idl.GoalInfo(goal_id=idl.UUID(uuid=goal_id or bytes(16)))
        response = await self.cancel_client.call(idl.CancelGoal_Request(goal_info=info), timeout)
        return int(response.return_code)


class _ServerGoal:
    __slots__ = ("goal_id", "stamp", "status", "task", "result", "done")

    def __init__(self, goal_id: bytes, stamp: idl.Time, done: asyncio.Future):
        self.goal_id = goal_id
        self.stamp = stamp
        self.status = S.STATUS_ACCEPTED
        self.task: asyncio.Task | None = None
        self.result: Any = None
        self.done = done


class GoalContext:
    """What an action server's ``execute`` sees: the goal, feedback, cancel state."""

    def __init__(self, server: ActionServer, goal: _ServerGoal):
        self._server = server
        self._goal = goal

    @property
    def goal_id(self) -> bytes:
        return self._goal.goal_id

    @property
    def cancel_requested(self) -> bool:
        return self._goal.status == S.STATUS_CANCELING

    def publish_feedback(self, feedback: Any) -> None:
        self._server.publish_feedback(self._goal.goal_id, feedback)


class ActionServer:
    """A ROS 2 action server. ``execute(goal, ctx) -> (status, result)`` runs as a task per
    accepted goal; a cancel request cancels that task (the coroutine should then return
    ``(STATUS_CANCELED, result)`` from its ``CancelledError`` handler, or it ends CANCELED with
    a default result). Terminal goals are kept (for ``get_result``) up to ``keep`` goals."""

    def __init__(self, node: DdsNode, name: str, types: idl.ActionTypes,
                 execute: Callable[[Any, GoalContext], Awaitable[tuple[int, Any]]], *, keep: int = 100):
        self.node = node
        self.name = node.fq(name)
        self.types = types
        self.execute = execute
        self.keep = keep
        self.goals: dict[bytes, _ServerGoal] = {}
        n = action_names(self.name)
        self.send_goal_server = ServiceServer(node, n["send_goal"], types.SendGoal_Request,
                                              types.SendGoal_Response, self._on_send_goal)
        self.result_server = ServiceServer(node, n["get_result"], types.GetResult_Request,
                                           types.GetResult_Response, self._on_get_result)
        self.cancel_server = ServiceServer(node, n["cancel_goal"], idl.CancelGoal_Request,
                                           idl.CancelGoal_Response, self._on_cancel)
        self.feedback_writer = node.writer("rt" + n["feedback"], types.FeedbackMessage, DEFAULT)
        self.status_writer = node.writer("rt" + n["status"], idl.GoalStatusArray, ACTION_STATUS)

    def _now(self) -> idl.Time:
        return idl.Time.now()

    def _on_send_goal(self, request: Any) -> Any:
        goal_id = bytes(request.goal_id.uuid)
        loop = self.node.loop
        goal = _ServerGoal(goal_id, self._now(), loop.create_future())
        self.goals[goal_id] = goal
        goal.task = loop.create_task(self._run(goal, request.goal), name=f"action:{self.name}")
        self._prune()
        self.publish_status()
        return self.types.SendGoal_Response(accepted=True, stamp=goal.stamp)

    async def _run(self, goal: _ServerGoal, goal_msg: Any) -> None:
        goal.status = S.STATUS_EXECUTING
        self.publish_status()
        ctx = GoalContext(self, goal)
        try:
            status, result = await self.execute(goal_msg, ctx)
        except asyncio.CancelledError:
            status, result = S.STATUS_CANCELED, self.types.Result()
        except Exception as exc:
            log.exception("action_execute_failed", action=self.name)
            status, result = S.STATUS_ABORTED, self.types.Result()
            if hasattr(result, "error_msg"):
                result.error_msg = f"internal error: {exc!r}"
        goal.status = status
        goal.result = result
        if not goal.done.done():
            goal.done.set_result(None)
        self.publish_status()

    async def _on_get_result(self, request: Any) -> Any:
        goal = self.goals.get(bytes(request.goal_id.uuid))
        if goal is None:
            return self.types.GetResult_Response(status=S.STATUS_UNKNOWN, result=self.types.Result())
        await asyncio.shield(goal.done)
        return self.types.GetResult_Response(status=goal.status, result=goal.result)

    def _on_cancel(self, request: Any) -> Any:
        target = bytes(request.goal_info.goal_id.uuid)
        stamp = request.goal_info.stamp
        cancel_all = target == bytes(16)
        canceling = []
        for goal in self.goals.values():
            if goal.status in TERMINAL:
                continue
            if (cancel_all and (stamp.sec == 0 and stamp.nanosec == 0 or
                                (goal.stamp.sec, goal.stamp.nanosec) <= (stamp.sec, stamp.nanosec))) \
                    or goal.goal_id == target:
                goal.status = S.STATUS_CANCELING
                if goal.task is not None:
                    goal.task.cancel()
                canceling.append(idl.GoalInfo(goal_id=idl.UUID(uuid=goal.goal_id), stamp=goal.stamp))
        if canceling:
            code = idl.CancelGoal_Response.ERROR_NONE
        elif not cancel_all and target in self.goals:
            code = idl.CancelGoal_Response.ERROR_GOAL_TERMINATED
        elif not cancel_all:
            code = idl.CancelGoal_Response.ERROR_UNKNOWN_GOAL_ID
        else:
            code = idl.CancelGoal_Response.ERROR_NONE
        self.publish_status()
        return idl.CancelGoal_Response(return_code=code, goals_canceling=canceling)

    def publish_feedback(self, goal_id: bytes, feedback: Any) -> None:
        if self.node.closed:
            return
        self.feedback_writer.write(self.types.FeedbackMessage(goal_id=idl.UUID(uuid=goal_id), feedback=feedback))

    def publish_status(self) -> None:
        if self.node.closed:
            return
        self.status_writer.write(idl.GoalStatusArray(status_list=[
            idl.GoalStatus(goal_info=idl.GoalInfo(goal_id=idl.UUID(uuid=g.goal_id), stamp=g.stamp), status=g.status)
            for g in self.goals.values()]))

    def _prune(self) -> None:
        if len(self.goals) <= self.keep:
            return
        for goal_id in [k for k, g in self.goals.items() if g.status in TERMINAL][: len(self.goals) - self.keep]:
            del self.goals[goal_id]

    def close(self) -> None:
        for goal in self.goals.values():
            if goal.task is not None and not goal.task.done():
                goal.task.cancel()
        for server in (self.send_goal_server, self.result_server, self.cancel_server):
            server.close()
