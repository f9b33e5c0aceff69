"""AsyncActionNode (our replacement for BT.CPP's ThreadedAction) and StatefulActionNode."""

from __future__ import annotations

import asyncio

import pytest

from bt_runtime import (
    AsyncActionNode,
    BehaviorTreeFactory,
    LogicError,
    NodeExecutionError,
    NodeStatus,
    StatefulActionNode,
    input_port,
)
from tests.engine.helpers import doc

S, F, R, IDLE = NodeStatus.SUCCESS, NodeStatus.FAILURE, NodeStatus.RUNNING, NodeStatus.IDLE


class Wait(AsyncActionNode):
    events: list[str] = []

    @classmethod
    def provided_ports(cls):
        return [input_port("delay", float, 0.01), input_port("result", NodeStatus, S)]

    async def run(self) -> NodeStatus:
        Wait.events.append(f"run:{self.name}")
        try:
            await asyncio.sleep(self.get_input("delay"))
        except asyncio.CancelledError:
            Wait.events.append(f"cancelled:{self.name}")
            raise
        Wait.events.append(f"done:{self.name}")
        return self.get_input("result")

    def on_halted(self) -> None:
        Wait.events.append(f"on_halted:{self.name}")


class Boom(AsyncActionNode):
    async def run(self) -> NodeStatus:
        await asyncio.sleep(0)
        raise ValueError("sensor unplugged")


@pytest.fixture
def factory():
    Wait.events = []
    f = BehaviorTreeFactory()
    f.register_node_type(Wait)
    f.register_node_type(Boom)
    return f


async def test_started_on_first_tick_and_polled(factory):
    tree = factory.create_tree_from_text(doc('<Wait name="w" delay="0.02"/>'))
    assert tree.tick_once() is R
    await asyncio.sleep(0)
    assert Wait.events == ["run:w"]
    assert tree.tick_once() is R  # polled, not restarted
    await asyncio.sleep(0.03)
    assert tree.tick_once() is S
    assert Wait.events == ["run:w", "done:w"]
    assert tree.root_node.status is IDLE


async def test_tick_while_running_async(factory):
    tree = factory.create_tree_from_text(doc(
        '<Sequence><Wait name="a"/><Wait name="b" result="FAILURE"/><Wait name="c"/></Sequence>'))
    assert await tree.tick_while_running_async(0.001) is F
    assert Wait.events == ["run:a", "done:a", "run:b", "done:b"]


async def test_parallel_async_children_run_concurrently(factory):
    tree = factory.create_tree_from_text(doc(
        '<Parallel><Wait name="a" delay="0.05"/><Wait name="b" delay="0.05"/></Parallel>'))
    loop = asyncio.get_running_loop()
    start = loop.time()
    assert await tree.tick_while_running_async(0.001) is S
    assert loop.time() - start < 0.09


async def test_wake_up_cuts_the_period_short(factory):
    tree = factory.create_tree_from_text(doc('<Wait name="w" delay="0.01"/>'))
    loop = asyncio.get_running_loop()
    start = loop.time()
    assert await tree.tick_while_running_async(5.0) is S  # not one 5 s period
    assert loop.time() - start < 1.0


async def test_cancelled_on_halt(factory):
    tree = factory.create_tree_from_text(doc('<Wait name="w" delay="10"/>'))
    assert tree.tick_once() is R
    await asyncio.sleep(0)
    tree.halt_tree()
    await asyncio.sleep(0)
    assert Wait.events == ["run:w", "on_halted:w", "cancelled:w"]
    assert tree.root_node.status is IDLE


async def test_halted_by_reactive_parent(factory):
    factory.register_simple_condition("Flag", lambda n: S if n.blackboard.get("ok") else F)
    tree = factory.create_tree_from_text(doc('<ReactiveSequence><Flag/><Wait name="w" delay="10"/></ReactiveSequence>'))
    tree.root_blackboard.set("ok", True)
    assert tree.tick_once() is R
    await asyncio.sleep(0)
    tree.root_blackboard.set("ok", False)
    assert tree.tick_once() is F
    await asyncio.sleep(0)
    assert "cancelled:w" in Wait.events


async def test_exception_propagates_with_node_path(factory):
    tree = factory.create_tree_from_text(doc('<Sequence><Boom name="boom"/></Sequence>'))
    with pytest.raises(NodeExecutionError) as info:
        await tree.tick_while_running_async(0.001)
    assert info.value.node_path == "boom"
    assert info.value.registration_id == "Boom"
    assert isinstance(info.value.original, ValueError)
    assert "Exception in node 'boom' [Boom]: sensor unplugged" in str(info.value)


