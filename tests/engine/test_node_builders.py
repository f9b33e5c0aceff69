"""The builders the factory registers for speed (one frame instead of a type call through the
``__init__`` chain) make the same node as the class's own constructor, and a built tree's
paths are the ones BT.CPP gives (joined lazily)."""

from __future__ import annotations

import pytest

from bt_runtime import BehaviorTreeFactory, NodeStatus
from bt_runtime.builtins.sequences import (
    AsyncFallbackNode,
    AsyncSequenceNode,
    FallbackNode,
    SequenceNode,
    SequentialNode,
)
from bt_runtime.node import NodeConfig, SimpleActionNode, SimpleConditionNode


def _state(node: object) -> dict:
    """Every slot and instance attribute of ``node``, the cell by its contents."""
    state = {}
    for cls in type(node).__mro__:
        for slot in cls.__dict__.get("__slots__", ()):
            if slot in ("__dict__", "__weakref__") or not hasattr(node, slot):
                continue
            value = getattr(node, slot)
            if slot == "_cell":
                value = (type(value), value.status, value.fast, value.node is node)
            state[slot] = value
    state["__dict__"] = dict(node.__dict__)
    return state


@pytest.mark.parametrize(("builder", "kwargs"), [
    (SequenceNode, {}), (FallbackNode, {"fallback": True}), (AsyncSequenceNode, {"asynch": True}),
    (AsyncFallbackNode, {"fallback": True, "asynch": True})])
def test_sequential_builders_make_what_the_constructor_makes(builder, kwargs) -> None:
    config = NodeConfig()
    assert _state(builder("n", config)) == _state(SequentialNode("n", config, **kwargs))


@pytest.mark.parametrize("cls", [SimpleConditionNode, SimpleActionNode])
def test_simple_node_builders_make_what_the_constructor_makes(cls) -> None:
    def fn(node):
        return NodeStatus.SUCCESS

    config = NodeConfig()
    built = cls.builder(fn)("n", config)
    assert type(built) is cls
    assert _state(built) == _state(cls("n", config, fn))


def test_paths_of_named_and_unnamed_nodes() -> None:
    f = BehaviorTreeFactory()
    f.register_simple_condition("Ok", lambda node: NodeStatus.SUCCESS)
    tree = f.create_tree_from_text(
        '<root BTCPP_format="4" main_tree_to_execute="Main">'
        '<BehaviorTree ID="Sub"><Sequence name="inner"><Ok/><Ok name="Ok"/><Ok name="x"/></Sequence></BehaviorTree>'
        '<BehaviorTree ID="Main"><Sequence><Ok name="first"/><SubTree ID="Sub"/><SubTree ID="Sub" name="s2"/>'
        '</Sequence></BehaviorTree></root>')
    assert [n.full_path for n in tree.nodes()] == [
        "Sequence::1", "first", "Sub::3", "Sub::3/inner", "Sub::3/Ok::5", "Sub::3/Ok::6", "Sub::3/x",
        "s2", "s2/inner", "s2/Ok::10", "s2/Ok::11", "s2/x"]
    node = tree.root_node
    node.config.path = "renamed"
    assert node.full_path == "renamed"


def test_every_built_node_has_read_only_port_maps() -> None:
    """One rule for every node an XML build makes, whatever path built its ports (first or
    repeated attribute set, a one-port literal, defaults only, no ports): the maps are
    read-only, so code writing into them fails on every node rather than on some."""
    factory = BehaviorTreeFactory()
    xml = """<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>
      <SetBlackboard value="1" output_key="a"/><SetBlackboard value="1" output_key="a"/>
      <SetBlackboard value="1" output_key="a"/><SetBlackboard name="s" value="2" output_key="b"/><Script code="n := 2"/>
      <Script code="c := 1"/><Script name="t" code="c := 2"/><Repeat num_cycles="2"><AlwaysSuccess/></Repeat><Repeat num_cycles="{n}"><AlwaysSuccess/></Repeat>
      <Delay delay_msec="0"><AlwaysSuccess/></Delay><AlwaysSuccess/>
    </Sequence></BehaviorTree></root>"""
    tree = factory.create_tree_from_text(xml)
    nodes = list(tree.nodes())
    assert len(nodes) >= 12
    for node in nodes:
        for ports in (node.config.input_ports, node.config.output_ports):
            with pytest.raises(TypeError):
                ports["x"] = "y"  # type: ignore[index]
    assert tree.tick_while_running() is NodeStatus.SUCCESS
