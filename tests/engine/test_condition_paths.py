"""Nodes with pre/post conditions keep the checks of their class (sync actions may not return
RUNNING; decorators reset a completed child) and report script errors like any other node."""

from __future__ import annotations

import pytest

from bt_runtime import BehaviorTreeFactory, NodeStatus, SyncActionNode
from bt_runtime.errors import BehaviorTreeException


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
