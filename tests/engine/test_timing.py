"""Sleep, Timeout and Delay on a fake clock: timers fire at tick boundaries (a deliberate
difference from BT.CPP's timer thread, see docs/btcpp_differences.md)."""

from __future__ import annotations

import pytest

from bt_runtime import BehaviorTreeFactory, NodeStatus
from tests.engine.helpers import FakeClock, counting_factory, doc

S, F, R, IDLE = NodeStatus.SUCCESS, NodeStatus.FAILURE, NodeStatus.RUNNING, NodeStatus.IDLE


def make(body: str, factory: BehaviorTreeFactory | None = None):
    factory = factory or BehaviorTreeFactory()
    tree = factory.create_tree_from_text(doc(body))
    clock = FakeClock()
    tree.set_clock(clock)
    return tree, clock


def test_sleep_runs_until_deadline():
    tree, clock = make('<Sleep msec="100"/>')
    assert tree.tick_once() is R
    clock.advance(0.099)
    assert tree.tick_once() is R
    clock.advance(0.001)
    assert tree.tick_once() is S


def test_sleep_zero_succeeds_at_once():
    tree, _ = make('<Sleep msec="0"/>')
    assert tree.tick_exactly_once() is S


def test_sleep_msec_from_blackboard_and_missing():
    tree, clock = make('<Sleep msec="{d}"/>')
    tree.root_blackboard.set("d", "50")  # a string feeds the unsigned port
    assert tree.tick_once() is R
    clock.advance(0.05)
    assert tree.tick_once() is S
    tree, _ = make('<Sleep msec="{nothing}"/>')
    with pytest.raises(Exception, match=r"Missing parameter \[msec\] in SleepNode"):
        tree.tick_once()


def test_sleep_halt_cancels_timer():
    tree, clock = make('<Sleep msec="100"/>')
    assert tree.tick_once() is R
    tree.halt_tree()
    assert len(tree.timers) == 0
    assert tree.tick_once() is R  # restarts with a fresh deadline
    clock.advance(0.1)
    assert tree.tick_once() is S


def test_sleep_timer_emits_wake_up():
    tree, clock = make('<Sleep msec="10"/>')
    tree.tick_once()
    clock.advance(0.01)
    assert tree.sleep(1.0) is True  # woken by the timer, without waiting the full second


def test_timeout_halts_running_child():
    factory, _ = counting_factory()
    halted = []
    factory.register_simple_stateful_action("Forever", lambda n: R, lambda n: R, lambda n: halted.append(1))
    tree, clock = make('<Timeout msec="200"><Forever/></Timeout>', factory)
    assert tree.tick_once() is R
    clock.advance(0.150)
    assert tree.tick_once() is R
    clock.advance(0.050)
    assert tree.tick_once() is F
    assert halted == [1]
    assert tree.root_node.status is IDLE
    assert tree.tick_once() is R  # a new activation restarts the timer
    clock.advance(0.199)
    assert tree.tick_once() is R


def test_timeout_child_finishes_in_time():
    factory, _ = counting_factory("RUNNING", "RUNNING", "SUCCESS")
    tree, clock = make('<Timeout msec="100"><Scripted/></Timeout>', factory)
    assert tree.tick_once() is R
    clock.advance(0.05)
    assert tree.tick_once() is R
    assert tree.tick_once() is S
    assert len(tree.timers) == 0  # the timer was cancelled
    clock.advance(1.0)
    assert tree.tick_once() is S


def test_timeout_zero_never_fires():
    factory, _ = counting_factory("RUNNING")
    tree, clock = make('<Timeout msec="0"><Scripted/></Timeout>', factory)
    for _ in range(3):
        assert tree.tick_once() is R
        clock.advance(10)


def test_timeout_with_sleep_child():
    tree, clock = make('<Timeout msec="50"><Sleep msec="500"/></Timeout>')
    assert tree.tick_once() is R
    clock.advance(0.05)
    assert tree.tick_once() is F


def test_timeout_halted_by_parent_cancels_timer():
    factory, _ = counting_factory()
    factory.register_simple_stateful_action("Forever", lambda n: R, lambda n: R)
    tree, clock = make('<Timeout msec="100"><Forever/></Timeout>', factory)
    tree.tick_once()
    tree.halt_tree()
    assert len(tree.timers) == 0


def test_delay_waits_without_ticking_child():
    factory, counts = counting_factory()
    tree, clock = make('<Delay delay_msec="100"><Count name="c"/></Delay>', factory)
    assert tree.tick_once() is R
    clock.advance(0.05)
    assert tree.tick_once() is R
    assert counts["c"] == 0
    clock.advance(0.05)
    assert tree.tick_once() is S
    assert counts["c"] == 1
    assert tree.tick_once() is R  # next activation waits again


def test_delay_then_running_child():
    factory, counts = counting_factory("RUNNING", "FAILURE")
    tree, clock = make('<Delay delay_msec="10"><Scripted name="c"/></Delay>', factory)
    assert tree.tick_exactly_once() is R
    clock.advance(0.01)
    assert tree.tick_exactly_once() is R  # the timer fired at the start of this tick
    assert tree.tick_exactly_once() is F
    assert counts["c"] == 2


def test_delay_expiry_wakes_tick_once():
    """As in BT.CPP, the timer's wake-up makes tick_once tick again at once."""
    factory, counts = counting_factory("RUNNING", "FAILURE")
    tree, clock = make('<Delay delay_msec="10"><Scripted name="c"/></Delay>', factory)
    assert tree.tick_once() is R
    clock.advance(0.01)
    assert tree.tick_once() is F
    assert counts["c"] == 2


def test_delay_halt_cancels():
    factory, counts = counting_factory()
    tree, clock = make('<Delay delay_msec="10"><Count name="c"/></Delay>', factory)
    tree.tick_once()
    tree.halt_tree()
    assert len(tree.timers) == 0
    clock.advance(1)
    assert tree.tick_once() is R  # restarted: waits again
    assert counts["c"] == 0


def test_tick_while_running_with_real_time():
    tree = BehaviorTreeFactory().create_tree_from_text(doc('<Sequence><Sleep msec="5"/><Sleep msec="5"/></Sequence>'))
    assert tree.tick_while_running(0.05) is S  # woken by each timer, not the 50 ms period


async def test_tick_while_running_async_uses_loop_clock():
    tree = BehaviorTreeFactory().create_tree_from_text(doc('<Delay delay_msec="20"><Sleep msec="20"/></Delay>'))
    assert await tree.tick_while_running_async(0.5) is S
