"""groot.server: the Groot2 protocol on the asyncio loop, hooks that never block the loop,
recording, and the shared checkers (groot2_probe.py --hooks --strict, btview) against it."""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import struct
import subprocess
import sys
import time

import msgpack
import pytest
import zmq

from bt_runtime import BehaviorTreeFactory, Blackboard, NodeStatus
from bt_runtime.xml.writer import write_tree_to_xml
from groot import GrootServer
from groot import protocol as P
from groot.testing import GrootClient, free_port_pair, groot2_tools

S = NodeStatus
TOOLS = groot2_tools()
needs_tools = pytest.mark.skipif(TOOLS is None, reason="shared/tools/groot2 (checkers) is absent")

XML = """
<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <ReactiveSequence name="guard">
      <Cond name="ok"/>
      <Sequence name="work">
        <Act name="first"/>
        <Move name="move"/>
        <SubTree ID="Sub" name="sub" x="{x}"/>
        <SubTree ID="Remap" value="{x}"/>
      </Sequence>
    </ReactiveSequence>
  </BehaviorTree>
  <BehaviorTree ID="Sub">
    <Sequence><Script code="local_n := 7"/><Act name="inner"/></Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Remap"><Act name="deep"/></BehaviorTree>
</root>
"""


class Leaves:
    """Leaf behaviour plus a log of every callback."""

    def __init__(self) -> None:
        self.log: list[str] = []
        self.cond = S.SUCCESS
        self.move_ticks = 3
        self._running: dict[int, int] = {}

    def register(self, f: BehaviorTreeFactory) -> None:
        def cond(n):
            self.log.append(f"cond:{n.name}")
            return self.cond

        def act(n):
            self.log.append(f"act:{n.name}")
            return S.SUCCESS

        def start(n):
            self.log.append(f"start:{n.name}")
            self._running[n.uid] = 0
            return S.RUNNING

        def running(n):
            self.log.append(f"run:{n.name}")
            self._running[n.uid] += 1
            return S.SUCCESS if self._running[n.uid] >= self.move_ticks else S.RUNNING

        def halted(n):
            self.log.append(f"halt:{n.name}")

        f.register_simple_condition("Cond", cond)
        f.register_simple_action("Act", act)
        f.register_simple_stateful_action("Move", start, running, halted)

    def count(self, entry: str) -> int:
        return self.log.count(entry)


def build(leaves: Leaves | None = None, xml: str = XML, bb: Blackboard | None = None):
    leaves = leaves or Leaves()
    f = BehaviorTreeFactory()
    leaves.register(f)
    return f.create_tree_from_text(xml, bb), leaves


def uid_of(tree, name: str) -> int:
    return next(n.uid for rec in tree.subtrees for n in rec.nodes if n.name == name)


class Ticker:
    """Tick the tree on the running loop every ``period`` seconds (like the runtime's tick task)."""

    def __init__(self, tree, period: float = 0.005):
        self.tree, self.period, self.ticks = tree, period, 0
        self.task: asyncio.Task | None = None

    async def _run(self) -> None:
        self.tree.set_clock(asyncio.get_running_loop().time)
        while True:
            self.tree.tick_once()
            self.ticks += 1
            await asyncio.sleep(self.period)

    def start(self) -> Ticker:
        self.task = asyncio.get_running_loop().create_task(self._run())
        return self

    async def stop(self) -> None:
        if self.task is not None:
            self.task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self.task

    async def wait_ticks(self, n: int, timeout: float = 5.0) -> None:
        target = self.ticks + n
        deadline = time.monotonic() + timeout
        while self.ticks < target:
            assert time.monotonic() < deadline, "the tree stopped ticking"
            await asyncio.sleep(0.002)


async def call(fn, *args, **kwargs):
    return await asyncio.to_thread(fn, *args, **kwargs)


async def wait_for(predicate, timeout: float = 3.0) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, "condition not reached in time"
        await asyncio.sleep(0.005)


@contextlib.asynccontextmanager
async def serving(tree, **kwargs):
    server = GrootServer(tree, port=0, **kwargs)
    await server.start()
    client = GrootClient(server.port)
    try:
        yield server, client
    finally:
        client.close()
        await server.stop()


# ---------------------------------------------------------------------------------------------
# protocol
# ---------------------------------------------------------------------------------------------

