"""Substitution rules as BT.CPP 4.10 applies them: a rule swaps the object that is built for a
node (another registered type or a configurable test node) and keeps everything else."""

from __future__ import annotations

import json

import pytest

from bt_runtime import BehaviorTreeFactory, Blackboard, BTRuntimeError, NodeStatus, input_port
from tests.engine.helpers import doc

S, F = NodeStatus.SUCCESS, NodeStatus.FAILURE


def factory_with(body: str, extra: str = "") -> BehaviorTreeFactory:
    factory = BehaviorTreeFactory()
    factory.register_simple_action("Greet", lambda node: S, [input_port("message", str)])
    factory.register_behavior_tree_from_text(doc(body, extra))
    return factory


def run(factory: BehaviorTreeFactory, **entries) -> tuple[NodeStatus, Blackboard]:
    bb = Blackboard()
    for key, value in entries.items():
        bb.set(key, value)
    return factory.create_tree("Main", bb).tick_while_running(), bb


def test_substitute_keeps_the_original_ports():
    """The substitute has no ports, yet the XML's ``message`` stays valid: ports come from the
    original node's registration."""
    factory = factory_with('<Sequence><Greet name="hello" message="hi"/><Greet message="{m}"/></Sequence>')
    seen = []
    factory.register_simple_action("Spy", lambda node: seen.append(node.get_input("message")) or S)
    factory.add_substitution_rule("Greet", "Spy")
    status, _ = run(factory, m="from the blackboard")
    assert status is S and seen == ["hi", "from the blackboard"]
    tree = factory.create_tree("Main")
    assert [n.registration_id for n in tree.nodes()][1:] == ["Greet", "Greet"]


def test_substitute_unknown_type_is_a_runtime_error():
    factory = factory_with("<Greet/>")
    factory.add_substitution_rule("Greet", "NoSuchType")
    with pytest.raises(BTRuntimeError, match=r"Substituted Node ID \[NoSuchType\] not found"):
        factory.create_tree("Main")


@pytest.mark.parametrize("script, expected", [
    ("flag ? FAILURE : SUCCESS", F),
    ("'FAILURE'", F),
    ("3", F),
    ("SKIPPED", None),  # skipped: the Sequence of one skipped child is SKIPPED, not stored
])
def test_return_status_script_names_and_numbers(script, expected):
    factory = factory_with('<Sequence><AlwaysSuccess name="target"/></Sequence>')
    factory.add_substitution_rule("target", {"return_status_script": script, "failure_script": "branch := 'f'"})
    tree = factory.create_tree("Main")
    tree.root_blackboard.set("flag", True)
    status = tree.tick_once()
    if expected is None:
        assert status is NodeStatus.SKIPPED
    else:
        assert status is expected and tree.root_blackboard.get("branch") == "f"


def test_script_wins_over_fixed_status():
    factory = factory_with('<AlwaysSuccess name="target"/>')
    factory.add_substitution_rule("target", {"return_status": "SUCCESS", "return_status_script": "FAILURE"})
    assert run(factory)[0] is F


@pytest.mark.parametrize("script, message", [
    ("IDLE", "invalid status \\(integer value: 0\\)"),
    ("0", "invalid status \\(integer value: 0\\)"),
    ("9", "invalid status \\(integer value: 9\\)"),
    ("2.5", "must evaluate to a NodeStatus-compatible value"),
    ("'WAITING'", "Cannot convert this to NodeStatus: WAITING"),
])
def test_bad_script_results_raise_runtime_errors(script, message):
    factory = factory_with('<AlwaysSuccess name="target"/>')
    factory.add_substitution_rule("target", {"return_status_script": script})
    with pytest.raises(BTRuntimeError, match=message):
        run(factory)


def test_status_names_are_visible_only_to_the_status_script():
    factory = factory_with('<AlwaysSuccess name="target"/>')
    factory.register_scripting_enum("ANSWER", 42)
    factory.add_substitution_rule("target", {"return_status": "SUCCESS",
                                             "post_script": "seen := SUCCESS; answer := ANSWER"})
    status, bb = run(factory, SUCCESS=99)
    assert status is S and bb.get("seen") == 99 and bb.get("answer") == 42


def test_async_delay_completes_on_the_timer():
    factory = factory_with('<Sequence><AlwaysSuccess name="slow"/></Sequence>')
    factory.add_substitution_rule("slow", {"return_status": "SUCCESS", "async_delay": 20})
    tree = factory.create_tree("Main")
    assert tree.tick_once() is NodeStatus.RUNNING
    assert tree.tick_while_running(sleep=0.005) is S


def test_subtree_can_be_substituted_without_expanding_it():
    factory = factory_with('<SubTree ID="Child" name="child"/>',
                           '<BehaviorTree ID="Child"><AlwaysFailure/></BehaviorTree>')
    factory.add_substitution_rule("child", {"return_status": "SUCCESS"})
    tree = factory.create_tree("Main")
    assert tree.tick_while_running() is S
    assert len(tree.subtrees) == 1


def test_later_rule_for_the_same_pattern_replaces_the_first():
    factory = factory_with('<AlwaysSuccess name="target"/>')
    factory.add_substitution_rule("target", {"return_status": "SUCCESS"})
    factory.add_substitution_rule("target", {"return_status": "FAILURE"})
    assert len(factory.substitution_rules) == 1
    assert run(factory)[0] is F


def test_json_rules_and_configs():
    factory = factory_with('<Sequence><AlwaysSuccess name="a"/><Greet name="b"/></Sequence>')
    factory.register_simple_action("Fails", lambda node: F)
    factory.load_substitution_rule_from_json(json.dumps({
        "TestNodeConfigs": {"Script": {"return_status_script": "flag ? FAILURE : SUCCESS"}},
        "SubstitutionRules": {"a": "Script", "b": "Fails"},
    }))
    assert run(factory, flag=False)[0] is F  # a succeeds, b is Fails
    assert dict(factory.substitution_rules)["b"] == "Fails"


@pytest.mark.parametrize("config", [{"post_script": "x := 1"}, {"return_status_script": ""}])
def test_json_config_without_a_status_is_refused(config):
    factory = BehaviorTreeFactory()
    with pytest.raises(BTRuntimeError, match=r"TestNodeConfig \[Broken\] must contain return_status"):
        factory.load_substitution_rule_from_json(json.dumps(
            {"TestNodeConfigs": {"Broken": config}, "SubstitutionRules": {"a": "Broken"}}))
    assert factory.substitution_rules == []


def test_json_config_with_a_bad_status_name_is_refused():
    with pytest.raises(BTRuntimeError, match="Cannot convert this to NodeStatus: DONE"):
        BehaviorTreeFactory().load_substitution_rule_from_json(json.dumps(
            {"TestNodeConfigs": {"Bad": {"return_status": "DONE"}}, "SubstitutionRules": {"a": "Bad"}}))


def test_fixed_idle_status_is_refused_when_built():
    factory = factory_with('<AlwaysSuccess name="target"/>')
    factory.add_substitution_rule("target", {"return_status": "IDLE"})
    with pytest.raises(BTRuntimeError, match="return_status resolved to invalid status"):
        factory.create_tree("Main")
