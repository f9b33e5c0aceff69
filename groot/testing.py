"""Helpers for testing Groot2 interoperability: a blocking protocol client, port picking, the
shared checkers' location. Used by ``tests/groot/`` and ``bench/groot.py``."""

from __future__ import annotations

import json
import os
import socket
from pathlib import Path
from typing import Any

import zmq

from . import protocol as P


def find_shared() -> Path | None:
    """The project's ``shared`` folder: ``$BT_RUNTIME_SHARED``, else a ``shared`` folder beside
    the repository or one of its parents; None when absent."""
    env = os.environ.get("BT_RUNTIME_SHARED")
    if env:
        return Path(env) if Path(env).is_dir() else None
    for parent in Path(__file__).resolve().parents[1:]:
        if (parent / "shared" / "tools" / "groot2").is_dir():
            return parent / "shared"
    return None


def groot2_tools() -> Path | None:
    shared = find_shared()
    tools = shared / "tools" / "groot2" if shared else None
    return tools if tools is not None and (tools / "groot2_probe.py").is_file() else None


def free_port_pair(host: str = "127.0.0.1") -> int:
    """A port p such that p and p+1 are both free right now (TCP)."""
    for _ in range(200):
        with socket.socket() as s:
            s.bind((host, 0))
            port = s.getsockname()[1]
        if port >= 65535:
            continue
        with socket.socket() as s2:
            try:
                s2.bind((host, port + 1))
            except OSError:
                continue
        return port
    raise OSError("no free port pair")


class GrootClient:
    """A lock-step REQ client of the Groot2 protocol (what Groot2 itself does)."""

    def __init__(self, port: int, host: str = "127.0.0.1", timeout: float = 2.0):
        self.ctx = zmq.Context()
        self.sock = self.ctx.socket(zmq.REQ)
        self.sock.setsockopt(zmq.LINGER, 0)
        self.sock.setsockopt(zmq.RCVTIMEO, int(timeout * 1000))
        self.sock.setsockopt(zmq.SNDTIMEO, int(timeout * 1000))
        self.sock.connect(f"tcp://{host}:{port}")
        self.host, self.port = host, port

    def raw(self, frames: list[bytes]) -> list[bytes]:
        self.sock.send_multipart(frames)
        return self.sock.recv_multipart()

    def request(self, rtype: int | str, payload: bytes | str | None = None) -> list[bytes]:
        """Reply frames after checking the header; ``[b"error", msg]`` errors are returned as is."""
        if isinstance(rtype, str):
            rtype = ord(rtype)
        header = P.request_header(rtype)
        frames = [header]
        if payload is not None:
            frames.append(payload.encode() if isinstance(payload, str) else payload)
        reply = self.raw(frames)
        if reply[0] == b"error":
            return reply
        if len(reply[0]) != P.REPLY_HEADER_SIZE or reply[0][:6] != bytes((2,)) + header[1:]:
            raise AssertionError(f"bad reply header {reply[0].hex()} for {header.hex()}")
        return reply

    def uuid(self) -> bytes:
        return self.request(P.STATUS)[0][6:]

    def fulltree(self) -> str:
        return self.request(P.FULLTREE)[1].decode()

    def status(self) -> list[tuple[int, int]]:
        return P.unpack_status(self.request(P.STATUS)[1])

    def status_bytes(self) -> bytes:
        return self.request(P.STATUS)[1]

    def blackboard(self, *names: str) -> bytes:
        return self.request(P.BLACKBOARD, ";".join(names))[1]

    def insert_hook(self, uid: int, *, mode: int = 0, desired: str = "SKIPPED", once: bool = False,
                    position: int = 0, enabled: bool = True) -> list[bytes]:
        hook = {"enabled": enabled, "uid": uid, "mode": mode, "once": once,
                "desired_status": desired, "position": position}
        return self.request(P.HOOK_INSERT, json.dumps(hook))

    def unlock(self, uid: int, desired: str = "SKIPPED", remove: bool = False,
               position: int = 0) -> list[bytes]:
        data = {"uid": uid, "desired_status": desired, "position": position, "remove_when_done": remove}
        return self.request(P.BREAKPOINT_UNLOCK, json.dumps(data))

    def hooks(self) -> list[dict[str, Any]]:
        return json.loads(self.request(P.HOOKS_DUMP)[1])

    def close(self) -> None:
        self.sock.close(linger=0)
        self.ctx.term()

    def __enter__(self) -> GrootClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


