"""Status observers that want FAILURE only (the run summary's failure witness) see exactly the
changes to FAILURE, beside observers that see everything, and unsubscribe cleanly."""

from bt_runtime import BehaviorTreeFactory
from bt_runtime.status import FAILURE

TREE = """<root BTCPP_format="4"><BehaviorTree ID="Main">
  <Sequence>
    <Script code="n := 0"/>
    <Repeat num_cycles="3"><Script code="n += 1"/></Repeat>
    <ScriptCondition code="n == 99"/>
  </Sequence>
</BehaviorTree></root>"""


def _run(observers):
    tree = BehaviorTreeFactory().create_tree_from_text(TREE)
    seen = {name: [] for name, _ in observers}
    removers = [tree.add_status_observer(lambda t, node, prev, new, name=name: seen[name].append(
        (node.name, prev.name, new.name)), failures_only=only) for name, only in observers]
    assert tree.tick_while_running() is FAILURE
    return tree, seen, removers


def test_failures_only_sees_exactly_the_changes_to_failure():
    _, seen, _ = _run([("all", False), ("failures", True)])
    assert seen["failures"] == [c for c in seen["all"] if c[2] == "FAILURE"]
    assert {c[0] for c in seen["failures"]} == {"ScriptCondition", "Sequence"}
    assert len(seen["all"]) > len(seen["failures"])


def test_failures_only_alone_and_after_the_full_observer_leaves():
    tree, seen, removers = _run([("failures", True)])
    alone = list(seen["failures"])
    assert alone and all(c[2] == "FAILURE" for c in alone)
    full = []
    remove_full = tree.add_status_observer(lambda *a: full.append(a))
    tree.tick_while_running()
    assert full and any(a[3] is not FAILURE for a in full)
    remove_full()
    n_full = len(full)
    seen["failures"].clear()
    tree.tick_while_running()
    assert len(full) == n_full  # gone
    assert seen["failures"] == alone  # the failure-only observer still hears failures, only them
    removers[0]()
    seen["failures"].clear()
    tree.tick_while_running()
    assert seen["failures"] == []
