"""Load-time checks BT.CPP 4.10 makes, and the exception class it throws for each: a located
``XMLLoadError`` that is also the BT.CPP class (RuntimeError for most, LogicError for a literal
that does not convert)."""

from __future__ import annotations

import pytest

from bt_runtime import (
    BehaviorTreeFactory,
    BTRuntimeError,
    LogicError,
    NodeStatus,
    SyncActionNode,
    XMLLoadError,
    input_port,
)
from tests.engine.helpers import doc


class Point:
    """A user type with no string converter."""


class ParsedPoint:
    def __init__(self, x: float, y: float):
        self.x, self.y = x, y

    @classmethod
    def from_string(cls, text: str) -> ParsedPoint:
        x, y = text.split(";")  # ValueError when a coordinate is missing
        return cls(float(x), float(y))


class UsesPoint(SyncActionNode):
    @staticmethod
    def provided_ports():
        return [input_port("point", Point)]

    def tick(self):
        return NodeStatus.SUCCESS


class UsesParsedPoint(SyncActionNode):
    @staticmethod
    def provided_ports():
        return [input_port("point", ParsedPoint)]

    def tick(self):
        return NodeStatus.SUCCESS if self.get_input("point").y == 2.5 else NodeStatus.FAILURE


@pytest.fixture
def factory():
    factory = BehaviorTreeFactory()
    factory.register_node_type(UsesPoint)
    factory.register_node_type(UsesParsedPoint)
    return factory


def two_async(control: str) -> str:
    return doc(f"<{control}><AsyncSequence><AlwaysFailure/></AsyncSequence>"
               f"<AsyncSequence><AlwaysSuccess/></AsyncSequence></{control}>")


def test_reactive_sequence_with_two_async_children_is_refused(factory):
    with pytest.raises(BTRuntimeError, match="cannot have more than one async child") as info:
        factory.create_tree_from_text(two_async("ReactiveSequence"))
    assert info.value.element == "ReactiveSequence" and info.value.line == 1


def test_reactive_sequence_with_one_async_child_loads(factory):
    tree = factory.create_tree_from_text(doc(
        "<ReactiveSequence><AlwaysSuccess/><AsyncSequence><AlwaysSuccess/></AsyncSequence></ReactiveSequence>"))
    assert tree.tick_while_running() is NodeStatus.SUCCESS


def test_reactive_fallback_has_no_such_check(factory):
    """4.10 checks only ReactiveSequence."""
    assert factory.create_tree_from_text(two_async("ReactiveFallback")).tick_while_running() is NodeStatus.SUCCESS


@pytest.mark.parametrize("literal", ["1;2", ""])
def test_literal_of_a_type_without_converter_is_refused_at_build(factory, literal):
    with pytest.raises(LogicError, match='The port with name "point" and value ".*" can not be converted') as info:
        factory.create_tree_from_text(doc(f'<UsesPoint point="{literal}"/>'))
    assert isinstance(info.value, XMLLoadError) and info.value.element == "UsesPoint"


def test_blackboard_reference_of_a_type_without_converter_loads(factory):
    tree = factory.create_tree_from_text(doc('<UsesPoint point="{p}"/>'))
    assert tree.tick_once() is NodeStatus.SUCCESS


def test_literal_that_its_converter_refuses_is_a_logic_error(factory):
    with pytest.raises(LogicError, match="can not be converted to ParsedPoint"):
        factory.create_tree_from_text(doc('<UsesParsedPoint point="1.5"/>'))
    assert factory.create_tree_from_text(doc('<UsesParsedPoint point="1.5;2.5"/>')).tick_once() is NodeStatus.SUCCESS


@pytest.mark.parametrize("body, extra, message", [
    ("<AlwaysSuccess", "", "Error parsing the XML"),
    ("<NoSuchNode/>", "", "Node not recognized: NoSuchNode"),
    ('<AlwaysSuccess typo="1"/>', "", "a port with name \\[typo\\] is found in the XML"),
    ("<TryCatch><AlwaysSuccess/></TryCatch>", "", "must have at least 2 children"),
    ('<Sequence><SubTree ID="S" name="s"/><SubTree ID="S" name="s"/></Sequence>',
     '<BehaviorTree ID="S"><AlwaysSuccess/></BehaviorTree>', "Duplicate SubTree path"),
    ('<SubTree ID="Main"/>', "", "Recursive behavior tree cycle"),
])
def test_load_errors_are_runtime_errors_with_a_location(factory, body, extra, message):
    with pytest.raises(BTRuntimeError, match=message) as info:
        factory.create_tree_from_text(doc(body, extra))
    assert isinstance(info.value, XMLLoadError) and not isinstance(info.value, LogicError)
    assert info.value.line == 1


def test_bad_precondition_script_is_a_logic_error(factory):
    with pytest.raises(LogicError, match="Error in the script"):
        factory.create_tree_from_text(doc('<AlwaysSuccess _skipIf="a == (1"/>'))


def test_bad_script_node_code_is_a_runtime_error(factory):
    with pytest.raises(BTRuntimeError, match="Error in the script") as info:
        factory.create_tree_from_text(doc('<Script code="a := (1"/>'))
    assert info.value.element == "Script"


def test_registered_behavior_trees_are_sorted(factory):
    factory.register_behavior_tree_from_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Zeta"><AlwaysSuccess/></BehaviorTree>'
        '<BehaviorTree ID="Alpha"><AlwaysSuccess/></BehaviorTree><BehaviorTree ID="Mid"><AlwaysSuccess/></BehaviorTree>'
        '</root>')
    assert factory.registered_behavior_trees() == ["Alpha", "Mid", "Zeta"]


@pytest.mark.parametrize("name", ["name", "ID", "_skipIf", "_private", "1port", "port name", ""])
def test_declaring_a_port_with_a_refused_name_is_a_runtime_error(name):
    with pytest.raises(BTRuntimeError):
        input_port(name, int)


@pytest.mark.parametrize("name", ["ID", "name", "_post", "input value", "1port"])
def test_subtree_model_port_names_are_checked(factory, name):
    text = ('<root BTCPP_format="4" main_tree_to_execute="Main"><BehaviorTree ID="Main"><AlwaysSuccess/>'
            f'</BehaviorTree><TreeNodesModel><SubTree ID="S"><input_port name="{name}"/></SubTree>'
            '</TreeNodesModel></root>')
    with pytest.raises(BTRuntimeError, match="Invalid port name") as info:
        factory.create_tree_from_text(text)
    assert info.value.element == "input_port"


class Vector3:
    def __init__(self, x: float, y: float, z: float):
        self.x, self.y, self.z = x, y, z

    @classmethod
    def from_json(cls, data: dict) -> Vector3:
        return cls(data["x"], data["y"], data["z"])


class UsesVector(SyncActionNode):
    @staticmethod
    def provided_ports():
        return [input_port("v", Vector3)]

    def tick(self):
        v = self.get_input("v")
        return NodeStatus.SUCCESS if (v.x, v.y, v.z) == (2.1, 4.2, 6.3) else NodeStatus.FAILURE


def test_json_literal_of_a_type_with_from_json(factory):
    """BT.CPP's generic converter reads ``json:{...}`` through the type's JSON conversion."""
    factory.register_node_type(UsesVector)
    tree = factory.create_tree_from_text(doc("""<UsesVector v='json:{"x":2.1, "y":4.2, "z":6.3}'/>"""))
    assert tree.tick_once() is NodeStatus.SUCCESS
    with pytest.raises(LogicError, match="can not be converted to Vector3"):
        factory.create_tree_from_text(doc('<UsesVector v="2.1;4.2;6.3"/>'))
