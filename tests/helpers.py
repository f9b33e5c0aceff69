"""Small helpers shared by the runtime and node tests."""

from __future__ import annotations


def tree_xml(body: str) -> str:
    """A one-tree BT.CPP v4 document whose main tree ``Main`` is ``body``."""
    return f'<root BTCPP_format="4"><BehaviorTree ID="Main">{body}</BehaviorTree></root>'


IDLE_TREE = tree_xml('<KeepRunningUntilFailure><AlwaysSuccess/></KeepRunningUntilFailure>')
