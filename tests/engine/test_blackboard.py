"""Blackboard hierarchy, remapping, autoremap, ``@`` and the set/get type rules (spec 8)."""

from __future__ import annotations

import pytest

from bt_runtime import BehaviorTreeFactory, Blackboard, BTRuntimeError, LogicError, NodeStatus
from bt_runtime.ports import DOUBLE, INT, STRING, UINT
from tests.engine.helpers import doc


def test_lookup_order():
    root = Blackboard()
    mid = Blackboard(root)
    leaf = Blackboard(mid)
    root.set("r", 1)
    mid.set("m", 2)
    mid.set("shadow", "mid")
    leaf.set("shadow", "leaf")
    leaf.add_subtree_remapping("alias", "m")
    leaf.add_subtree_remapping("top", "@r")
    assert leaf.get("alias") == 2
    assert leaf.get("top") == 1
    assert leaf.get("@r") == 1
    assert leaf.get("shadow") == "leaf"
    assert leaf.get_entry("m") is None  # no autoremap: isolated
    leaf.enable_auto_remapping(True)
    assert leaf.get("m") == 2
    mid.enable_auto_remapping(True)
    assert leaf.get("r") == 1
    mid.set("_private", 3)
    assert leaf.get_entry("_private") is None  # private keys are never autoremapped
    assert leaf.root() is root


def test_remapped_entries_are_shared():
    parent = Blackboard()
    child = Blackboard(parent)
    child.add_subtree_remapping("inner", "outer")
    child.set("inner", 5)  # created in the parent under the external name
    assert parent.get("outer") == 5
    assert child.keys() == []
    assert child.get_entry("inner") is parent.get_entry("outer")


def test_autoremap_creates_in_parent_except_private():
    parent = Blackboard()
    child = Blackboard(parent)
    child.enable_auto_remapping(True)
    child.set("shared", 1)
    child.set("_mine", 2)
    assert parent.keys() == ["shared"]
    assert child.keys() == ["_mine"]


def test_root_writes_from_anywhere():
    root = Blackboard()
    leaf = Blackboard(Blackboard(root))
    leaf.set("@goal", "dock")
    assert root.get("goal") == "dock"
    assert leaf.get_entry("goal") is None
    with pytest.raises(LogicError, match="'@' used multiple times"):
        leaf.create_entry("@@x")


def test_keys_and_unset_are_local():
    parent = Blackboard()
    child = Blackboard(parent)
    child.enable_auto_remapping(True)
    parent.set("p", 1)
    child.set("_c", 2)
    assert child.keys() == ["_c"]
    child.unset("p")  # not local: nothing happens
    assert parent.get("p") == 1
    child.unset("_c")
    assert child.keys() == []
    child.unset("absent")


def test_string_writes_lock_on_second_write():
    bb = Blackboard()
    bb.set("a", "x")  # first write of a string: untyped entry
    bb.set("a", 1)  # ... so an int is accepted and locks the type
    assert bb.get("a") == 1
    bb.set("b", "x")
    bb.set("b", "y")  # now typed std::string
    with pytest.raises(LogicError, match=r"Blackboard::set\(b\): once declared, the type of a port shall not "
                                         r"change. Previously declared type \[std::string\], current type \[int\]"):
        bb.set("b", 1)


def test_numeric_writes_into_typed_entries():
    bb = Blackboard()
    bb.set("d", 1.5)
    bb.set("d", 2)  # int into double: exact
    assert bb.get("d") == 2.0 and type(bb.get("d")) is float
    bb.set("i", 1)
    bb.set("i", 2.0)
    assert type(bb.get("i")) is int
    with pytest.raises(LogicError):
        bb.set("i", 2.5)
    bb.set("i", True)  # a bool into an int entry is exact...
    with pytest.raises(LogicError):
        bb.set("i", False)  # ...except false into a signed one (BT.CPP's isCastingSafe<bool> quirk)
    bb.set("u", 3)
    bb.get_entry("u").type = UINT
    bb.set("u", False)
    assert bb.get("u") == 0
    bb.set("flag", True)
    with pytest.raises(LogicError):
        bb.set("flag", 1)  # any int into a bool entry is rejected
    bb.set("i", "42")
    assert bb.get("i") == 42
    with pytest.raises(BTRuntimeError, match="Can't convert string"):
        bb.set("i", "many")


def test_typed_empty_entry_keeps_the_first_value_kind():
    """Any::copyInto: an empty entry (as ports create them) takes a number as it is; later
    numbers are converted to the stored kind."""
    bb = Blackboard()
    bb.create_entry("n", INT)
    bb.set("n", 2.0)  # accepted (exactly 2) and stored as a double
    assert bb.get("n", str) == "2.000000" and bb.get("n", int) == 2
    bb.set("n", 5)
    assert type(bb.get("n")) is float and bb.get("n") == 5.0
    with pytest.raises(LogicError):
        bb.set("n", 2.5)


