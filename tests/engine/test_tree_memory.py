"""A dropped tree is freed by reference counting (no wait for the cyclic collector), and a load
does not leave the collector disabled."""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager

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


def _warm(factory: BehaviorTreeFactory) -> None:
    """Build, tick and drop one tree: every lazy cache of the factory is filled."""
    warm = factory.create_tree("Main")
    warm.root_blackboard.set("n", 0)
    warm.tick_exactly_once()


@contextmanager
def _cyclic_collector_off() -> Iterator[None]:
    """Collected first, then off for the block (restored as it was): a ``gc.collect()`` in the
    block finds only the cycles the block left."""
    gc.collect()
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


def test_a_dropped_tree_leaves_no_cycles_behind() -> None:
    factory = _factory()
    _warm(factory)
    with _cyclic_collector_off():
        tree = factory.create_tree("Main")
        tree.root_blackboard.set("n", 0)
        assert tree.tick_exactly_once() is NodeStatus.SUCCESS
        del tree
        assert gc.collect() == 0


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


def test_a_built_tree_is_not_left_to_the_young_collections() -> None:
    """Its objects start in the oldest generation: the next young collections do not traverse
    the whole new tree (they cost as much as the build)."""
    tree = _factory().create_tree("Main")
    young = {id(obj) for generation in (0, 1) for obj in gc.get_objects(generation)}
    nodes = [node for record in tree.subtrees for node in record.nodes]
    assert len(nodes) > 100
    assert not any(id(node) in young or id(node._cell) in young or id(node.config) in young for node in nodes)


def test_loading_keeps_the_applications_frozen_objects_frozen() -> None:
    factory = _factory()
    gc.freeze()
    try:
        frozen = gc.get_freeze_count()
        factory.create_tree("Main")
        assert gc.get_freeze_count() == frozen
    finally:
        gc.unfreeze()


def test_a_dropped_factory_and_its_tree_leave_no_cycles_behind() -> None:
    """A runtime that reloads builds a new factory each time: the old one, with its documents
    and their plans, is freed by reference counting too."""
    tree = _factory().create_tree("Main")  # warm every lazy cache
    del tree
    with _cyclic_collector_off():
        factory = _factory()
        tree = factory.create_tree("Main")
        tree.root_blackboard.set("n", 0)
        assert tree.tick_exactly_once() is NodeStatus.SUCCESS
        del factory, tree
        assert gc.collect() == 0


def test_a_dropped_tree_and_its_forgotten_scripts_leave_no_cycles_behind() -> None:
    """The compiled scripts a dropped tree alone used (a fresh process's cold load: the cache
    of compiled scripts emptied) are freed by reference counting too, ticked or not."""
    from bt_runtime import Blackboard
    from bt_runtime.script.compiler import forget_compiled

    def blackboard() -> Blackboard:
        bb = Blackboard.create()
        for i in range(5):
            bb.set(f"x{i}", 0.0)
        bb.set("y", 0.0)
        return bb

    xml = ('<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>'
           + "".join(f'<Script code="x{i} := x{i} + 1"/><ScriptCondition code="x{i} &gt; 0"/>'
                     f'<Script code="y := x{i} * 2"/><Script code="x{i} := 1; y := x{i}"/>' for i in range(5))
           + '</Sequence></BehaviorTree></root>')
    factory = BehaviorTreeFactory()
    factory.create_tree_from_text(xml, blackboard()).tick_exactly_once()  # warm the factory's lazy caches
    with _cyclic_collector_off():
        for ticked in (False, True):
            forget_compiled()
            tree = factory.create_tree_from_text(xml, blackboard())
            if ticked:
                assert tree.tick_exactly_once() is NodeStatus.SUCCESS
            del tree
            forget_compiled()
            assert gc.collect() == 0, ticked


def test_a_dropped_tree_with_hooked_nodes_leaves_no_cycles_behind() -> None:
    """A pre/post-tick hook or a tick monitor binds the node's execute_tick to it (as a
    pre/post condition does); a hook removed again unbinds it. Either way the tree is freed."""
    factory = _factory()
    _warm(factory)
    with _cyclic_collector_off():
        tree = factory.create_tree("Main")
        tree.root_blackboard.set("n", 0)
        nodes = [node for record in tree.subtrees for node in record.nodes]
        nodes[1].set_pre_tick_function(lambda node: None)
        nodes[2].set_post_tick_function(lambda node, status: None)
        nodes[3].set_tick_monitor_callback(lambda node, status, us: None)
        nodes[4].set_pre_tick_function(lambda node: None)
        nodes[4].set_pre_tick_function(None)
        assert tree.tick_exactly_once() is NodeStatus.SUCCESS
        del tree, nodes
        assert gc.collect() == 0
