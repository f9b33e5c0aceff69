"""Real-time pacing: the default loop has microsecond timers and the tick task does not spin."""

from __future__ import annotations

import asyncio
import selectors

import pytest
from pydantic import ValidationError

from bt_runtime.runtime import clock
from bt_runtime.runtime.config import RuntimeConfig, TickConfig


def test_real_time_runs_use_a_select_loop() -> None:
    async def which_selector():
        return type(asyncio.get_running_loop()._selector)  # type: ignore[attr-defined]

    assert clock.run(which_selector, virtual=False) is selectors.SelectSelector


def test_pacing_is_efficient_by_default_and_validated() -> None:
    assert RuntimeConfig().tick.pacing == "efficient"
    assert TickConfig(pacing="precise").pacing == "precise"
    with pytest.raises(ValidationError):
        TickConfig(pacing="busy")


def _run_real_time(xml: str, pacing: str = "efficient", seconds: float = 1.0, **config):
    from bt_runtime import BehaviorTreeFactory
    from bt_runtime.runtime import tick_loop

    tree = BehaviorTreeFactory().create_tree_from_text(xml)
    loop = tick_loop.TickLoop(tree, TickConfig(pacing=pacing, **config), realtime=True)

    async def main():
        await asyncio.wait_for(loop.run(), seconds)

    clock.run(main, virtual=False)
    return loop


def _leaf_loop(leaf):
    """A real-time tick loop (default pacing) of ``KeepRunningUntilFailure`` over one condition
    whose tick is ``leaf``: the tree runs until ``leaf`` fails."""
    from bt_runtime import BehaviorTreeFactory
    from bt_runtime.runtime import tick_loop

    factory = BehaviorTreeFactory()
    factory.register_simple_condition("Leaf", leaf)
    tree = factory.create_tree_from_text('<root BTCPP_format="4"><BehaviorTree ID="M">'
                                         '<KeepRunningUntilFailure><Leaf/></KeepRunningUntilFailure></BehaviorTree></root>')
    return tick_loop.TickLoop(tree, TickConfig(), realtime=True)


SLEEP_TREE = '<root BTCPP_format="4"><BehaviorTree ID="M"><Sequence><Sleep msec="30"/></Sequence></BehaviorTree></root>'


def test_efficient_pacing_never_yields_in_a_busy_loop() -> None:
    """With pacing 'efficient' each deadline is one timer; 'precise' yields to the loop before it."""
    efficient = _run_real_time(SLEEP_TREE, "efficient")
    assert efficient.status.name == "SUCCESS" and efficient.stats.count >= 3
    assert efficient.pacer.yields == 0
    precise = _run_real_time(SLEEP_TREE, "precise")
    assert precise.status.name == "SUCCESS" and precise.pacer.yields > 0


def test_real_time_ticks_keep_the_grid_and_skip_deadlines_a_slow_tick_passed() -> None:
    import time

    from bt_runtime import NodeStatus

    stamps: list[float] = []

    def slow(node):
        stamps.append(1.0)
        if len(stamps) == 5:
            time.sleep(0.035)  # runs past three deadlines
        return NodeStatus.FAILURE if len(stamps) >= 12 else NodeStatus.SUCCESS

    loop = _leaf_loop(slow)

    async def main():
        return await asyncio.wait_for(loop.run(), 2.0)

    assert clock.run(main, virtual=False) is NodeStatus.FAILURE
    assert loop.stats.count == 12 and loop.stats.overruns >= 3  # 3, or more if descheduled meanwhile
    assert all(late >= -1e-6 for late in loop.stats.lateness[:12])  # never early


def test_cancelling_the_tick_task_from_inside_a_tick_stops_the_ticking() -> None:
    """A node that restarts the tree cancels the running tick task from within a tick: no tick
    follows in that run, and the task ends cancelled."""
    from bt_runtime import NodeStatus

    ticks: list[int] = []
    holder: dict[str, asyncio.Task] = {}

    def cancel_self(node):
        ticks.append(1)
        if len(ticks) == 3:
            holder["task"].cancel()
        return NodeStatus.SUCCESS

    loop = _leaf_loop(cancel_self)

    async def main():
        holder["task"] = task = asyncio.get_running_loop().create_task(loop.run())
        with pytest.raises(asyncio.CancelledError):
            await task
        await asyncio.sleep(0.05)  # five more periods: nothing ticks
        return task.cancelled()

    assert clock.run(main, virtual=False)
    assert len(ticks) == 3 and loop.done.done()


def test_a_virtual_time_loop_takes_the_task_path_even_when_told_real_time() -> None:
    """Precise pacing yields until the deadline; virtual time only moves when the loop is idle,
    so on a virtual loop that would never end: the tick loop sleeps there instead."""
    from bt_runtime import BehaviorTreeFactory
    from bt_runtime.runtime import tick_loop

    tree = BehaviorTreeFactory().create_tree_from_text(SLEEP_TREE)
    loop = tick_loop.TickLoop(tree, TickConfig(pacing="precise"), realtime=True)

    async def main():
        return await asyncio.wait_for(loop.run(), 1.0)

    assert clock.run(main, virtual=True).name == "SUCCESS"
    assert loop.pacer is None and loop.stats.count >= 3