def test_unsigned_entries_refuse_plain_ints():
    """BT.CPP's isCastingSafe casts the unsigned limit to the source type first: a C++ int (a
    Python int that fits 32 bits) is never accepted by an unsigned entry; larger ints are
    range-checked against a 32-bit unsigned entry; a string still converts."""
    bb = Blackboard()
    bb.create_entry("u", UINT)
    with pytest.raises(LogicError, match="Previously declared type \\[unsigned int\\], current type \\[int\\]"):
        bb.set("u", 5)
    bb.set("u", 3_000_000_000)
    bb.set("u", "7")
    assert bb.get("u") == 7
    bb.set("u", 8.0)
    assert bb.get("u") == 8


def test_remapped_writes_are_strict():
    parent = Blackboard()
    parent.create_entry("speed", DOUBLE)
    child = Blackboard(parent)
    child.add_subtree_remapping("v", "speed")
    with pytest.raises(LogicError, match="once declared"):
        child.set("v", 1)  # an int into a remapped double entry: no conversion through a remapping
    child.set("v", 1.0)
    assert parent.get("speed") == 1.0


def test_create_entry_type_check():
    bb = Blackboard()
    bb.create_entry("k", INT)
    bb.create_entry("k", INT)
    with pytest.raises(LogicError, match="Previously declared type \\[int\\], current type \\[std::string\\]"):
        bb.create_entry("k", STRING)


def test_get_errors_and_conversions():
    bb = Blackboard()
    with pytest.raises(BTRuntimeError, match="Missing key \\[nope\\]"):
        bb.get("nope")
    bb.create_entry("empty", INT)
    with pytest.raises(BTRuntimeError, match="hasn't been initialized"):
        bb.get("empty")
    assert bb.get("nope", default=3) == 3
    bb.set("n", 7)
    assert bb.get("n", float) == 7.0
    assert bb.get("n", str) == "7"
    bb.set("s", "12")
    assert bb.get("s", int) == 12


def test_bool_and_status_values_read_as_numbers_in_strings():
    """BT.CPP stores bool and enums as int64, so they read back as "1", "0", "2"."""
    bb = Blackboard()
    bb.set("flag", True)
    bb.set("off", False)
    bb.set("st", NodeStatus.SUCCESS)
    assert (bb.get("flag", str), bb.get("off", str), bb.get("st", str)) == ("1", "0", "2")
    assert bb.get("flag", int) == 1


def test_sequence_ids_and_stamps():
    bb = Blackboard()
    bb.set("x", 1)
    _, seq1, stamp1 = bb.get_stamped("x")
    bb.set("x", 1)
    _, seq2, stamp2 = bb.get_stamped("x")
    assert seq2 == seq1 + 1 and stamp2 >= stamp1


def test_clone_into():
    src, dst = Blackboard(), Blackboard()
    src.set("a", 1)
    dst.set("a", 5)
    dst.set("gone", 1)
    src.clone_into(dst)
    assert dst.keys() == ["a"] and dst.get("a") == 1


def test_subtree_blackboards_in_a_tree():
    factory = BehaviorTreeFactory()
    xml = doc('<Sequence><Script code="x := 1; @g := 2"/>'
              '<SubTree ID="Iso"/><SubTree ID="Auto" _autoremap="true"/><SubTree ID="Map" y="{x}"/></Sequence>',
              '<BehaviorTree ID="Iso"><Script code="x := 10; iso := @g"/></BehaviorTree>'
              '<BehaviorTree ID="Auto"><Script code="x := x + 100; auto_new := 1; _priv := 1"/></BehaviorTree>'
              '<BehaviorTree ID="Map"><Script code="y := y * 2"/></BehaviorTree>')
    tree = factory.create_tree_from_text(xml)
    assert tree.tick_once() is NodeStatus.SUCCESS
    root = tree.root_blackboard
    assert root.get("x") == 202  # Iso wrote its own x; Auto and Map wrote the root's
    assert sorted(root.keys()) == ["auto_new", "g", "x"]
    iso, auto, mapped = (r.blackboard for r in tree.subtrees[1:])
    assert iso.keys() == ["x", "iso"] and iso.get("x") == 10 and iso.get("iso") == 2
    assert auto.keys() == ["_priv"]
    assert mapped.keys() == []


def test_external_root_blackboard():
    factory = BehaviorTreeFactory()
    shared = Blackboard()
    shared.set("limit", 3)
    tree = factory.create_tree_from_text(doc('<Script code="seen := limit"/>'), blackboard=shared)
    tree.tick_once()
    assert tree.root_blackboard is shared and shared.get("seen") == 3


def test_debug_message_shows_the_type_of_remapped_entries(capsys):
    from bt_runtime import Blackboard

    parent = Blackboard()
    parent.set("parent_value", 42)
    child = Blackboard(parent=parent)
    child.add_subtree_remapping("local_name", "parent_value")
    child.add_subtree_remapping("dangling", "nowhere")
    text = child.debug_message()
    assert "[local_name] remapped to port of parent tree [parent_value] (int)" in text
    assert text.endswith("[dangling] remapped to port of parent tree [nowhere]")  # no entry: no type
    assert capsys.readouterr().out.strip() == text  # printed, as BT.CPP's debugMessage
