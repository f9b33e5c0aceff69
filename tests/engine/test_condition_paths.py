"""Nodes with pre/post conditions keep the checks of their class (sync actions may not return
RUNNING; decorators reset a completed child) and report script errors like any other node."""

from __future__ import annotations

import pytest

from bt_runtime import BehaviorTreeFactory, NodeStatus, SyncActionNode
from bt_runtime.errors import BehaviorTreeException
from bt_runtime.node import ActionNodeBase


class Stuck(SyncActionNode):
    def tick(self) -> NodeStatus:
        return NodeStatus.RUNNING


def _tree(body: str):
    f = BehaviorTreeFactory()
    f.register_node_type(Stuck)
    return f.create_tree_from_text(f'<root BTCPP_format="4"><BehaviorTree ID="M">{body}</BehaviorTree></root>')


@pytest.mark.parametrize("attrs", ["", ' _skipIf="false"', ' _post="x := 1"'])
def test_a_sync_action_returning_running_is_an_error_with_or_without_conditions(attrs: str) -> None:
    tree = _tree(f"<Sequence><Stuck{attrs}/></Sequence>")
    with pytest.raises(BehaviorTreeException, match="never return RUNNING"):
        tree.tick_exactly_once()


@pytest.mark.parametrize("hooked", [False, True])
def test_a_failing_pre_condition_script_is_reported_with_its_text(hooked: bool) -> None:
    """The specialised condition path and the full one (taken with a hook) report alike."""
    tree = _tree('<Sequence><AlwaysSuccess name="a" _skipIf="missing &gt; 1"/></Sequence>')
    if hooked:
        next(n for n in tree.nodes() if n.name == "a").set_pre_tick_function(lambda node: None)
    with pytest.raises(BehaviorTreeException, match=r"Error in script \[missing > 1\]\nVariable not found: missing"):
        tree.tick_exactly_once()


class FromBlackboard(ActionNodeBase):
    """Returns the status named by the blackboard entry 'ret' (RUNNING included)."""

    def tick(self) -> NodeStatus:
        return NodeStatus[self.config.blackboard.get("ret")]


CONDITION_SETS = [
    '_skipIf="skip"', '_successIf="ok"', '_failureIf="bad"', '_while="go"',
    '_skipIf="skip" _onSuccess="s += 1" _onFailure="f += 1"', '_while="go" _onHalted="h += 1" _post="p += 1"',
    '_failureIf="bad" _post="p += 1"', '_post="p += 1"', '_onSuccess="s += 1"',
    '_skipIf="skip" _successIf="ok" _failureIf="bad" _while="go"',  # several checks: the general closure
    '_successIf="ok" _onSuccess="s += 1" _post="p := p + 2" _onFailure="f += 1"',
]


@pytest.mark.parametrize("attrs", CONDITION_SETS)
def test_specialised_condition_ticks_match_the_full_path(attrs: str) -> None:
    """Over a seeded run of changing blackboards, a node with conditions ticks exactly as the
    full path does (taken when a hook is set), RUNNING and halts included."""
    import random

    from bt_runtime.condition_tick import conditions_tick

    def run(hooked: bool) -> list:
        f = BehaviorTreeFactory()
        f.register_node_type(FromBlackboard)
        tree = f.create_tree_from_text(
            '<root BTCPP_format="4"><BehaviorTree ID="M"><ReactiveSequence>'
            f'<ScriptCondition code="live"/><FromBlackboard name="n" {attrs}/>'
            '</ReactiveSequence></BehaviorTree></root>')
        node = next(n for n in tree.nodes() if n.name == "n")
        if hooked:
            node.set_pre_tick_function(lambda n: None)
        else:
            assert node._cell.fast.__module__ == conditions_tick.__module__
        bb = tree.root_blackboard
        for key in ("s", "f", "p", "h"):
            bb.set(key, 0.0)
        rng = random.Random(1414)
        seen = []
        for _ in range(300):
            for key in ("skip", "ok", "bad", "live"):
                bb.set(key, float(rng.random() < (0.8 if key == "live" else 0.25)))
            bb.set("go", float(rng.random() < 0.8))
            bb.set("ret", rng.choice(["SUCCESS", "FAILURE", "RUNNING", "RUNNING"]))
            seen.append((tree.tick_exactly_once().name, node.status.name,
                         *(bb.get(k) for k in ("s", "f", "p", "h"))))
        return seen

    assert run(hooked=False) == run(hooked=True)



