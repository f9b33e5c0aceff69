"""The public API names users rely on (README, DESIGN) keep existing and working together."""

from __future__ import annotations

import inspect

import bt_runtime
from bt_runtime import BehaviorTreeFactory, NodeStatus, SyncActionNode, input_port, output_port
from tests.engine.helpers import doc


def test_top_level_exports():
    for name in ("BehaviorTreeFactory", "NodeStatus", "NodeType", "PortDirection", "Tree", "TreeNode",
                 "SyncActionNode", "StatefulActionNode", "AsyncActionNode", "ConditionNode", "ControlNode",
                 "DecoratorNode", "Blackboard", "BehaviorTreeException", "LogicError", "BTRuntimeError",
                 "XMLLoadError", "NodeExecutionError", "input_port", "output_port", "bidirectional_port"):
        assert hasattr(bt_runtime, name), name
        assert name in bt_runtime.__all__


def test_node_status_values():
    assert [s.name for s in NodeStatus] == ["IDLE", "RUNNING", "SUCCESS", "FAILURE", "SKIPPED"]
    assert [int(s) for s in NodeStatus] == [0, 1, 2, 3, 4]


def test_factory_methods():
    for name in ("register_simple_action", "register_simple_condition", "register_simple_stateful_action",
                 "register_node_type", "register_behavior_tree_from_text", "register_behavior_tree_from_file",
                 "create_tree_from_text", "create_tree_from_file", "create_tree", "register_models_from_file",
                 "registered_behavior_trees", "register_scripting_enum"):
        assert callable(getattr(BehaviorTreeFactory, name)), name
    params = inspect.signature(BehaviorTreeFactory.register_node_type).parameters
    assert list(params)[:3] == ["self", "cls", "name"]


class Greet(SyncActionNode):
    @classmethod
    def provided_ports(cls):
        return [input_port("who", str, "world"), output_port("said", str)]

    def tick(self) -> NodeStatus:
        self.set_output("said", f"hello {self.get_input('who')}")
        return NodeStatus.SUCCESS


def test_end_to_end_api():
    factory = BehaviorTreeFactory()
    factory.register_node_type(Greet)
    factory.register_node_type(Greet, "Hello")
    factory.register_simple_condition("Ready", lambda node: NodeStatus.SUCCESS)
    factory.register_simple_action("Noop", lambda node: NodeStatus.SUCCESS)
    factory.register_simple_stateful_action("Twice", lambda node: NodeStatus.RUNNING,
                                            lambda node: NodeStatus.SUCCESS)
    tree = factory.create_tree_from_text(doc('<Sequence><Ready/><Twice/><Greet said="{a}"/>'
                                             '<Hello who="you" said="{b}"/><Noop/></Sequence>'))
    assert tree.tick_once() is NodeStatus.RUNNING
    assert tree.tick_exactly_once() is NodeStatus.SUCCESS
    assert tree.tick_while_running(0.001) is NodeStatus.SUCCESS  # a whole new run
    tree.halt_tree()
    bb = tree.root_blackboard
    assert bb.get("a") == "hello world" and bb.get("b") == "hello you"
    bb.set("extra", 1)
    assert set(bb.keys()) >= {"a", "b", "extra"}
    node = tree.root_node
    assert (node.name, node.uid, node.full_path, node.status) == ("Sequence", 1, "Sequence::1", NodeStatus.IDLE)


async def test_async_api():
    factory = BehaviorTreeFactory()
    tree = factory.create_tree_from_text(doc('<Sleep msec="1"/>'))
    assert await tree.tick_while_running_async(0.001) is NodeStatus.SUCCESS