async def test_fulltree_status_headers_uuid_and_errors() -> None:
    tree, _ = build()
    async with serving(tree) as (server, client):
        assert server.host == "127.0.0.1" and server.port > 0
        assert await call(client.fulltree) == write_tree_to_xml(tree)
        uuid = await call(client.uuid)
        assert (uuid[6] >> 4) == 4 and (uuid[8] >> 6) == 2
        status = await call(client.status)
        assert [u for u, _ in status] == [n.uid for rec in tree.subtrees for n in rec.nodes]
        assert {c for _, c in status} == {0}  # never ticked
        # BT.CPP's error replies, and the server keeps answering afterwards
        assert await call(client.raw, [b"\x02S"]) == [b"error", b"wrong request header"]
        assert await call(client.raw, [P.request_header(ord("Z"))]) == [b"error", b"Request not recognized"]
        for rtype in "BIRUr":
            assert await call(client.raw, [P.request_header(ord(rtype))]) == [b"error", b"must be 2 parts message"]
        assert (await call(client.request, "I", b"{not json"))[0] == b"error"
        assert (await call(client.request, "I", b'{"uid": 2}'))[0] == b"error"  # missing keys
        assert await call(client.request, "R", b'{"uid": 2, "position": 0}') == [b"error", b"Node ID not found"]
        assert await call(client.unlock, 2) == [b"error", b"Node ID not found"]
        assert (await call(client.request, "D"))[1] == b"[]"
        assert len(await call(client.request, "A")) == 1 and len(await call(client.request, "X")) == 1
        reply = await call(client.request, "r", "start")
        assert abs(int(reply[1]) / 1e6 - time.time()) < 5
        transitions = await call(client.request, "t")
        assert len(transitions) == 2 and transitions[0][6:] == uuid and len(transitions[1]) % 9 == 0
        assert len(await call(client.request, "r", "stop")) == 1
        assert len(await call(client.request, "r", "whatever")) == 1
        assert await call(client.uuid) == uuid
        # unknown hook uid: silently ignored, like BT.CPP
        assert len(await call(client.insert_hook, 9999)) == 1 and await call(client.hooks) == []
    # the same tree keeps its UUID across server restarts; another tree gets another one
    async with serving(tree) as (_, client):
        assert await call(client.uuid) == uuid
    async with serving(build()[0]) as (_, client):
        assert await call(client.uuid) != uuid


async def test_blackboard_msgpack_like_nlohmann() -> None:
    class Opaque:
        pass

    bb = Blackboard()
    for key, value in {"i": 5, "big": 0x7FFFFFFF, "neg": -200, "half": 1.5, "tenth": 0.1, "flag": True,
                       "off": False, "s": "txt", "vec": [1, 2, 3], "obj": Opaque(), "st": S.FAILURE}.items():
        bb.set(key, value)
    bb.create_entry("empty")
    tree, leaves = build(bb=bb)
    leaves.move_ticks = 1
    for _ in range(3):
        tree.tick_once()
    async with serving(tree) as (_, client):
        raw = await call(client.blackboard, "Main")
        data = msgpack.unpackb(raw)
        assert list(data) == ["Main"]
        main = data["Main"]
        assert list(main) == sorted(main)  # std::map order
        assert main == {"big": 0x7FFFFFFF, "empty": None, "flag": 1, "half": 1.5, "i": 5, "neg": -200,
                        "obj": None, "off": 0, "s": "txt", "st": 3, "tenth": 0.1, "vec": [1, 2, 3]}
        assert b"\xa4half\xca\x3f\xc0\x00\x00" in raw  # float32 when exact
        assert b"\xa5tenth\xcb" in raw  # float64 otherwise
        assert b"\xa3big\xce\x7f\xff\xff\xff" in raw
        both = msgpack.unpackb(await call(client.blackboard, "Main", "sub", "Remap::10", "nope", "sub"))
        assert set(both) == {"Main", "sub", "Remap::10"}
        assert both["sub"] == {"local_n": 7} and both["Remap::10"] is None  # remap only: nil
        assert await call(client.blackboard, "nope") == b"\xc0"
        assert await call(client.blackboard, "") == b"\xc0"


# ---------------------------------------------------------------------------------------------
# hooks and breakpoints
# ---------------------------------------------------------------------------------------------

