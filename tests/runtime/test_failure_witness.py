"""The run summary's failure witness names the leaf whose failure failed its SubTree, and
observes only the nodes it can report on (an observed node's status stores cost every tick)."""

import asyncio
from types import SimpleNamespace

from bt_runtime import BehaviorTreeFactory
from bt_runtime.node import NodeCell
from bt_runtime.runtime.explain import FailureWitness
from bt_runtime.status import FAILURE, SUCCESS

TREE = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence name="main">
      <Inverter name="not_blocked"><ScriptCondition name="blocked" code="blocked"/></Inverter>
      <SubTree ID="Plan" name="planning" _autoremap="true"/>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Plan">
    <Fallback name="plan">
      <ScriptCondition name="have_path" code="have_path"/>
      <Sequence name="replan">
        <Script name="count" code="tries += 1"/>
        <ScriptCondition name="planner_ok" code="planner_ok"/>
      </Sequence>
    </Fallback>
  </BehaviorTree>
</root>"""


async def _witness(**values):
    tree = BehaviorTreeFactory().create_tree_from_text(TREE)
    for key, value in {"blocked": False, "have_path": False, "tries": 0, "planner_ok": True, **values}.items():
        tree.root_blackboard.set(key, value)
    now = [0.0]
    runtime = SimpleNamespace(tree=tree, driver=SimpleNamespace(), clock=lambda: now[0],
                              loop=asyncio.get_running_loop())
    return tree, now, FailureWitness.attach(runtime)


async def test_the_leaf_that_failed_its_subtree_is_the_failing_node():
    tree, now, why = await _witness(planner_ok=False)
    now[0] = 2.5
    assert tree.tick_once() is FAILURE
    failure = why.last_node_failure()
    assert (failure.path, failure.node_type, failure.t) == ("planning/planner_ok", "ScriptCondition", 2.5)
    assert why.last_node_failure(since=3.0) is None
    assert "last failing node planning/planner_ok [ScriptCondition]" in why.reason()
    why.detach()


async def test_failures_the_tree_absorbs_are_not_causes():
    tree, _, why = await _witness()  # have_path fails, the fallback replans: the subtree succeeds
    for _ in range(3):
        assert tree.tick_once() is SUCCESS
    assert why.last_node_failure() is None
    assert why.reason() == "no node failed and the navigation stack reported no error"
    why.detach()


async def test_only_subtree_nodes_and_the_leaves_under_them_are_observed_until_detach():
    tree, _, why = await _witness()
    observed = {n.full_path for n in tree.nodes() if type(n._cell) is not NodeCell}
    assert observed == {"planning", "planning/have_path", "planning/count", "planning/planner_ok"}
    why.detach()
    assert all(type(n._cell) is NodeCell for n in tree.nodes())
