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
