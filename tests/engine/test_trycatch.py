"""TryCatch (BT.CPP 4.9+; absent from the 4.8.2 oracle): upstream gtest_try_catch.cpp semantics."""

from __future__ import annotations

import pytest

from bt_runtime import NodeStatus, XMLLoadError
from tests.engine.helpers import counting_factory, doc

S, F, R = NodeStatus.SUCCESS, NodeStatus.FAILURE, NodeStatus.RUNNING


def test_all_try_children_succeed():
    factory, counts = counting_factory()
    tree = factory.create_tree_from_text(doc('<TryCatch><Count name="a"/><Count name="b"/>'
                                             '<Count name="catch"/></TryCatch>'))
    assert tree.tick_while_running(0) is S
    assert counts == {"a": 1, "b": 1}


@pytest.mark.parametrize("catch", ["AlwaysSuccess", "AlwaysFailure", "Count"])
def test_failure_runs_catch_and_always_fails(catch):
    factory, counts = counting_factory()
    tree = factory.create_tree_from_text(doc(f'<TryCatch><Count name="a"/><AlwaysFailure/><Count name="b"/>'
                                             f'<{catch} name="catch"/></TryCatch>'))
    assert tree.tick_exactly_once() is F  # the catch child runs within the failing tick
    assert counts["a"] == 1 and counts["b"] == 0
    assert counts["catch"] == (1 if catch == "Count" else 0)


def test_running_try_child_then_success():
    factory, counts = counting_factory("RUNNING", "SUCCESS")
    tree = factory.create_tree_from_text(doc('<TryCatch><Scripted name="t"/><Count name="catch"/></TryCatch>'))
    assert tree.tick_once() is R
    assert tree.tick_once() is S
    assert counts["catch"] == 0


def test_running_catch_child_then_failure():
    factory, counts = counting_factory("RUNNING", "SUCCESS")
    tree = factory.create_tree_from_text(doc('<TryCatch><AlwaysFailure/><Scripted name="c"/></TryCatch>'))
    assert tree.tick_once() is R
    assert tree.tick_once() is F  # the catch child succeeded, TryCatch still fails
    assert counts["c"] == 2


def test_one_child_rejected_at_load():
    factory, _ = counting_factory()
    with pytest.raises(XMLLoadError, match="at least 2 children"):
        factory.create_tree_from_text(doc("<TryCatch><AlwaysSuccess/></TryCatch>"))


def test_re_execution_after_failure_starts_at_first_try_child():
    factory, counts = counting_factory("FAILURE", "SUCCESS")
    tree = factory.create_tree_from_text(doc('<TryCatch><Scripted name="t"/><Count name="catch"/></TryCatch>'))
    assert tree.tick_while_running(0) is F
    assert counts["catch"] == 1
    tree.halt_tree()
    assert tree.tick_while_running(0) is S
    assert counts == {"t": 2, "catch": 1}


@pytest.mark.parametrize("catch_on_halt, expected", [("false", 0), ("true", 1)])
def test_catch_on_halt(catch_on_halt, expected):
    factory, counts = counting_factory("RUNNING")
    tree = factory.create_tree_from_text(doc(f'<TryCatch catch_on_halt="{catch_on_halt}"><Scripted name="t"/>'
                                             '<Count name="catch"/></TryCatch>'))
    assert tree.tick_once() is R
    tree.halt_tree()
    assert counts["catch"] == expected
    assert tree.root_node.status is NodeStatus.IDLE


def test_catch_on_halt_not_when_already_in_catch():
    factory, counts = counting_factory("RUNNING")
    tree = factory.create_tree_from_text(doc('<TryCatch catch_on_halt="true"><AlwaysFailure/>'
                                             '<Scripted name="c"/></TryCatch>'))
    assert tree.tick_once() is R
    tree.halt_tree()
    assert counts["c"] == 1


def test_catch_on_halt_not_when_idle():
    factory, counts = counting_factory()
    tree = factory.create_tree_from_text(doc('<TryCatch catch_on_halt="true"><Count name="t"/>'
                                             '<Count name="catch"/></TryCatch>'))
    tree.halt_tree()
    assert counts["catch"] == 0


def test_running_catch_halted_by_catch_on_halt():
    """A catch child that is still RUNNING after its one synchronous tick on halt is halted."""
    factory, counts = counting_factory("RUNNING")
    halted = []
    factory.register_simple_stateful_action("Cleanup", lambda n: R, lambda n: R, lambda n: halted.append(n.name))
    tree = factory.create_tree_from_text(doc('<TryCatch catch_on_halt="true"><Scripted name="t"/>'
                                             '<Cleanup name="clean"/></TryCatch>'))
    assert tree.tick_once() is R
    tree.halt_tree()
    assert halted == ["clean"]


def test_catch_inside_sequence_keeps_running_until_done():
    factory, counts = counting_factory("RUNNING", "RUNNING", "RUNNING", "SUCCESS")
    tree = factory.create_tree_from_text(doc('<Sequence><TryCatch><AlwaysFailure/><Scripted name="c"/>'
                                             '</TryCatch><Count name="after"/></Sequence>'))
    assert [tree.tick_once() for _ in range(4)] == [R, R, R, F]
    assert counts["after"] == 0


def test_skipped_try_children():
    factory, counts = counting_factory()
    tree = factory.create_tree_from_text(doc('<TryCatch><Count name="a" _skipIf="1"/><Count name="b" _skipIf="1"/>'
                                             '<Count name="catch"/></TryCatch>'))
    assert tree.tick_once() is NodeStatus.SKIPPED
    tree = factory.create_tree_from_text(doc('<TryCatch><Count name="a" _skipIf="1"/><Count name="b"/>'
                                             '<Count name="catch"/></TryCatch>'))
    assert tree.tick_once() is S
    assert counts == {"b": 1}


def test_catch_body_sees_blackboard_of_try():
    factory, _ = counting_factory()
    tree = factory.create_tree_from_text(doc(
        '<TryCatch><Script code="step := 1"/><ScriptCondition code="step == 2"/>'
        '<Script code="recovered := step"/></TryCatch>'))
    assert tree.tick_once() is F
    assert tree.root_blackboard.get("recovered") == 1