def subscriber(port: int) -> zmq.Socket:
    ctx = zmq.Context.instance()
    sub = ctx.socket(zmq.SUB)
    sub.setsockopt(zmq.LINGER, 0)
    sub.setsockopt(zmq.SUBSCRIBE, b"")
    sub.connect(f"tcp://127.0.0.1:{port + 1}")
    return sub


def recv_notifications(sub: zmq.Socket, timeout: float = 2.0, want: int = 1) -> list[int]:
    got, deadline = [], time.monotonic() + timeout
    while len(got) < want and time.monotonic() < deadline:
        if sub.poll(50):
            header, payload = sub.recv_multipart()
            assert len(header) == 6 and header[:2] == b"\x02N"
            got.append(int(payload))
    return got


async def test_breakpoint_holds_node_while_the_loop_runs() -> None:
    tree, leaves = build()
    move = uid_of(tree, "move")
    async with serving(tree) as (server, client):
        sub = subscriber(server.port)
        await asyncio.sleep(0.2)  # let the subscription reach the PUB socket
        other = {"n": 0}

        async def other_task():  # stands for the supervisor / decision gate
            while True:
                other["n"] += 1
                await asyncio.sleep(0.001)

        side = asyncio.get_running_loop().create_task(other_task())
        assert len(await call(client.insert_hook, move)) == 1
        assert await call(client.hooks) == [{"desired_status": "SKIPPED", "enabled": True, "mode": 0,
                                            "once": False, "position": 0, "uid": move}]
        ticker = Ticker(tree).start()
        assert await call(recv_notifications, sub) == [move]
        await ticker.wait_ticks(20)
        before = other["n"]
        await ticker.wait_ticks(20)
        # held: ticked 40 times, never started; the other task and the server kept running
        assert other["n"] > before and leaves.count("start:move") == 0
        assert server.hooks.held == [move]
        codes = dict(await call(client.status))
        assert codes[move] == 1 and codes[uid_of(tree, "work")] == 1
        assert leaves.count("cond:ok") >= 40  # the rest of the tree keeps ticking (reactive guard)
        # unlock, run for real (on_start first) and drop the hook when done
        assert len(await call(client.unlock, move, "SKIPPED", True)) == 1
        await wait_for(lambda: leaves.count("run:move") >= 3)
        assert leaves.log.index("start:move") < leaves.log.index("run:move")
        assert await call(client.hooks) == [] and server.hooks.held == []
        assert leaves.count("halt:move") == 0
        side.cancel()
        await ticker.stop()
        sub.close(linger=0)


async def test_breakpoint_unlock_result_replaces_tick_and_rebreaks_each_tick() -> None:
    tree, leaves = build()
    first = uid_of(tree, "first")
    async with serving(tree) as (server, client):
        await call(client.insert_hook, first)
        tree.tick_once()
        assert server.hooks.held == [first] and leaves.count("act:first") == 0
        await call(client.unlock, first, "FAILURE")
        assert tree.tick_once() is S.FAILURE  # Sequence failed through the replaced result
        assert leaves.count("act:first") == 0
        tree.tick_once()  # the hook is still there: it breaks again
        assert server.hooks.held == [first]
        await call(client.unlock, first, "whatever")  # anything else: run the real tick
        tree.tick_once()
        assert leaves.count("act:first") == 1
        # 'first' is SUCCESS now (its Sequence is RUNNING on 'move'): completed nodes are not
        # hooked, like BT.CPP. Switching a held breakpoint to REPLACE releases the node.
        move = uid_of(tree, "move")
        await call(client.insert_hook, move)
        tree.tick_once()
        assert server.hooks.held == [move] and leaves.count("start:move") == 1  # held while RUNNING
        await call(client.insert_hook, move, mode=1, desired="SUCCESS")
        assert server.hooks.held == []
        tree.tick_once()
        assert leaves.count("run:move") == 0 and leaves.count("act:inner") == 1


