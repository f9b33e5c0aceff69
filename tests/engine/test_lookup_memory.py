"""Remembered remapped lookups and compiled-once scripts must never return stale answers."""

from __future__ import annotations

from bt_runtime import BehaviorTreeFactory, NodeStatus
from bt_runtime.blackboard import Blackboard


def _chain() -> tuple[Blackboard, Blackboard, Blackboard]:
    root = Blackboard.create()
    mid = Blackboard.create(root)
    mid.add_subtree_remapping("b", "a")
    leaf = Blackboard.create(mid)
    leaf.add_subtree_remapping("c", "b")
    return root, mid, leaf


def test_remapped_read_follows_a_removed_and_recreated_entry() -> None:
    root, _, leaf = _chain()
    root.set("a", 1)
    assert leaf.get("c") == 1
    root.unset("a")
    assert leaf.get_entry("c") is None  # not the remembered, removed entry
    root.set("a", 2)
    assert leaf.get("c") == 2


def test_remapped_read_sees_an_entry_added_by_cloning() -> None:
    root, mid, leaf = _chain()
    mid.enable_auto_remapping()
    root.set("z", "from root")
    assert leaf.get_entry("c") is None
    leaf.enable_auto_remapping()
    assert leaf.get("z") == "from root"
    source = Blackboard.create()
    source.set("z", "cloned")
    source.clone_into(mid)  # mid now has its own 'z', which shadows the root's
    assert leaf.get("z") == "cloned"


def test_a_remapping_added_after_a_read_is_honoured() -> None:
    root = Blackboard.create()
    root.set("x", 1)
    root.set("y", 2)
    child = Blackboard.create(root)
    child.add_subtree_remapping("k", "x")
    assert child.get("k") == 1
    child.add_subtree_remapping("k", "y")
    assert child.get("k") == 2


def test_script_code_from_the_blackboard_is_read_on_every_tick() -> None:
    bb = Blackboard.create()  # as in BT.CPP, the code must exist when the node is built
    bb.set("program", "n := 1")
    bb.set("check", "n == 1")
    tree = BehaviorTreeFactory().create_tree_from_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>'
        '<Script code="{program}"/><ScriptCondition code="{check}"/></Sequence></BehaviorTree></root>', bb)
    assert tree.tick_exactly_once() is NodeStatus.SUCCESS
    bb.set("program", "n := 5")
    assert tree.tick_exactly_once() is NodeStatus.FAILURE
    bb.set("check", "n == 5")
    assert tree.tick_exactly_once() is NodeStatus.SUCCESS


def test_precondition_from_the_blackboard_is_read_on_every_tick() -> None:
    bb = Blackboard.create()
    bb.set("cond", "true")
    tree = BehaviorTreeFactory().create_tree_from_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Main">'
        '<Precondition if="{cond}" else="FAILURE"><AlwaysSuccess/></Precondition></BehaviorTree></root>', bb)
    assert tree.tick_exactly_once() is NodeStatus.SUCCESS
    tree.root_blackboard.set("cond", "false")
    assert tree.tick_exactly_once() is NodeStatus.FAILURE
