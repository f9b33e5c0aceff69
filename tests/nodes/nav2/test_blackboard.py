"""Writes through a SubTree remapping into a typed parent entry (what the Nav2 nodes need when
Nav2's tree runs as a SubTree, as in trees/navigation.xml).

A node writes with its output port's declared type as the value's static type (as C++'s
``setOutput<T>``), so an ``int`` error code reaches an ``unsigned short`` entry and a Path a
``nav_msgs::msg::Path`` entry. A host write of an inferred type into a remapped typed entry
stays strict, as in BT.CPP (spec 8.4).
"""

from __future__ import annotations

import numpy as np
import pytest

from bt_runtime import BehaviorTreeFactory, NodeStatus, SyncActionNode
from bt_runtime.blackboard import Blackboard
from bt_runtime.errors import LogicError
from bt_runtime.ports import PortType, output_port
from bt_runtime.runtime.messages import Path

UINT16 = PortType("unsigned short", "int", int, lo=0, hi=65535)
PATH = PortType("nav_msgs::msg::Path", "custom", Path)
PLAN = Path(1.0, np.zeros((2, 3)))


class Planner(SyncActionNode):
    @classmethod
    def provided_ports(cls):
        return [output_port("error_code_id", UINT16), output_port("path", PATH)]

    def tick(self):
        self.set_output("error_code_id", 105)
        self.set_output("path", PLAN)
        return NodeStatus.SUCCESS


XML = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main"><Sequence>
    <Planner error_code_id="{code}" path="{path}"/>
    <SubTree ID="Sub" {remap}/>
  </Sequence></BehaviorTree>
  <BehaviorTree ID="Sub"><Planner error_code_id="{code}" path="{path}"/></BehaviorTree>
</root>"""


@pytest.mark.parametrize("remap", ['_autoremap="true"', 'code="{code}" path="{path}"'])
def test_node_writes_reach_typed_parent_entries_through_subtrees(remap):
    factory = BehaviorTreeFactory()
    factory.register_node_type(Planner)
    tree = factory.create_tree_from_text(XML.replace("{remap}", remap))
    assert tree.tick_once() is NodeStatus.SUCCESS
    bb = tree.root_blackboard
    assert bb.get("code") == 105 and bb.get_entry("code").type == UINT16
    assert bb.get("path") is PLAN
    assert [k for rec in tree.subtrees[1:] for k in rec.blackboard.keys()] == []  # noqa: SIM118 - Blackboard is not iterable


def test_host_writes_into_remapped_typed_entries_stay_strict_like_btcpp():
    parent = Blackboard()
    parent.create_entry("code", UINT16)
    child = Blackboard(parent)
    child.enable_auto_remapping(True)
    with pytest.raises(LogicError, match="once declared"):
        child.set("code", 105)  # an inferred int is not an unsigned short
    child.set("code", 105, UINT16)  # with its static type it is
    assert parent.get("code") == 105


def test_wrong_value_for_a_typed_output_port_is_refused():
    class Bad(SyncActionNode):
        @classmethod
        def provided_ports(cls):
            return [output_port("path", PATH)]

        def tick(self):
            self.set_output("path", "not a path")
            return NodeStatus.SUCCESS

    factory = BehaviorTreeFactory()
    factory.register_node_type(Bad)
    tree = factory.create_tree_from_text('<root BTCPP_format="4"><BehaviorTree ID="M"><Bad path="{p}"/>'
                                         '</BehaviorTree></root>')
    with pytest.raises(Exception, match="declared"):
        tree.tick_once()
