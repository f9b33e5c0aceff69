"""Equal elements of a document share one port pass and one compile of their pre/post
conditions (builder.py ``_ports``, ``_compile_conditions``). Each node must still get what a
node of a distinct element gets: its own blackboard entries in its own blackboard (a subtree's
may differ from the first node's), the conditions of its own attributes (the same script under
another attribute is another condition), the same load errors, and the same ticks.

The reference is the same document with every element made distinct by a unique name (Groot2
writes trees that way): nothing is shared in its build.
"""

from __future__ import annotations

import pytest
from lxml import etree

from bt_runtime import BehaviorTreeFactory, NodeStatus, SyncActionNode, input_port, output_port
from bt_runtime.errors import BehaviorTreeException

RUN = NodeStatus.RUNNING


class Count(SyncActionNode):
    """Reads an int, writes it plus one (typed ports: they give typed blackboard entries)."""

    @classmethod
    def provided_ports(cls):
        return [input_port("n", int, default=0), output_port("out", int)]

    def tick(self) -> NodeStatus:
        n = self.get_input("n")
        self.set_output("out", n + 1)
        return NodeStatus.SUCCESS if n % 2 == 0 else NodeStatus.FAILURE


# The same elements in the main tree and in subtrees with their own blackboards, and one script
# under different condition attributes.
SUB = ('<Sequence>'
       '<Script code="x := x + 1" _skipIf="x &gt; 2"/>'
       '<Script code="x := x + 1" _successIf="x &gt; 2"/>'
       '<ForceSuccess><Script code="x := x + 1" _failureIf="x &gt; 5" _onSuccess="hits += 1"/></ForceSuccess>'
       '<ForceSuccess><Script code="x := x + 1" _failureIf="x &gt; 5" _post="hits += 1"/></ForceSuccess>'
       '<ForceSuccess><Count n="{k}" out="{k}"/></ForceSuccess><Count n="{k}" out="{k}"/>'
       '</Sequence>')
MAIN = ('<Sequence>'
        '<Script code="k := 0; x := 0; hits := 0"/>'
        '<Count n="{k}" out="{k}"/>'
        '<ForceSuccess><SubTree ID="Sub" k="1" x="0" hits="0"/></ForceSuccess>'
        '<ForceSuccess><SubTree ID="Sub" k="2" x="5" hits="0"/></ForceSuccess>'
        '<ForceSuccess><SubTree ID="Sub" _autoremap="true"/></ForceSuccess>'
        '<ForceSuccess><SubTree ID="Sub" k="{k}" x="{x}" hits="{hits}"/></ForceSuccess>'
        '<ForceSuccess><Sequence><AlwaysFailure/><SubTree ID="Sub"/></Sequence></ForceSuccess>'
        '<Script code="x := x + 1" _skipIf="x &gt; 2"/>'
        '<Script code="x := x + 1" _successIf="x &gt; 2"/>'
        '<Count n="{k}" out="{k}"/>'
        '</Sequence>')


def document(main: str, sub: str) -> str:
    return (f'<root BTCPP_format="4" main_tree_to_execute="Main"><BehaviorTree ID="Main">{main}</BehaviorTree>'
            f'<BehaviorTree ID="Sub">{sub}</BehaviorTree></root>')


def distinct(xml: str) -> str:
    """Every element under a BehaviorTree given a unique name (no two elements alike)."""
    root = etree.fromstring(xml)
    k = 0
    for tree in root.iter("BehaviorTree"):
        for elem in tree.iter():
            if elem is not tree:
                k += 1
                elem.set("name", f"e{k}")
    return etree.tostring(root, encoding="unicode")


def build(xml: str):
    factory = BehaviorTreeFactory()
    factory.register_node_type(Count, "Count")
    factory.register_behavior_tree_from_text(xml)
    return factory.create_tree("Main")


def what_was_built(tree) -> list:
    """Per node (names and paths aside): ports, other attributes, conditions; per subtree: its
    blackboard's entries and types."""
    nodes = [(n.uid, n.registration_name, sorted(n.config.input_ports.items()),
              sorted(n.config.output_ports.items()),
              sorted((k, v) for k, v in n.config.other_attributes.items() if k != "name"),
              sorted(n.config.pre_conditions), sorted(n.config.post_conditions)) for n in tree.nodes()]
    boards = [sorted((key, entry.type.name) for key, entry in rec.blackboard.local_entries().items())
              for rec in tree.subtrees]
    return [nodes, boards]


def ticks(tree, n: int = 6) -> list:
    changes: list = []
    tree.add_status_observer(lambda stamp, node, prev, new: changes.append((node.uid, prev.name, new.name)))
    out = []
    for _ in range(n):
        try:
            status = tree.tick_exactly_once().name
        except BehaviorTreeException as exc:  # (the path in the message has the names)
            status = type(exc).__name__
            tree.halt_tree()
        values = [sorted((k, repr(e.value)) for k, e in rec.blackboard.local_entries().items())
                  for rec in tree.subtrees]
        out.append((status, list(changes), values))
        changes.clear()
    return out


def test_the_reference_shares_nothing():
    xml = distinct(document(MAIN, SUB))
    root = etree.fromstring(xml)
    elements = [etree.tostring(e) for t in root.iter("BehaviorTree") for e in t.iter() if e is not t]
    assert len(set(elements)) == len(elements)


def test_equal_elements_build_and_tick_as_distinct_ones():
    xml = document(MAIN, SUB)
    shared, reference = build(xml), build(distinct(xml))
    built = what_was_built(shared)
    assert built == what_was_built(reference)
    boards = built[1]
    assert len(boards) == 6 and all(("k", "int") in board for board in boards[1:3] + boards[-1:]), boards
    # each Script has the conditions of its own attributes (a script text under another
    # attribute is another condition)
    conditions = [(pre, post) for _, rid, _, _, _, pre, post in built[0] if rid == "Script"]
    sub = [(["_skipIf"], []), (["_successIf"], []), (["_failureIf"], ["_onSuccess"]), (["_failureIf"], ["_post"])]
    assert conditions == [([], [])] + sub * 5 + [(["_skipIf"], []), (["_successIf"], [])], conditions
    traced = ticks(shared)
    assert traced == ticks(reference)
    seen = {new for _, changes, _ in traced for _, _, new in changes}
    assert seen >= {"SUCCESS", "FAILURE"}, traced


def test_equal_elements_report_the_type_conflict_of_their_own_blackboard():
    """The second node of an element meets an entry of another type in its subtree's blackboard:
    the same error as for a distinct element (nothing learnt from the first node hides it)."""
    sub = '<Sequence><Say k="{k}"/><Count n="{k}" out="{k}"/></Sequence>'
    xml = document('<Sequence><Count n="{k}" out="{k}"/><SubTree ID="Sub"/></Sequence>', sub)

    class Say(SyncActionNode):
        @classmethod
        def provided_ports(cls):
            return [output_port("k", bool)]

        def tick(self) -> NodeStatus:
            return NodeStatus.SUCCESS

    def error(text: str) -> str:
        factory = BehaviorTreeFactory()
        factory.register_node_type(Count, "Count")
        factory.register_node_type(Say, "Say")
        factory.register_behavior_tree_from_text(text)
        with pytest.raises(BehaviorTreeException) as caught:
            factory.create_tree("Main")
        return str(caught.value)

    message = error(xml)
    assert "initially created with type" in message, message
    assert message == error(distinct(xml))
