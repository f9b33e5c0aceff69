"""A node type whose one port is an input given as a literal (Script's ``code``) skips the
builder's port pass: its node must get exactly the ports, attributes and blackboard entries
the full pass gives, and the same load errors."""

from __future__ import annotations

import pytest

from bt_runtime import BehaviorTreeFactory, NodeStatus, SyncActionNode, input_port
from bt_runtime.errors import BehaviorTreeException
from bt_runtime.xml import builder as builder_module
from tests.engine.helpers import doc


class Say(SyncActionNode):
    @classmethod
    def provided_ports(cls):
        return [input_port("text", str)]

    def tick(self) -> NodeStatus:
        return NodeStatus.SUCCESS


class Count(SyncActionNode):
    @classmethod
    def provided_ports(cls):
        return [input_port("n", int)]

    def tick(self) -> NodeStatus:
        return NodeStatus.SUCCESS


BODY = (
    '<Sequence>'
    '<Script code="x := 1"/><Script name="set_y" code="y := x + 1"/>'
    '<Script name="n" code="x := 2" _skipIf="x &gt; 5"/><Action ID="Script" code="z := 3"/>'
    '<ScriptCondition code="x &gt; 0"/><ScriptCondition name="c" code="y == 2"/>'
    '<Say text="hello"/><Say name="s" text="{msg}"/><Say text=""/>'
    '<Say name="t" text="=" /><Count n="3"/><Count name="k" n="{k}"/>'
    '<UnsetBlackboard key="y"/><UnsetBlackboard name="u" key="{which}"/>'
    '</Sequence>'
)


def _factory() -> BehaviorTreeFactory:
    factory = BehaviorTreeFactory()
    factory.register_node_type(Say, "Say")
    factory.register_node_type(Count, "Count")
    return factory


def _build(monkeypatch: pytest.MonkeyPatch, full: bool):
    passes = []
    ports = builder_module.TreeBuilder._ports

    def counted(self, cfg, *args):
        passes.append(cfg.registration_id)
        return ports(self, cfg, *args)

    monkeypatch.setattr(builder_module.TreeBuilder, "_ports", counted)
    if full:  # every node through the full port pass
        full_type = builder_module.TreeBuilder._type

        def no_single(self, *args):
            known = full_type(self, *args)
            self._types[args[0]] = known = (*known[:3], None)
            return known

        monkeypatch.setattr(builder_module.TreeBuilder, "_type", no_single)
    factory = _factory()
    factory.register_behavior_tree_from_text(doc(BODY))
    tree = factory.create_tree("Main")
    nodes = [(n.name, type(n).__name__, n.config) for n in tree.nodes()]
    monkeypatch.undo()
    return nodes, sorted(tree.root_blackboard.get_keys()), passes


def test_single_port_nodes_get_what_the_full_port_pass_gives(monkeypatch: pytest.MonkeyPatch) -> None:
    fast, fast_keys, fast_passes = _build(monkeypatch, full=False)
    full, full_keys, full_passes = _build(monkeypatch, full=True)
    # the literal Script/ScriptCondition/Say/UnsetBlackboard without other attributes skip the pass
    assert len(full_passes) - len(fast_passes) == 7, (full_passes, fast_passes)
    assert fast_keys == full_keys and "msg" in fast_keys and "k" in fast_keys
    assert [(n, k) for n, k, _ in fast] == [(n, k) for n, k, _ in full]
    for (name, _, a), (_, _, b) in zip(fast, full):
        assert dict(a.input_ports) == dict(b.input_ports), name
        assert dict(a.output_ports) == dict(b.output_ports), name
        assert dict(a.other_attributes) == dict(b.other_attributes), name
    assert dict(fast[1][2].input_ports) == {"code": "x := 1"}


@pytest.mark.parametrize("element", ['<Script code="x := "/>', '<Script name="s" code="x := (1"/>',
                                     '<ScriptCondition code="x &gt;"/>', '<Script code="x := 1" bogus="2"/>'])
def test_single_port_nodes_report_load_errors_with_line_and_element(element: str) -> None:
    factory = _factory()
    with pytest.raises(BehaviorTreeException) as caught:
        factory.create_tree_from_text(doc(f"<Sequence>\n{element}</Sequence>"))
    text = str(caught.value)
    assert "line 2" in text or getattr(caught.value, "line", None) == 2, text
