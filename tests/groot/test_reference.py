"""Our Groot2 server against BT.CPP's own (behaviortreepy's Groot2Publisher, BT.CPP 4.8.2):
the same XML and leaf behaviour in both engines, queried with the same client code, tick after
tick: FULLTREE (node order, uids, full paths, attributes), STATUS bytes, BLACKBOARD msgpack."""

from __future__ import annotations

import asyncio
import xml.etree.ElementTree as ET

import msgpack
import pytest

from groot import GrootServer
from groot import protocol as P
from groot.testing import GrootClient, demo_tree, free_port_pair
from tests.groot.reference import reference_tree

pytestmark = pytest.mark.oracle
bt = pytest.importorskip("behaviortreepy")

def our_tree():
    return demo_tree()


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
