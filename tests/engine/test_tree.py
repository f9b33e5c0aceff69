"""Tree structure and tick loop: uids, full paths, subtree records, visitors, status observers
(spec 2.12, 3.4, 9.1), pre/post hooks and the main tree selection rules (spec 2.2)."""

from __future__ import annotations

import pytest

from bt_runtime import BehaviorTreeFactory, BTRuntimeError, NodeStatus, XMLLoadError
from tests.engine.helpers import doc

S, F, R, IDLE = NodeStatus.SUCCESS, NodeStatus.FAILURE, NodeStatus.RUNNING, NodeStatus.IDLE


@pytest.fixture
def factory():
    f = BehaviorTreeFactory()
    f.register_simple_action("A", lambda n: S)
    f.register_simple_action("B", lambda n: F)
    f.register_simple_action("P", lambda n: S)
    return f


NESTED = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence name="root_seq">
      <Script code="a:=1"/>
      <SubTree ID="Sub" name="first" in="{a}"/>
      <A/>
      <SubTree ID="Sub" in="{a}"/>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Sub">
    <Sequence>
      <Script code="loc := in"/>
      <SubTree ID="Leaf"/>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Leaf">
    <A name="leafA"/>
  </BehaviorTree>
</root>"""


def test_uids_are_depth_first_preorder_through_subtrees(factory):
    tree = factory.create_tree_from_text(NESTED)
    paths = {n.uid: n.full_path for n in tree.nodes()}
    assert paths == {
        1: "root_seq", 2: "Script::2", 3: "first", 4: "first/Sequence::4", 5: "first/Script::5",
        6: "first/Leaf::6", 7: "first/Leaf::6/leafA", 8: "A::8", 9: "Sub::9", 10: "Sub::9/Sequence::10",
        11: "Sub::9/Script::11", 12: "Sub::9/Leaf::12", 13: "Sub::9/Leaf::12/leafA",
    }


def test_subtree_records(factory):
    tree = factory.create_tree_from_text(NESTED)
    records = [(r.tree_id, r.instance_name, [n.uid for n in r.nodes]) for r in tree.subtrees]
    assert records == [
        ("Main", "", [1, 2, 3, 8, 9]),
        ("Sub", "first", [4, 5, 6]),
        ("Leaf", "first/Leaf::6", [7]),
        ("Sub", "Sub::9", [10, 11, 12]),
        ("Leaf", "Sub::9/Leaf::12", [13]),
    ]
    assert tree.root_node.uid == 1
    assert tree.subtrees[1].blackboard.parent is tree.root_blackboard


def test_full_path_rules(factory):
    xml = doc('<Sequence><P/><P name="P"/><P name="custom"/><P name="with space. dots"/></Sequence>')
    tree = factory.create_tree_from_text(xml)
    assert [n.full_path for n in tree.nodes()] == ["Sequence::1", "P::2", "P::3", "custom", "with space. dots"]
    assert [n.name for n in tree.nodes()] == ["Sequence", "P", "P", "custom", "with space. dots"]


def test_apply_visitor_and_get_nodes_by_path(factory):
    tree = factory.create_tree_from_text(NESTED)
    visited = []
    tree.apply_visitor(lambda n: visited.append(n.uid))
    assert visited == list(range(1, 14))
    assert [n.uid for n in tree.get_nodes_by_path("*leafA")] == [7, 13]
    assert [n.uid for n in tree.get_nodes_by_path("first/*")] == [4, 5, 6, 7]
    assert [n.uid for n in tree.get_nodes_by_path("Sub::?")] == [9]
    assert tree.node_by_uid(6).full_path == "first/Leaf::6"


def test_node_api(factory):
    tree = factory.create_tree_from_text(doc('<Sequence><Script name="s" code="x := 3"/></Sequence>'))
    node = tree.get_nodes_by_path("s")[0]
    assert (node.name, node.uid, node.full_path, node.status) == ("s", 2, "s", IDLE)
    assert node.registration_name == "Script"
    assert node.get_input("code") == "x := 3"
    tree.tick_once()
    assert tree.root_blackboard.get("x") == 3


def test_status_observer_transitions(factory):
    """Spec 9.1: Sequence(A, Inverter(B -> FAILURE)), one tick."""
    tree = factory.create_tree_from_text(doc("<Sequence><A/><Inverter><B/></Inverter></Sequence>"))
    seen = []
    remove = tree.add_status_observer(lambda t, node, prev, new: seen.append(f"{node.uid}:{new.name}"))
    assert tree.tick_once() is S
    assert seen == ["1:RUNNING", "2:RUNNING", "2:SUCCESS", "3:RUNNING", "4:RUNNING", "4:FAILURE", "4:IDLE",
                    "3:SUCCESS", "2:IDLE", "3:IDLE", "1:SUCCESS", "1:IDLE"]
    remove()
    tree.tick_once()
    assert len(seen) == 12


def test_status_observer_gets_previous_status_and_clock(factory):
    tree = factory.create_tree_from_text(doc("<AlwaysSuccess/>"))
    tree.set_clock(lambda: 42.0)
    seen = []
    tree.add_status_observer(lambda t, node, prev, new: seen.append((t, prev.name, new.name)))
    tree.tick_once()
    assert seen == [(42.0, "IDLE", "SUCCESS"), (42.0, "SUCCESS", "IDLE")]


def test_observer_of_halted_and_skipped_nodes(factory):
    factory.register_simple_stateful_action("Run", lambda n: R, lambda n: R)
    tree = factory.create_tree_from_text(doc('<Sequence><A _skipIf="1"/><Run/></Sequence>'))
    seen = []
    tree.add_status_observer(lambda t, node, prev, new: seen.append(f"{node.uid}:{prev.name}->{new.name}"))
    tree.tick_once()
    tree.halt_tree()
    # SKIPPED is never stored, so node 2 has no transition at all.
    assert seen == ["1:IDLE->RUNNING", "3:IDLE->RUNNING", "3:RUNNING->IDLE", "1:RUNNING->IDLE"]


def test_pre_and_post_tick_hooks(factory):
    tree = factory.create_tree_from_text(doc("<Sequence><A/><B/></Sequence>"))
    a, b = tree.get_nodes_by_path("A::2")[0], tree.get_nodes_by_path("B::3")[0]
    b.set_post_tick_function(lambda node, status: S)
    assert tree.tick_once() is S
    a.set_pre_tick_function(lambda node: F)
    assert tree.tick_once() is F
    a.set_pre_tick_function(None)
    b.set_post_tick_function(None)
    assert tree.tick_once() is F


def test_tick_monitor(factory):
    tree = factory.create_tree_from_text(doc("<A/>"))
    calls = []
    tree.root_node.set_tick_monitor_callback(lambda node, status, micros: calls.append((status, micros >= 0)))
    tree.tick_once()
    assert calls == [(S, True)]


def test_root_reset_after_completion_and_skipped_root_stays_running(factory):
    tree = factory.create_tree_from_text(doc('<Sequence><A _skipIf="1"/></Sequence>'))
    assert tree.tick_once() is NodeStatus.SKIPPED
    assert tree.root_node.status is R  # spec 13.1
    tree = factory.create_tree_from_text(doc("<Sequence><A/></Sequence>"))
    assert tree.tick_once() is S
    assert tree.root_node.status is IDLE


def test_tick_while_running_returns_final_status(factory):
    factory.register_simple_stateful_action("Twice", lambda n: R, lambda n: S)
    tree = factory.create_tree_from_text(doc("<Sequence><Twice/><Twice/></Sequence>"))
    assert tree.tick_while_running(0) is S


def test_context_manager_halts(factory):
    halted = []
    factory.register_simple_stateful_action("Run", lambda n: R, lambda n: R, lambda n: halted.append(1))
    with factory.create_tree_from_text(doc("<Run/>")) as tree:
        tree.tick_once()
    assert halted == [1]


# -- main tree selection (spec 2.2) ------------------------------------------------------------------

TWO = ('<root BTCPP_format="4"{main}><BehaviorTree ID="X"><Script code="who := \'X\'"/></BehaviorTree>'
       '<BehaviorTree ID="Y"><Script code="who := \'Y\'"/></BehaviorTree></root>')


def _who(tree) -> str:
    tree.tick_once()
    return tree.root_blackboard.get("who")


def test_main_tree_to_execute(factory):
    assert _who(factory.create_tree_from_text(TWO.format(main=' main_tree_to_execute="Y"'))) == "Y"


def test_single_tree_is_main(factory):
    xml = '<root BTCPP_format="4"><BehaviorTree ID="Only"><Script code="who := \'O\'"/></BehaviorTree></root>'
    assert _who(factory.create_tree_from_text(xml)) == "O"


def test_tree_without_id_when_alone(factory):
    xml = '<root BTCPP_format="4"><BehaviorTree><Script code="who := \'anon\'"/></BehaviorTree></root>'
    assert _who(factory.create_tree_from_text(xml)) == "anon"
    assert factory.registered_behavior_trees() == ["BehaviorTree_0"]


def test_ambiguous_main_tree_is_an_error(factory):
    with pytest.raises(XMLLoadError, match=r"\[main_tree_to_execute\] was not specified correctly"):
        factory.create_tree_from_text(TWO.format(main=""))


def test_one_new_tree_added_to_registered_ones(factory):
    factory.register_behavior_tree_from_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Lib"><AlwaysSuccess/></BehaviorTree></root>')
    xml = ('<root BTCPP_format="4"><BehaviorTree ID="Lib"><AlwaysFailure/></BehaviorTree>'
           '<BehaviorTree ID="New"><Sequence><SubTree ID="Lib"/><Script code="who := \'N\'"/></Sequence>'
           '</BehaviorTree></root>')
    tree = factory.create_tree_from_text(xml)  # Lib is replaced, New is the only new ID
    assert tree.tick_once() is F


def test_unknown_main_tree(factory):
    with pytest.raises(XMLLoadError, match="Can't find a tree with name: Z"):
        factory.create_tree_from_text(TWO.format(main=' main_tree_to_execute="Z"'))


def test_create_tree_by_id_and_reregistration(factory):
    factory.register_behavior_tree_from_text(TWO.format(main=""))
    assert sorted(factory.registered_behavior_trees()) == ["X", "Y"]
    assert _who(factory.create_tree("X")) == "X"
    factory.register_behavior_tree_from_text(
        '<root BTCPP_format="4"><BehaviorTree ID="X"><Script code="who := \'X2\'"/></BehaviorTree></root>')
    assert _who(factory.create_tree("X")) == "X2"
    factory.clear_registered_behavior_trees()
    with pytest.raises(XMLLoadError):
        factory.create_tree("X")


def test_empty_tree_error():
    """BT.CPP throws RuntimeError("Empty Tree")."""
    from bt_runtime import Tree

    with pytest.raises(BTRuntimeError, match="Empty Tree"):
        Tree([], {}, None, None).tick_once()


def test_tick_once_reticks_on_wake_up_until_bounded(factory):
    calls = []
    factory.register_simple_action("Count", lambda n: (calls.append(1), NodeStatus.SUCCESS)[1])
    tree = factory.create_tree_from_text(
        '<root BTCPP_format="4"><BehaviorTree ID="T"><Repeat num_cycles="10"><Count/></Repeat>'
        '</BehaviorTree></root>')
    assert tree.tick_once() is NodeStatus.SUCCESS and len(calls) == 10  # unbounded, as BT.CPP
    calls.clear()
    assert tree.tick_once(max_reticks=3) is NodeStatus.RUNNING and len(calls) == 4
    assert tree.wake_up.is_set and tree.retick_cutoffs == 1  # the next tick goes on at once
    assert tree.tick_once() is NodeStatus.SUCCESS and len(calls) == 10


def test_print_tree_recursively_indents_by_depth():
    import io

    from bt_runtime import print_tree_recursively

    factory = BehaviorTreeFactory()
    tree = factory.create_tree_from_text(doc(
        '<Sequence name="root"><Fallback name="pick"><AlwaysFailure name="a"/><AlwaysSuccess name="b"/>'
        '</Fallback><SubTree ID="S" name="sub"/></Sequence>',
        '<BehaviorTree ID="S"><Inverter name="inv"><AlwaysFailure name="c"/></Inverter></BehaviorTree>'))
    out = io.StringIO()
    print_tree_recursively(tree.root_node, out)
    assert out.getvalue().splitlines() == [
        "-" * 16, "root", "   pick", "      a", "      b", "   sub", "      inv", "         c", "-" * 16]
