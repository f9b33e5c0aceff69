"""Our Groot2 server against BT.CPP's own (behaviortreepy's Groot2Publisher, BT.CPP 4.8.2):
the same XML and leaf behaviour in both engines, queried with the same client code, tick after
tick: FULLTREE (node order, uids, full paths, attributes), STATUS bytes, BLACKBOARD msgpack."""

from __future__ import annotations

import asyncio
import xml.etree.ElementTree as ET

import msgpack
import pytest

from bt_runtime import BehaviorTreeFactory, Blackboard, NodeStatus
from groot import GrootServer
from groot import protocol as P
from groot.testing import GrootClient, free_port_pair

pytestmark = pytest.mark.oracle
bt = pytest.importorskip("behaviortreepy")

XML = """
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
MOVE_TICKS = 2


class Behaviour:
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
        return "SUCCESS" if self.state["moves"][uid] >= MOVE_TICKS else "RUNNING"

    def move_halted(self, node):
        self.state["moves"].pop(self.uid_of(node), None)


def register(factory, behaviour: Behaviour, status) -> None:
    def wrap(fn):
        return lambda node: getattr(status, fn(node))

    factory.register_simple_condition("BatteryOK", wrap(behaviour.battery_ok))
    factory.register_simple_action("TickCounter", wrap(behaviour.tick_counter))
    factory.register_simple_action("FlakyAction", wrap(behaviour.flaky))
    factory.register_simple_stateful_action("MoveBase", wrap(behaviour.move_start), wrap(behaviour.move_running),
                                            behaviour.move_halted)


def reference_tree():
    bb = bt.Blackboard.create(None)
    bb.set_string("goal_a", "kitchen")
    bb.set_string("goal_b", "dock")
    bb.set_double("battery", 0.97)
    bb.set_int("ticks", 0)
    bb.set_bool("skip_flag", False)
    f = bt.BehaviorTreeFactory()
    register(f, Behaviour(bb.set_int, bb.set_bool, lambda n: n.uid()), bt.NodeStatus)
    return f.create_tree_from_text(XML, bb), bb


def our_tree():
    bb = Blackboard()
    for key, value in (("goal_a", "kitchen"), ("goal_b", "dock"), ("battery", 0.97), ("ticks", 0),
                       ("skip_flag", False)):
        bb.set(key, value)
    f = BehaviorTreeFactory()
    register(f, Behaviour(bb.set, bb.set, lambda n: n.uid), NodeStatus)
    return f.create_tree_from_text(XML, bb)


def elements(xml: str) -> list[tuple]:
    root = ET.fromstring(xml)
    out = []
    for block in root.findall("BehaviorTree"):
        out.append(("BehaviorTree", dict(block.attrib)))
        out += [(e.tag, dict(e.attrib), len(e)) for e in block.iter() if e is not block]
    return out


async def test_fulltree_status_blackboard_match_btcpp() -> None:
    ref_tree, _ = reference_tree()
    port = free_port_pair()
    publisher = bt.Groot2Publisher(ref_tree, port)
    ours = our_tree()
    exact = GrootServer(ours, port=0, status_mode="exact")
    sampled = GrootServer(ours, port=0)
    await exact.start()
    await sampled.start()
    clients = [GrootClient(port), GrootClient(exact.port), GrootClient(sampled.port)]
    ref, mine, mine_sampled = clients
    try:
        ref_xml, our_xml = [await asyncio.to_thread(c.fulltree) for c in (ref, mine)]
        assert elements(our_xml) == elements(ref_xml)
        info = ET.fromstring(our_xml)
        names = [info.find("BehaviorTree").get("ID")] + [b.get("_fullpath") for b in info.findall("BehaviorTree")][1:]
        assert names[0] == "MainTree" and len(names) == 5

        async def both(fn, *args):
            return await asyncio.to_thread(fn, ref, *args), await asyncio.to_thread(fn, mine, *args)

        seen_codes: set[int] = set()
        for tick in range(14):
            if tick:
                assert ref_tree.tick_once().name == ours.tick_once().name, f"tick {tick}"
            ref_status, our_status = await both(GrootClient.status_bytes)
            assert our_status == ref_status, f"STATUS differs after {tick} ticks"
            seen_codes |= set(our_status[2::3])
            # sampled mode: nodes that are active right now are reported exactly
            sampled_codes = dict(await asyncio.to_thread(mine_sampled.status))
            for uid, code in P.unpack_status(our_status):
                if code in (1, 2, 3):
                    assert sampled_codes[uid] == code
            ref_bb, our_bb = await both(GrootClient.blackboard, *names)
            assert msgpack.unpackb(our_bb) == msgpack.unpackb(ref_bb), f"BLACKBOARD differs after {tick} ticks"
            assert our_bb == ref_bb  # byte for byte: same int widths, float32/64 choice, key order
        # halting a running tree: RUNNING nodes go to 11 (idle after running)
        assert ref_tree.tick_once().name == ours.tick_once().name == "RUNNING"
        ref_tree.halt_tree()
        ours.halt_tree()
        ref_status, our_status = await both(GrootClient.status_bytes)
        assert our_status == ref_status
        seen_codes |= set(our_status[2::3])
        assert {0, 1, 2, 3, 11, 12, 13} <= seen_codes  # the comparison covered every kind of code
    finally:
        for c in clients:
            c.close()
        await exact.stop()
        await sampled.stop()
        del publisher
