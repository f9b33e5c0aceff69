"""A Groot2 monitor server on the asyncio event loop (BT.CPP's ``Groot2Publisher``).

    server = GrootServer(tree, port=1667)          # binds 127.0.0.1 unless host= says otherwise
    await server.start()
    ...                                            # tick the tree on the same loop
    await server.stop()

Sockets: a ZeroMQ ROUTER on ``port`` (REQ clients such as Groot2 see a REP server) and a PUB on
``port + 1`` for BREAKPOINT_REACHED notifications. Requests are answered by one task, one
request per loop iteration, each with bounded work and a non-blocking send, so a slow or
vanished client never stalls the tick. Every request type of the protocol is served: FULLTREE,
STATUS, BLACKBOARD, HOOK_INSERT/REMOVE, BREAKPOINT_UNLOCK, HOOKS_DUMP, REMOVE_ALL_HOOKS,
DISABLE_ALL_HOOKS, TOGGLE_RECORDING, GET_TRANSITIONS. Malformed requests get BT.CPP's error
replies. Hostile clients are bounded: frames over 64 KiB disconnect the peer inside ZMQ (never
reaching the loop), at most 64 requests queue, a BLACKBOARD request names at most 256
blackboards and stops with an error reply past its 2 ms budget. See ``docs/groot.md`` for what differs from BT.CPP and why.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import random
import time
import weakref
from collections import deque
from typing import TYPE_CHECKING, Any

import zmq
import zmq.asyncio

from bt_runtime.status import NodeStatus
from bt_runtime.xml.writer import write_tree_to_xml

from . import protocol as P
from .hooks import HookError, HookManager, parse_json
from .tracker import SAMPLED, StatusTracker

if TYPE_CHECKING:
    from bt_runtime.tree import Tree

DEFAULT_PORT = 1667
MAX_TRANSITIONS = 1000
# Limits against hostile or broken clients (the server shares the loop with the tick):
MAX_MESSAGE_BYTES = 64 * 1024  # ZMQ_MAXMSGSIZE: a bigger frame disconnects the peer in ZMQ's I/O thread
MAX_QUEUED_MESSAGES = 64  # ZMQ_RCVHWM: requests waiting beyond this are dropped by ZMQ
MAX_FRAMES = 8  # identity, delimiter, header, payload: anything longer is refused unread
MAX_BLACKBOARD_NAMES = 256
REQUEST_BUDGET_S = 0.002  # work one request may do on the loop; more is refused, not finished
_UUIDS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def tree_uuid(tree: Tree) -> bytes:
    """A random (RFC 4122 v4) UUID, the same for the lifetime of this tree object."""
    value = _UUIDS.get(tree)
    if value is None:
        value = _UUIDS[tree] = P.new_tree_uuid()
    return value


class _ErrorReply(Exception):
    pass


class GrootServer:
    """Serve one tree to Groot2 (and other clients of its protocol).

    ``status_mode``: ``"sampled"`` (default, near-zero tick overhead) or ``"exact"`` (a status
    observer on every node, BT.CPP-identical STATUS bytes); see ``groot.tracker``.
    ``port=0`` picks a free pair of ports (see ``.port``).
    """

    def __init__(self, tree: Tree, port: int = DEFAULT_PORT, host: str = "127.0.0.1", *,
                 status_mode: str = SAMPLED, observe_period: float = 1.0,
                 heartbeat_timeout: float = 5.0, max_transitions: int = MAX_TRANSITIONS):
        self.tree = tree
        self.host = host
        self.port = port
        self.heartbeat_timeout = heartbeat_timeout
        self.observe_period = observe_period
        self.uuid = tree_uuid(tree)
        self.tracker = StatusTracker(tree, status_mode)
        self.hooks = HookManager(tree, self._publish_breakpoint)
        self._xml: bytes | None = None
        self._subtrees: dict[str, Any] = {}
        for record in tree.subtrees:
            self._subtrees.setdefault(record.instance_name or record.tree_id, record)
        self._ctx: zmq.asyncio.Context | None = None
        self._router: zmq.asyncio.Socket | None = None
        self._router_sync: zmq.Socket | None = None
        self._pub: zmq.Socket | None = None
        self._pub_async: zmq.asyncio.Socket | None = None
        self._tasks: list[asyncio.Task] = []
        self._loop: asyncio.AbstractEventLoop | None = None
        self._last_request = 0.0
        self._has_heartbeat = False
        # recording (TOGGLE_RECORDING / GET_TRANSITIONS)
        self._recording: deque[tuple[float, int, int]] = deque(maxlen=max_transitions)
        self._record_remove = None
        self._record_start = 0.0
        self._handlers = {
            P.FULLTREE: self._on_fulltree, P.STATUS: self._on_status, P.BLACKBOARD: self._on_blackboard,
            P.HOOK_INSERT: self._on_hook_insert, P.HOOK_REMOVE: self._on_hook_remove,
            P.BREAKPOINT_UNLOCK: self._on_unlock, P.HOOKS_DUMP: self._on_hooks_dump,
            P.REMOVE_ALL_HOOKS: self._on_remove_all, P.DISABLE_ALL_HOOKS: self._on_disable_all,
            P.TOGGLE_RECORDING: self._on_toggle_recording, P.GET_TRANSITIONS: self._on_transitions,
        }
        self.requests_served = 0
        self.requests_refused = 0
        self.max_request_cost = 0.0  # s of CPU the costliest request took on the loop's thread

    # -- lifecycle -------------------------------------------------------------------------------
    @property
    def pub_port(self) -> int:
        return self.port + 1

    @property
    def running(self) -> bool:
        return bool(self._tasks)

    @property
    def fulltree_xml(self) -> bytes:
        if self._xml is None:
            self._xml = write_tree_to_xml(self.tree).encode("utf-8")
        return self._xml

    async def start(self) -> GrootServer:
        if self._tasks:
            return self
        self._loop = asyncio.get_running_loop()
        self.fulltree_xml  # noqa: B018 - built once, like BT.CPP (and before any client asks)
        self._ctx = zmq.asyncio.Context()
        try:
            self._bind()
        except BaseException:
            self._close_sockets()
            raise
        self.tracker.start(self._loop)
        self._last_request = time.monotonic()
        self._has_heartbeat = False
        self._tasks = [self._loop.create_task(self._serve(), name="groot2:serve"),
                       self._loop.create_task(self._housekeeping(), name="groot2:heartbeat")]
        return self

    async def stop(self) -> None:
        """Release every hook (held nodes run again), stop recording, close the sockets."""
        tasks, self._tasks = self._tasks, []
        for task in tasks:
            task.cancel()
        for task in tasks:
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task
        self.hooks.remove_all()
        self._stop_recording()
        self.tracker.stop()
        self._close_sockets()

    async def __aenter__(self) -> GrootServer:
        return await self.start()

    async def __aexit__(self, *exc: object) -> None:
        await self.stop()

    def _endpoint(self, port: int) -> str:
        host = "*" if self.host in ("*", "0.0.0.0", "") else self.host
        if ":" in host and not host.startswith("["):
            host = f"[{host}]"
        return f"tcp://{host}:{port}"

    def _bind(self) -> None:
        ctx = self._ctx
        attempts = 50 if self.port == 0 else 1
        last_error: Exception | None = None
        for _ in range(attempts):
            port = self.port or random.randint(20000, 60000)
            router = ctx.socket(zmq.ROUTER)
            router.setsockopt(zmq.LINGER, 0)
            router.setsockopt(zmq.MAXMSGSIZE, MAX_MESSAGE_BYTES)
            router.setsockopt(zmq.RCVHWM, MAX_QUEUED_MESSAGES)
            if ":" in self.host:
                router.setsockopt(zmq.IPV6, 1)
            pub = ctx.socket(zmq.PUB)
            pub.setsockopt(zmq.LINGER, 0)
            try:
                router.bind(self._endpoint(port))
                pub.bind(self._endpoint(port + 1))
            except zmq.ZMQError as exc:
                router.close(linger=0)
                pub.close(linger=0)
                last_error = exc
                continue
            self.port = port
            self._router = router
            self._router_sync = zmq.Socket.shadow(router.underlying)
            self._pub_async = pub
            self._pub = zmq.Socket.shadow(pub.underlying)  # plain sends from inside a tick
            return
        raise OSError(f"Groot2 server: cannot bind {self.host}:{self.port} and port+1: {last_error}")

    def _close_sockets(self) -> None:
        for sock in (self._router, self._pub_async):
            if sock is not None:
                with contextlib.suppress(Exception):
                    sock.close(linger=0)
        self._router = self._router_sync = self._pub = self._pub_async = None
        if self._ctx is not None:
            with contextlib.suppress(Exception):
                self._ctx.term()
            self._ctx = None

    # -- loops -------------------------------------------------------------------------------------
    async def _serve(self) -> None:
        router = self._router
        send = self._router_sync.send_multipart
        while True:
            frames = await router.recv_multipart()
            self._last_request = time.monotonic()
            if not self._has_heartbeat:
                self._heartbeat(True)
            # ROUTER envelope: identity frame(s), an empty delimiter (REQ), then the request.
            split = next((i for i, f in enumerate(frames) if not f), None)
            if split is None:
                envelope, body = frames[:1], frames[1:]
            else:
                envelope, body = frames[:split + 1], frames[split + 1:]
            if len(frames) > MAX_FRAMES:
                self.requests_refused += 1
                reply = [b"error", b"too many message parts"]
            else:
                t0 = time.thread_time()  # CPU, not wall: a preempted process is not the request's cost
                reply = self.handle(body)
                cost = time.thread_time() - t0
                if cost > self.max_request_cost:
                    self.max_request_cost = cost
            with contextlib.suppress(zmq.ZMQError):
                send(envelope + reply, flags=zmq.NOBLOCK)
            self.requests_served += 1
            await asyncio.sleep(0)  # one request per loop iteration: the tick comes first

    async def _housekeeping(self) -> None:
        next_observation = 0.0
        while True:
            await asyncio.sleep(0.05)
            now = time.monotonic()
            alive = now - self._last_request < self.heartbeat_timeout
            if alive != self._has_heartbeat:
                self._heartbeat(alive)
            if alive and now >= next_observation:
                self.tracker.observe_next_tick()
                next_observation = now + self.observe_period

    def _heartbeat(self, alive: bool) -> None:
        """BT.CPP: losing the client disables every hook (releasing held nodes), regaining it
        re-enables them. Recording also stops when the client is gone (nobody will fetch it,
        and it costs a callback per status change)."""
        self._has_heartbeat = alive
        self.hooks.enable_all(alive)
        if not alive:
            self._stop_recording()

    # -- requests ----------------------------------------------------------------------------------
    def handle(self, body: list[bytes]) -> list[bytes]:
        """One request (without envelope) -> reply frames. Never raises."""
        if not body or len(body[0]) != P.HEADER_SIZE:
            return [b"error", b"wrong request header"]
        _, rtype, rid = P.HEADER.unpack(body[0])
        handler = self._handlers.get(rtype)
        if handler is None:
            return [b"error", b"Request not recognized"]
        try:
            frames = handler(body)
        except _ErrorReply as exc:
            return [b"error", str(exc).encode()]
        except (HookError, ValueError, TypeError, KeyError) as exc:
            return [b"error", str(exc).encode()]
        except Exception as exc:  # noqa: BLE001 - the client must always get a reply
            return [b"error", f"{type(exc).__name__}: {exc}".encode()]
        return [P.HEADER.pack(P.PROTOCOL_ID, rtype, rid) + self.uuid, *frames]

    @staticmethod
    def _payload(body: list[bytes]) -> bytes:
        if len(body) != 2:
            raise _ErrorReply("must be 2 parts message")
        return body[1]

    def _on_fulltree(self, body: list[bytes]) -> list[bytes]:
        return [self.fulltree_xml]

    def _on_status(self, body: list[bytes]) -> list[bytes]:
        return [self.tracker.buffer()]

    def _on_blackboard(self, body: list[bytes]) -> list[bytes]:
        payload = self._payload(body)
        if payload.count(b";") > MAX_BLACKBOARD_NAMES:
            self.requests_refused += 1
            raise _ErrorReply(f"too many blackboard names (at most {MAX_BLACKBOARD_NAMES})")
        start = time.thread_time()
        out: dict[str, Any] = {}
        for name in dict.fromkeys(_split_names(payload.decode("utf-8", "replace"))):
            record = self._subtrees.get(name)
            if record is not None:
                out[name] = P.export_blackboard(record.blackboard)
            if time.thread_time() - start > REQUEST_BUDGET_S:
                self.requests_refused += 1
                raise _ErrorReply(f"request over its {REQUEST_BUDGET_S * 1e3:.0f} ms budget: ask for fewer blackboards")
        return [P.msgpack_encode(out or None)]

    def _on_hook_insert(self, body: list[bytes]) -> list[bytes]:
        self.hooks.insert(parse_json(self._payload(body)))
        return []

    def _on_hook_remove(self, body: list[bytes]) -> list[bytes]:
        data = parse_json(self._payload(body))
        from .hooks import _uid_and_position

        uid, position = _uid_and_position(data)
        if not self.hooks.remove(uid, position):
            raise _ErrorReply("Node ID not found")
        return []

    def _on_unlock(self, body: list[bytes]) -> list[bytes]:
        data = parse_json(self._payload(body))
        from .hooks import _uid_and_position

        uid, position = _uid_and_position(data)
        try:
            status = data["desired_status"]
            remove = data["remove_when_done"]
        except KeyError as exc:
            raise HookError(f"unlock json: missing key {exc}") from None
        if not isinstance(status, str) or not isinstance(remove, bool):
            raise HookError("unlock json: desired_status must be a string, remove_when_done a bool")
        if not self.hooks.unlock(uid, position, status, remove):
            raise _ErrorReply("Node ID not found")
        return []

    def _on_hooks_dump(self, body: list[bytes]) -> list[bytes]:
        return [json.dumps(self.hooks.dump(), separators=(",", ":"), sort_keys=True).encode()]

    def _on_remove_all(self, body: list[bytes]) -> list[bytes]:
        self.hooks.remove_all()
        return []

    def _on_disable_all(self, body: list[bytes]) -> list[bytes]:
        self.hooks.enable_all(False)
        return []

    def _on_toggle_recording(self, body: list[bytes]) -> list[bytes]:
        cmd = self._payload(body)
        if cmd == b"start":
            self._stop_recording()
            self._recording.clear()
            self._record_start = self.tree.clock()
            self._record_remove = self.tree.add_status_observer(self._record)
            return [str(time.time_ns() // 1000).encode()]
        if cmd == b"stop":
            self._stop_recording()
        return []

    def _on_transitions(self, body: list[bytes]) -> list[bytes]:
        start = self._record_start
        records = []
        last = 0
        for stamp, uid, status in self._recording:
            usec = max(last, int(round((stamp - start) * 1e6)))
            last = usec
            records.append((usec, uid, status))
        self._recording.clear()
        return [P.pack_transitions(records)]

    # -- helpers ---------------------------------------------------------------------------------
    def _record(self, stamp: float, node: Any, prev: NodeStatus, new: NodeStatus) -> None:
        self._recording.append((stamp, node.uid, int(new)))

    def _stop_recording(self) -> None:
        if self._record_remove is not None:
            self._record_remove()
            self._record_remove = None

    def _publish_breakpoint(self, uid: int) -> None:
        pub = self._pub
        if pub is None:
            return
        with contextlib.suppress(zmq.ZMQError):
            pub.send_multipart([P.request_header(P.BREAKPOINT_REACHED), str(uid).encode()],
                               flags=zmq.NOBLOCK)


def _split_names(text: str) -> list[str]:
    """BT.CPP ``splitString(s, ';')``."""
    if not text:
        return []
    parts = text.split(";")
    if parts and parts[-1] == "":
        parts.pop()
    return parts
