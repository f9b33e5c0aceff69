"""Sleeping between ticks answers a wake-up signal: the signal is consumed, as BT.CPP's
``Tree::sleep`` does, so the next tick does not tick the tree a second time for it."""

from __future__ import annotations

import asyncio
import time

from bt_runtime import BehaviorTreeFactory, NodeStatus, StatefulActionNode
from tests.engine.helpers import doc


class Poller(StatefulActionNode):
    """RUNNING for three ticks; its first tick arms a timer that emits a wake-up at once."""

    ticks: list[float] = []

    def on_start(self):
        Poller.ticks.append(time.monotonic())
        self.config.timers.add(0.0, self.emit_wake_up_signal)
        return NodeStatus.RUNNING

    def on_running(self):
        Poller.ticks.append(time.monotonic())
        return NodeStatus.SUCCESS if len(Poller.ticks) >= 3 else NodeStatus.RUNNING


def poller_tree():
    Poller.ticks = []
    factory = BehaviorTreeFactory()
    factory.register_node_type(Poller)
    return factory.create_tree_from_text(doc("<Poller/>"))


def test_sleep_returns_early_and_consumes_the_wake_up():
    tree = poller_tree()
    assert tree.tick_once() is NodeStatus.RUNNING
    started = time.monotonic()
    assert tree.sleep(5.0) is True  # the timer fired and woke it
    assert time.monotonic() - started < 1.0
    assert not tree.wake_up.is_set
    assert tree.tick_once() is NodeStatus.RUNNING
    assert len(Poller.ticks) == 2  # one tick, not a tick and a re-tick


def test_sleep_without_a_wake_up_waits_the_whole_time():
    tree = poller_tree()
    tree.tick_once()
    tree.sleep(0.0)  # consumes the timer's wake-up
    started = time.monotonic()
    assert tree.sleep(0.05) is False
    assert time.monotonic() - started >= 0.045


def test_tick_while_running_sleeps_after_a_woken_sleep():
    tree = poller_tree()
    assert tree.tick_while_running(sleep=0.05) is NodeStatus.SUCCESS
    first, second, third = Poller.ticks
    assert second - first < 0.04  # the wake-up cut the first sleep short
    assert third - second >= 0.045  # and was consumed: the second sleep ran in full


def test_async_tick_loop_consumes_the_wake_up():
    tree = poller_tree()
    assert asyncio.run(tree.tick_while_running_async(period=0.05)) is NodeStatus.SUCCESS
    first, second, third = Poller.ticks
    assert second - first < 0.04
    assert third - second >= 0.045


def test_exactly_once_leaves_the_wake_up_for_the_next_tick():
    tree = poller_tree()
    tree.tick_once()
    tree.wake_up.emit()
    assert tree.tick_exactly_once() is NodeStatus.RUNNING
    assert tree.wake_up.is_set