async def test_halt_while_held_is_quiet_and_disable_releases() -> None:
    tree, leaves = build()
    move = uid_of(tree, "move")
    async with serving(tree) as (server, client):
        await call(client.insert_hook, move)
        tree.tick_once()
        assert server.hooks.held == [move]
        leaves.cond = S.FAILURE  # the reactive guard halts the branch holding the node
        assert tree.tick_once() is S.FAILURE
        assert leaves.count("halt:move") == 0 and leaves.count("start:move") == 0
        leaves.cond = S.SUCCESS
        tree.tick_once()  # reached again (still waiting), still not started
        assert server.hooks.held == [move] and leaves.count("start:move") == 0
        await call(client.request, "X")  # DISABLE_ALL_HOOKS releases it: it runs for real
        assert server.hooks.held == []
        tree.tick_once()
        assert leaves.log[-1] == "start:move"
        # a breakpoint set on a node that is already running holds it; a halt is then real
        await call(client.request, "A")
        await call(client.insert_hook, move)
        tree.tick_once()
        assert server.hooks.held == [move] and leaves.count("run:move") == 0
        leaves.cond = S.FAILURE
        tree.tick_once()
        assert leaves.count("halt:move") == 1


async def test_heartbeat_loss_disables_hooks_and_stops_recording() -> None:
    tree, leaves = build()
    move = uid_of(tree, "move")
    async with serving(tree, heartbeat_timeout=0.3) as (server, client):
        await call(client.request, "r", "start")
        await call(client.insert_hook, move)
        ticker = Ticker(tree).start()
        await wait_for(lambda: server.hooks.held == [move])
        assert leaves.count("start:move") == 0 and server._record_remove is not None
        await wait_for(lambda: leaves.count("start:move") == 1, timeout=3.0)  # client gone: released
        assert server._record_remove is None
        assert all(not h.enabled for h in server.hooks.hooks.values())
        assert all(h["enabled"] for h in await call(client.hooks))  # a request re-enables them
        await ticker.stop()


async def test_replace_hooks_pre_and_post() -> None:
    tree, leaves = build()
    leaves.move_ticks = 1
    first, inner = uid_of(tree, "first"), uid_of(tree, "inner")
    async with serving(tree) as (server, client):
        sub = subscriber(server.port)
        await asyncio.sleep(0.2)
        await call(client.insert_hook, first, mode=1, desired="SUCCESS", once=True)
        await call(client.insert_hook, inner, mode=1, desired="FAILURE", position=1)
        assert [h["position"] for h in await call(client.hooks)] == [0, 1]
        assert tree.tick_once() is S.RUNNING  # 'first' replaced (not called), 'move' started
        assert leaves.count("act:first") == 0 and leaves.count("start:move") == 1
        assert await call(recv_notifications, sub) == [first]
        assert await call(client.hooks) == [{"desired_status": "FAILURE", "enabled": True, "mode": 1,
                                            "once": False, "position": 1, "uid": inner}]  # once: gone
        # a POST hook lets the node tick, then overrides its result: the Sequence fails
        assert tree.tick_once() is S.FAILURE
        assert leaves.count("act:inner") == 1 and leaves.count("act:deep") == 0
        assert await call(recv_notifications, sub) == [inner]
        assert tree.tick_once() is S.RUNNING and leaves.count("act:first") == 1
        sub.close(linger=0)


# ---------------------------------------------------------------------------------------------
# status modes, recording, robustness
# ---------------------------------------------------------------------------------------------

async def test_status_exact_mode_tracks_every_change() -> None:
    tree, leaves = build()
    changes: dict[int, int] = {}
    tree.add_status_observer(lambda t, n, prev, new: changes.__setitem__(n.uid, 10 + prev if new is S.IDLE else new))
    async with serving(tree, status_mode="exact") as (_, client):
        leaves.move_ticks = 1
        for _ in range(5):
            tree.tick_once()
            status = await call(client.status)
            assert status == [(u, changes.get(u, 0)) for u, _ in status]
        assert {c for _, c in status} & {12}  # idle after success: 10 + 2


async def test_status_sampled_mode_active_nodes_exact_and_cheap() -> None:
    tree, leaves = build()
    move, first = uid_of(tree, "move"), uid_of(tree, "first")
    leaves.move_ticks = 10**6
    async with serving(tree, observe_period=0.05) as (server, client):
        tree.set_clock(asyncio.get_running_loop().time)
        tree.tick_once()
        tree.tick_once()
        codes = dict(await call(client.status))
        assert codes[move] == 1 and codes[first] == 2 and codes[uid_of(tree, "inner")] == 0
        assert not any(n._subscribers for rec in tree.subtrees for n in rec.nodes)
        ticker = Ticker(tree).start()
        await wait_for(lambda: server.tracker.observed_ticks >= 2)  # one observed tick per period
        await ticker.stop()
        assert not any(n._subscribers for rec in tree.subtrees for n in rec.nodes)


