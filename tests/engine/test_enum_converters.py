"""BT.CPP's built-in string converters for NodeType and PortDirection, through a port and
through ``convert_from_string``."""

from __future__ import annotations

import pytest

from bt_runtime import (
    BehaviorTreeFactory,
    BTRuntimeError,
    NodeStatus,
    NodeType,
    PortDirection,
    SyncActionNode,
)
from bt_runtime.ports import convert_from_string, input_port
from tests.engine.helpers import doc


@pytest.mark.parametrize("text, expected", [
    ("Action", NodeType.ACTION), ("Condition", NodeType.CONDITION), ("Control", NodeType.CONTROL),
    ("Decorator", NodeType.DECORATOR), ("SubTree", NodeType.SUBTREE),
    ("ACTION", NodeType.UNDEFINED), ("anything", NodeType.UNDEFINED), ("3", NodeType.CONTROL),
])
def test_node_type_from_string(text, expected):
    assert convert_from_string(NodeType, text) is expected


@pytest.mark.parametrize("text, expected", [
    ("Input", PortDirection.INPUT), ("INPUT", PortDirection.INPUT), ("Output", PortDirection.OUTPUT),
    ("OUTPUT", PortDirection.OUTPUT), ("InOut", PortDirection.INOUT), ("INOUT", PortDirection.INOUT),
])
def test_port_direction_from_string(text, expected):
    assert convert_from_string(PortDirection, text) is expected


@pytest.mark.parametrize("text", ["input", "Inout", ""])
def test_unknown_port_direction_is_a_runtime_error(text):
    with pytest.raises(BTRuntimeError, match="Cannot convert this to PortDirection"):
        convert_from_string(PortDirection, text)


def test_port_direction_names_round_trip():
    assert [convert_from_string(PortDirection, d.display_name) for d in PortDirection] == list(PortDirection)


class Classify(SyncActionNode):
    @staticmethod
    def provided_ports():
        return [input_port("kind", NodeType), input_port("direction", PortDirection)]

    def tick(self):
        self.config.blackboard.set("seen", f"{self.get_input('kind').name}/{self.get_input('direction').name}")
        return NodeStatus.SUCCESS


def test_enum_ports_read_btcpp_names():
    factory = BehaviorTreeFactory()
    factory.register_node_type(Classify)
    tree = factory.create_tree_from_text(doc('<Classify kind="Decorator" direction="OUTPUT"/>'))
    assert tree.tick_once() is NodeStatus.SUCCESS
    assert tree.root_blackboard.get("seen") == "DECORATOR/OUTPUT"
