"""Simple decorators (``register_simple_decorator``) and subclasses of their node class: the
one-frame tick keeps BT.CPP's order of status changes, and an overridden ``tick()`` is used."""

from __future__ import annotations

from bt_runtime import BehaviorTreeFactory, NodeStatus
from bt_runtime.node import SimpleDecoratorNode, TreeNodeManifest
from bt_runtime.status import NodeType
from tests.engine.helpers import doc

S, F, R = NodeStatus.SUCCESS, NodeStatus.FAILURE, NodeStatus.RUNNING


def _factory() -> BehaviorTreeFactory:
    factory = BehaviorTreeFactory()
    factory.register_simple_action("A", lambda node: S)
    factory.register_simple_decorator("Flip", lambda status, node: F if status is S else S)
    return factory


def test_the_decorators_status_changes_before_its_completed_child_is_reset():
    """BT.CPP DecoratorNode::executeTick stores the decorator's status, then resets the child:
    observers (Groot2, the recorder) see the changes in that order."""
    tree = _factory().create_tree_from_text(doc('<Flip name="d"><A name="a"/></Flip>'))
    seen = []
    tree.add_status_observer(lambda stamp, node, prev, new: seen.append((node.name, prev.name, new.name)))
    assert tree.tick_exactly_once() is F
    assert seen == [("a", "IDLE", "RUNNING"), ("a", "RUNNING", "SUCCESS"), ("d", "IDLE", "FAILURE"),
                    ("a", "SUCCESS", "IDLE"), ("d", "FAILURE", "IDLE")]


class CountingDecorator(SimpleDecoratorNode):
    """A subclass with its own tick(): parents must tick it through that tick."""

    ticks = 0

    def tick(self) -> NodeStatus:
        CountingDecorator.ticks += 1
        return SimpleDecoratorNode.tick(self)


def test_a_subclass_overriding_tick_is_ticked_through_it():
    factory = _factory()
    factory.register_builder(TreeNodeManifest("Counted", NodeType.DECORATOR, {}),
                             lambda name, config: CountingDecorator(name, config, lambda status, node: status))
    tree = factory.create_tree_from_text(doc('<Counted><A/></Counted>'))
    CountingDecorator.ticks = 0
    assert tree.tick_exactly_once() is S
    assert tree.tick_exactly_once() is S
    assert CountingDecorator.ticks == 2
