"""halt_tree halts every running node even when some on_halted raises; the errors come after."""

from __future__ import annotations

import pytest

from bt_runtime.factory import BehaviorTreeFactory
from bt_runtime.node import StatefulActionNode
from bt_runtime.status import IDLE, RUNNING
from bt_runtime.tree import HaltError
from tests.helpers import tree_xml


class Busy(StatefulActionNode):
    halted: list[str] = []

    def on_start(self):
        return RUNNING

    def on_running(self):
        return RUNNING

    def on_halted(self):
        Busy.halted.append(self.name)
        if self.name.startswith("bad"):
            raise RuntimeError(f"{self.name} cannot stop")


def test_halt_tree_halts_every_node_and_reports_the_failures_afterwards():
    factory = BehaviorTreeFactory()
    factory.register_node_type(Busy)
    body = ('<Parallel success_count="-1" failure_count="1">'
            '<Busy name="bad_first"/><Busy name="second"/>'
            '<Sequence><Busy name="bad_nested"/></Sequence><Busy name="last"/></Parallel>')
    tree = factory.create_tree_from_text(tree_xml(body))
    Busy.halted = []
    assert tree.tick_once() is RUNNING
    with pytest.raises(HaltError) as caught:
        tree.halt_tree()
    assert {"bad_first", "second", "bad_nested", "last"} <= set(Busy.halted)
    assert all(node.status is IDLE for node in tree.nodes())
    paths = [path for path, _ in caught.value.errors]
    assert len(paths) == 2 and any("bad_first" in p for p in paths) and any("bad_nested" in p for p in paths)
    assert "bad_first cannot stop" in str(caught.value)
