"""A dropped tree is freed by reference counting (no wait for the cyclic collector), and a load
does not leave the collector disabled."""

from __future__ import annotations

import gc

from bt_runtime import BehaviorTreeFactory, NodeStatus

XML = ('<root BTCPP_format="4" main_tree_to_execute="Main">'
       '<BehaviorTree ID="Sub"><Sequence><Script code="n := n + 1"/><Ok _skipIf="n &gt; 99"/></Sequence>'
       '</BehaviorTree><BehaviorTree ID="Main"><Sequence>'
       + '<Fallback><Ok/><Ok/></Fallback><ReactiveSequence><Ok/></ReactiveSequence><SubTree ID="Sub" n="{n}"/>' * 20
       + '</Sequence></BehaviorTree></root>')


def _factory() -> BehaviorTreeFactory:
    f = BehaviorTreeFactory()
    f.register_simple_condition("Ok", lambda node: NodeStatus.SUCCESS)
    f.register_behavior_tree_from_text(XML)
    return f


def test_a_dropped_tree_leaves_no_cycles_behind() -> None:
    factory = _factory()
    warm = factory.create_tree("Main")  # warm every lazy cache of the factory
    warm.root_blackboard.set("n", 0)
    warm.tick_exactly_once()
    del warm
    gc.collect()
    was = gc.isenabled()
    gc.disable()
    try:
        tree = factory.create_tree("Main")
        tree.root_blackboard.set("n", 0)
        assert tree.tick_exactly_once() is NodeStatus.SUCCESS
        del tree
        assert gc.collect() == 0
    finally:
        if was:
            gc.enable()


def test_loading_restores_the_collector_state() -> None:
    factory = _factory()
    assert gc.isenabled()
    factory.create_tree("Main")
    assert gc.isenabled()
    gc.disable()
    try:
        factory.create_tree("Main")
        assert not gc.isenabled()
    finally:
        gc.enable()