async def test_exception_inside_subtree_names_full_path(factory):
    xml = doc('<SubTree ID="Inner" name="inner"/>',
              '<BehaviorTree ID="Inner"><Sequence><Boom/></Sequence></BehaviorTree>')
    tree = factory.create_tree_from_text(xml)
    with pytest.raises(NodeExecutionError) as info:
        await tree.tick_while_running_async(0.001)
    assert info.value.node_path == "inner/Boom::3"


def test_needs_a_running_loop(factory):
    tree = factory.create_tree_from_text(doc('<Wait name="w"/>'))
    with pytest.raises(NodeExecutionError) as info:
        tree.tick_once()
    assert isinstance(info.value.original, LogicError)
    assert "needs a running asyncio event loop" in str(info.value)


async def test_async_failure_is_cleaned_up_by_tick_while_running_async(factory):
    """An error out of tick_while_running_async halts the tree (cancelling other tasks)."""
    tree = factory.create_tree_from_text(doc('<Parallel><Wait name="slow" delay="10"/><Boom/></Parallel>'))
    with pytest.raises(NodeExecutionError):
        await tree.tick_while_running_async(0.001)
    await asyncio.sleep(0)
    assert "cancelled:slow" in Wait.events


# -- StatefulActionNode ------------------------------------------------------------------------------

class Count3(StatefulActionNode):
    log: list[str] = []

    def on_start(self) -> NodeStatus:
        self.n = 0
        Count3.log.append("start")
        return R

    def on_running(self) -> NodeStatus:
        self.n += 1
        Count3.log.append(f"running{self.n}")
        return S if self.n >= 3 else R

    def on_halted(self) -> None:
        Count3.log.append(f"halted(requested={self.is_halt_requested()})")


def test_stateful_action_lifecycle():
    Count3.log = []
    factory = BehaviorTreeFactory()
    factory.register_node_type(Count3)
    tree = factory.create_tree_from_text(doc("<Count3/>"))
    assert [tree.tick_once() for _ in range(4)] == [R, R, R, S]
    assert Count3.log == ["start", "running1", "running2", "running3"]
    tree.tick_once()
    tree.halt_tree()
    assert Count3.log[-2:] == ["start", "halted(requested=True)"]
    tree.halt_tree()  # not RUNNING: on_halted is not called again
    assert Count3.log.count("halted(requested=True)") == 1


def test_stateful_on_start_must_not_return_idle():
    factory = BehaviorTreeFactory()
    factory.register_simple_stateful_action("Bad", lambda n: NodeStatus.IDLE, lambda n: S)
    tree = factory.create_tree_from_text(doc("<Bad/>"))
    with pytest.raises(NodeExecutionError, match="onStart\\(\\) must not return IDLE"):
        tree.tick_once()


def test_stateful_immediate_success_skips_on_running():
    calls = []
    factory = BehaviorTreeFactory()
    factory.register_simple_stateful_action("Quick", lambda n: calls.append("start") or S,
                                            lambda n: calls.append("run") or S)
    tree = factory.create_tree_from_text(doc("<Quick/>"))
    assert tree.tick_once() is S
    assert tree.tick_once() is S
    assert calls == ["start", "start"]


def test_sync_action_returning_running_is_an_error():
    factory = BehaviorTreeFactory()
    factory.register_simple_action("Runs", lambda n: R)
    tree = factory.create_tree_from_text(doc("<Runs/>"))
    with pytest.raises(NodeExecutionError, match="SyncActionNode MUST never return RUNNING"):
        tree.tick_once()


def test_condition_may_return_running():
    factory = BehaviorTreeFactory()
    factory.register_simple_condition("Maybe", lambda n: R)
    tree = factory.create_tree_from_text(doc("<Maybe/>"))
    assert tree.tick_once() is R


def test_node_returning_idle_is_an_error():
    factory = BehaviorTreeFactory()
    factory.register_simple_action("Idle", lambda n: NodeStatus.IDLE)
    tree = factory.create_tree_from_text(doc("<Sequence><Idle/></Sequence>"))
    with pytest.raises(NodeExecutionError, match="not allowed to set manually the status to IDLE"):
        tree.tick_once()