async def test_recording_transitions() -> None:
    tree, leaves = build()
    async with serving(tree, max_transitions=50) as (_, client):
        tree.set_clock(asyncio.get_running_loop().time)
        start = await call(client.request, "r", "start")
        assert start[1].isdigit()
        tree.tick_once()
        await asyncio.sleep(0.01)
        tree.tick_once()
        records = P.unpack_transitions((await call(client.request, "t"))[1])
        assert records[0][1:] == (1, 1)  # the root goes RUNNING first
        assert [r[0] for r in records] == sorted(r[0] for r in records)
        assert all(0 <= s <= 4 for _, _, s in records) and any(s == 0 for _, _, s in records)
        assert (await call(client.request, "t"))[1] == b""  # emptied
        for _ in range(30):
            tree.tick_once()
        assert len((await call(client.request, "t"))[1]) == 9 * 50  # only the last 50 kept
        await call(client.request, "r", "stop")
        tree.tick_once()
        assert (await call(client.request, "t"))[1] == b""


async def test_slow_and_vanished_clients_never_stall_the_tick() -> None:
    tree, _ = build()
    async with serving(tree) as (server, client):
        ticker = Ticker(tree, period=0.002).start()
        ctx = zmq.Context.instance()
        # a flood from a client that never reads its replies
        flood = ctx.socket(zmq.DEALER)
        flood.setsockopt(zmq.LINGER, 0)
        flood.connect(f"tcp://127.0.0.1:{server.port}")
        for _ in range(2000):
            flood.send_multipart([b"", P.request_header(P.FULLTREE)])
        # clients that send and vanish
        for _ in range(20):
            gone = ctx.socket(zmq.REQ)
            gone.setsockopt(zmq.LINGER, 0)
            gone.connect(f"tcp://127.0.0.1:{server.port}")
            gone.send_multipart([P.request_header(P.STATUS)])
            gone.close(linger=0)
        # garbage without the REQ delimiter
        flood.send_multipart([b"junk", b"more"])
        t0, n0 = time.monotonic(), ticker.ticks
        await asyncio.sleep(0.5)
        rate = (ticker.ticks - n0) / (time.monotonic() - t0)
        assert rate > 50, f"tick rate collapsed to {rate:.0f}/s"
        assert len(await call(client.status)) == sum(len(r.nodes) for r in tree.subtrees)
        flood.close(linger=0)
        await ticker.stop()


async def test_bind_host_and_port_conflict() -> None:
    tree, _ = build()
    port = free_port_pair()
    async with serving(tree):
        pass
    server = GrootServer(tree, port=port)
    await server.start()
    try:
        assert server.port == port and server.pub_port == port + 1
        with pytest.raises(OSError):
            await GrootServer(tree, port=port).start()
    finally:
        await server.stop()


# ---------------------------------------------------------------------------------------------
# the shared checkers and btview, as subprocesses
# ---------------------------------------------------------------------------------------------

async def flip_guard(leaves: Leaves, ticker: Ticker) -> None:
    """Make the guard fail now and then: without it the test tree looks the same at every
    STATUS sample (one action RUNNING, the rest idle-after-success), and clients that report
    changes (the probe, btview echo) would see none."""
    while True:
        leaves.cond = S.FAILURE if leaves.cond is S.SUCCESS and ticker.ticks % 3 == 0 else S.SUCCESS
        await asyncio.sleep(0.023)


