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


def test_efficient_pacing_never_yields_in_a_busy_loop(monkeypatch) -> None:
    """With pacing 'efficient' the tick task sleeps straight to each deadline."""
    calls: list[bool] = []
    real = clock.sleep_until

    async def spy(deadline, *, precise=False, spin_window=0.0):
        calls.append(precise)
        await real(deadline, precise=precise, spin_window=spin_window)

    from bt_runtime import BehaviorTreeFactory
    from bt_runtime.runtime import tick_loop

    monkeypatch.setattr(tick_loop, "sleep_until", spy)
    tree = BehaviorTreeFactory().create_tree_from_text(
        '<root BTCPP_format="4"><BehaviorTree ID="M"><Sequence><Sleep msec="30"/></Sequence></BehaviorTree></root>')

    async def main(pacing: str):
        loop = tick_loop.TickLoop(tree, TickConfig(pacing=pacing), realtime=True)
        await asyncio.wait_for(loop.run(), 1.0)

    clock.run(main("efficient"), virtual=False)
    assert calls and not any(calls)
    calls.clear()
    clock.run(main("precise"), virtual=False)
    assert calls and all(calls)