@pytest.mark.parametrize("attrs", ['_skipIf="flag"', '_skipIf="flag" _failureIf="flag &gt; 1" _post="n += 1"'])
def test_nodes_sharing_conditions_each_use_their_own_blackboard(attrs: str) -> None:
    """Equal condition closures are shared between nodes built together; each node still reads
    its own blackboard: the same `_skipIf` skips in the SubTree whose `flag` is set only."""
    f = BehaviorTreeFactory()
    tree = f.create_tree_from_text(f"""<root BTCPP_format="4" main_tree_to_execute="M">
      <BehaviorTree ID="M"><Sequence>
        <Script code="ran_off := 0; ran_on := 0"/>
        <SubTree ID="S" name="on" flag="1" n="0" ran="{{ran_on}}"/>
        <SubTree ID="S" name="off" flag="0" n="0" ran="{{ran_off}}"/>
      </Sequence></BehaviorTree>
      <BehaviorTree ID="S"><Script code="ran := 1" {attrs}/></BehaviorTree></root>""")
    assert tree.tick_exactly_once() is NodeStatus.SUCCESS
    bb = tree.root_blackboard
    assert (bb.get("ran_off"), bb.get("ran_on")) == (1, 0)


_FLAG_VALUES = {"missing": None, "zero": 0.0, "one": 1.0, "negative": -2.0, "nan": float("nan"), "int": 3,
                "string": "true", "bool": True}


@pytest.mark.parametrize("attr", ["_skipIf", "_failureIf", "_successIf", "_while"])
@pytest.mark.parametrize("code", ["flag", "!flag"])
@pytest.mark.parametrize("value", list(_FLAG_VALUES))
@pytest.mark.parametrize("shadowed", [False, True])
def test_a_check_reading_one_variable_gives_what_the_full_tick_gives(attr, code, value, shadowed) -> None:
    """condition_tick reads a double for 'flag' / '!flag' itself: every kind of entry (and a
    scripting enum of that name) gives the status, or the error, that the full executeTick
    path (taken by a node with a hook) gives."""
    def outcome(hooked: bool):
        f = BehaviorTreeFactory()
        f.register_simple_action("Act", lambda node: NodeStatus.SUCCESS)
        if shadowed:
            f.register_scripting_enum("flag", 1)
        tree = f.create_tree_from_text(f'<root BTCPP_format="4"><BehaviorTree ID="M"><Sequence>'
                                       f'<Act {attr}="{code}"/></Sequence></BehaviorTree></root>')
        if _FLAG_VALUES[value] is not None:
            tree.root_blackboard.set("flag", _FLAG_VALUES[value])
        node = tree.root_node.children[0]
        if hooked:
            node.set_pre_tick_function(lambda n: None)
        seen = []
        for _ in range(2):
            try:
                seen.append(tree.tick_exactly_once().name)
            except BehaviorTreeException as exc:
                seen.append(f"{type(exc).__name__}: {exc}")
        return seen

    assert outcome(False) == outcome(True)


def test_a_node_given_other_conditions_does_not_change_its_twins() -> None:
    """Elements with the same condition attributes share their compiled scripts while the
    tree is built; a node whose conditions are changed afterwards gets its own, the others
    keep theirs (and an error in a shared script still names the first element carrying it)."""
    from bt_runtime.script import compile_script

    twin = '_skipIf="skip" _onSuccess="n += 1"'
    tree = _tree(f'<Sequence><AlwaysSuccess name="a" {twin}/><AlwaysSuccess name="b" {twin}/></Sequence>')
    tree.root_blackboard.set("skip", True)
    tree.root_blackboard.set("n", 0)
    a, b = (n for n in tree.nodes() if n.name in ("a", "b"))
    a.config.pre_conditions["_skipIf"] = compile_script("!skip")
    a.refresh_conditions()
    assert "_skipIf" in b.config.pre_conditions and b.config.pre_conditions["_skipIf"].text == "skip"
    assert tree.tick_exactly_once() is NodeStatus.SUCCESS
    assert tree.root_blackboard.get("n") == 1  # a ran, b was skipped
    with pytest.raises(BehaviorTreeException, match="line 2") as raised:
        BehaviorTreeFactory().create_tree_from_text(
            '<root BTCPP_format="4"><BehaviorTree ID="M"><Sequence>\n<AlwaysSuccess _skipIf="a +"/>\n'
            '<AlwaysSuccess _skipIf="a +"/></Sequence></BehaviorTree></root>')
    assert "_skipIf" in str(raised.value)