async def run_proc(*argv: str, timeout: float = 40.0) -> tuple[int, str, str]:
    env = dict(os.environ, NO_COLOR="1", COLUMNS="160")
    proc = await asyncio.create_subprocess_exec(*argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    try:
        out, err = await asyncio.wait_for(proc.communicate(), timeout)
    except TimeoutError:
        proc.kill()
        raise
    return proc.returncode, out.decode(), err.decode()


@needs_tools
async def test_groot2_probe_hooks_strict_passes() -> None:
    tree, leaves = build()
    leaves.move_ticks = 7
    async with serving(tree) as (server, _):
        ticker = Ticker(tree, period=0.01).start()
        flipper = asyncio.get_running_loop().create_task(flip_guard(leaves, ticker))
        count = sum(len(r.nodes) for r in tree.subtrees)
        rc, out, err = await run_proc(sys.executable, str(TOOLS / "groot2_probe.py"), "--port", str(server.port),
                                      "--expect-nodes", str(count), "--hooks", "--strict", "--no-btview",
                                      "--samples", "8", "--interval", "0.037", "--record-seconds", "0.3")
        flipper.cancel()
        await ticker.stop()
    report = json.loads(out)
    assert rc == 0 and report["passed"], (report["required_failed"], report["advisory_failed"], err[-500:])
    assert report["required_total"] >= 40 and report["advisory_total"] >= 18
    print("probe checks:", report["required_total"], "required,", report["advisory_total"], "advisory")


def btview_available() -> bool:
    import importlib.util
    return importlib.util.find_spec("btview") is not None


@pytest.mark.skipif(not btview_available(), reason="btview is not installed")
async def test_btview_headless_commands(tmp_path) -> None:
    tree, leaves = build()
    count = sum(len(r.nodes) for r in tree.subtrees)
    async with serving(tree) as (server, _):
        ticker = Ticker(tree, period=0.01).start()
        flipper = asyncio.get_running_loop().create_task(flip_guard(leaves, ticker))
        # five clients start at once on a loaded machine: a request may wait seconds for its answer
        conn = ["--port", str(server.port), "--timeout", "15"]
        btview = [sys.executable, "-m", "btview"]
        rec = tmp_path / "session.btv.jsonl"
        results = await asyncio.gather(
            run_proc(*btview, "snapshot", *conn, "--uid", "--no-color", "--ascii", "--no-legend"),
            run_proc(*btview, "info", *conn, "--samples", "5", "--no-color"),
            run_proc(*btview, "blackboard", *conn, "--json", "Main", "sub"),
            run_proc(*btview, "echo", *conn, "--json", "--duration", "3.0", "--exit-on-error"),
            run_proc(*btview, "record", *conn, "--duration", "3.0", "-o", str(rec)))  # the clock runs while it connects
        flipper.cancel()
        await ticker.stop()
    (rc1, snap, e1), (rc2, info, e2), (rc3, bb, e3), (rc4, echo, e4), (rc5, _, e5) = results
    assert rc1 == 0 and f"{count} nodes" in snap, e1
    assert rc2 == 0 and any(line.split()[:2] == ["nodes", str(count)] for line in info.splitlines()), e2
    assert rc3 == 0 and json.loads(bb)["sub"] == {"local_n": 7}, e3
    lines = [json.loads(line) for line in echo.splitlines() if line.startswith("{")]
    assert rc4 == 0 and lines and all("uid" in line for line in lines), e4
    rows = [json.loads(line) for line in rec.read_text().splitlines() if line.strip()]
    assert rc5 == 0 and rows[0].get("kind") == "header" and len(rows) > 1, e5


def test_protocol_helpers() -> None:
    assert P.pack_transitions([(1, 2, 3)]) == b"\x01\x00\x00\x00\x00\x00\x02\x00\x03"
    assert P.unpack_transitions(P.pack_transitions([(2**40, 65535, 4)])) == [(2**40, 65535, 4)]
    assert P.msgpack_encode({"b": [1, -1, -33, 300], "a": None}) == msgpack.packb({"a": None, "b": [1, -1, -33, 300]})
    assert P.msgpack_encode(float("inf"))[:1] == b"\xcb" and P.msgpack_encode(1e300)[:1] == b"\xcb"
    assert struct.unpack(">f", P.msgpack_encode(0.5)[1:])[0] == 0.5


async def test_cli_wiring(tmp_path) -> None:
    import argparse

    from groot.btlog import read_btlog
    from groot.cli import Monitoring, add_arguments

    parser = argparse.ArgumentParser()
    add_arguments(parser)
    assert parser.parse_args([]).groot is None
    assert parser.parse_args(["--groot"]).groot == 1667
    args = parser.parse_args(["--groot", "0", "--btlog", str(tmp_path / "r.btlog"), "--groot-status", "exact"])
    tree, _ = build()
    tree.set_clock(asyncio.get_running_loop().time)
    async with Monitoring.from_args(tree, args) as monitoring:
        assert monitoring.server.tracker.mode == "exact" and monitoring.server.host == "127.0.0.1"
        for _ in range(3):
            tree.tick_once()
        with GrootClient(monitoring.server.port) as client:
            assert len(await call(client.status)) == sum(len(r.nodes) for r in tree.subtrees)
    assert monitoring.server is None and len(read_btlog(tmp_path / "r.btlog")[2]) > 10
