"""Small helpers shared by the engine unit tests."""

from __future__ import annotations

from collections import Counter

from bt_runtime import BehaviorTreeFactory, NodeStatus


def doc(body: str, extra: str = "", main: str = "Main") -> str:
    """A v4 document whose main tree ``main`` is ``body``."""
    return (f'<root BTCPP_format="4" main_tree_to_execute="{main}">'
            f'<BehaviorTree ID="{main}">{body}</BehaviorTree>{extra}</root>')


class FakeClock:
    """A clock (seconds) that only moves when told to."""

    def __init__(self, start: float = 100.0):
        self.now = start

    def __call__(self) -> float:
        return self.now

    def advance(self, seconds: float) -> None:
        self.now += seconds


def counting_factory(*results: str) -> tuple[BehaviorTreeFactory, Counter]:
    """A factory with ``Count`` (SUCCESS), ``CountFail`` (FAILURE) and ``Script``-free leaves
    ``Seq`` returning the given statuses in turn; ticks are counted per instance name."""
    factory = BehaviorTreeFactory()
    counts: Counter = Counter()
    queue = list(results)

    def count(node):
        counts[node.name] += 1
        return NodeStatus.SUCCESS

    def count_fail(node):
        counts[node.name] += 1
        return NodeStatus.FAILURE

    def scripted(node):
        counts[node.name] += 1
        return NodeStatus[queue.pop(0)] if len(queue) > 1 else NodeStatus[queue[0]]

    factory.register_simple_action("Count", count)
    factory.register_simple_action("CountFail", count_fail)
    factory.register_simple_condition("Scripted", scripted)
    return factory, counts