# ---------------------------------------------------------------------------------------------
# A demo tree shared by the tests and the benchmark (same XML and leaves in BT.CPP and here)
# ---------------------------------------------------------------------------------------------

DEMO_XML = """
<root BTCPP_format="4" main_tree_to_execute="MainTree">
  <BehaviorTree ID="MainTree">
    <Sequence name="mission">
      <RunOnce name="init_once">
        <Script name="init_bb" code="mission := 'patrol'; speed := 1.5; laps := 0"/>
      </RunOnce>
      <ReactiveSequence name="guarded">
        <BatteryOK name="battery_ok"/>
        <Fallback name="pick_task">
          <Inverter name="never"><AlwaysSuccess name="always_ok"/></Inverter>
          <Sequence name="do_work">
            <Parallel name="move_both" success_count="-1" failure_count="1">
              <SubTree ID="Navigate" name="nav_a" goal="{goal_a}" result="{result_a}"/>
              <SubTree ID="Navigate" name="nav_b" goal="{goal_b}" result="{result_b}"/>
            </Parallel>
            <RetryUntilSuccessful name="retry_flaky" num_attempts="3"><FlakyAction name="flaky"/></RetryUntilSuccessful>
            <ForceSuccess name="ignore_failure"><AlwaysFailure name="fails"/></ForceSuccess>
            <AlwaysSuccess name="sometimes_skipped" _skipIf="skip_flag"/>
            <TickCounter name="count"/>
            <Script name="count_lap" code="laps := laps + 1"/>
          </Sequence>
        </Fallback>
      </ReactiveSequence>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Navigate">
    <Sequence name="nav_seq">
      <ScriptCondition name="has_goal" code="goal != ''"/>
      <MoveBase name="move_base"/>
      <SubTree ID="Approach" _autoremap="true"/>
      <Script name="report" code="result := 'arrived'; legs := 1"/>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Approach">
    <Sequence name="approach_seq"><Script name="approach_mark" code="approach_done := 2"/></Sequence>
  </BehaviorTree>
</root>
"""
DEMO_MOVE_TICKS = 2


class DemoBehaviour:
    """The leaves, written once for both engines (they only differ in how they reach the
    blackboard and the node uid)."""

    def __init__(self, set_int, set_bool, uid_of):
        self.state = {"ticks": 0, "flaky": 0, "moves": {}}
        self.set_int, self.set_bool, self.uid_of = set_int, set_bool, uid_of

    def battery_ok(self, node):
        return "SUCCESS"

    def tick_counter(self, node):
        self.state["ticks"] += 1
        self.set_int("ticks", self.state["ticks"])
        self.set_bool("skip_flag", self.state["ticks"] % 2 == 0)
        return "SUCCESS"

    def flaky(self, node):
        self.state["flaky"] += 1
        return "SUCCESS" if self.state["flaky"] % 2 == 0 else "FAILURE"

    def move_start(self, node):
        self.state["moves"][self.uid_of(node)] = 0
        return "RUNNING"

    def move_running(self, node):
        uid = self.uid_of(node)
        self.state["moves"][uid] = self.state["moves"].get(uid, 0) + 1
        return "SUCCESS" if self.state["moves"][uid] >= DEMO_MOVE_TICKS else "RUNNING"

    def move_halted(self, node):
        self.state["moves"].pop(self.uid_of(node), None)


def register_demo(factory: Any, behaviour: DemoBehaviour, status: Any) -> None:
    def wrap(fn):
        return lambda node: getattr(status, fn(node))

    factory.register_simple_condition("BatteryOK", wrap(behaviour.battery_ok))
    factory.register_simple_action("TickCounter", wrap(behaviour.tick_counter))
    factory.register_simple_action("FlakyAction", wrap(behaviour.flaky))
    factory.register_simple_stateful_action("MoveBase", wrap(behaviour.move_start), wrap(behaviour.move_running),
                                            behaviour.move_halted)


def demo_tree(blackboard: Any = None) -> Any:
    """The demo tree built with bt_runtime (31 nodes, two instances of a nested subtree)."""
    from bt_runtime import BehaviorTreeFactory, Blackboard, NodeStatus

    bb = blackboard if blackboard is not None else Blackboard()
    for key, value in (("goal_a", "kitchen"), ("goal_b", "dock"), ("battery", 0.97), ("ticks", 0),
                       ("skip_flag", False)):
        bb.set(key, value)
    f = BehaviorTreeFactory()
    register_demo(f, DemoBehaviour(bb.set, bb.set, lambda n: n.uid), NodeStatus)
    return f.create_tree_from_text(DEMO_XML, bb)
