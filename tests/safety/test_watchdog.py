"""A node that blocks the event loop for 2 s in real time: the off-loop watchdog zeroes the
simulated base within the dead-man timeout + 20 ms, and the loop's return does not undo it."""

from __future__ import annotations

import asyncio
import time

import pytest

from bt_runtime.runtime.app import AutonomyRuntime
from bt_runtime.runtime.config import GateConfig, RuntimeConfig
from bt_runtime.runtime.watchdog import LoopWatchdog
from sim.driver import SimDriver
from tests.helpers import tree_xml
from tests.safety.support import BaseRecorder, StallLoop, register_fault_nodes

STALL_TREE = tree_xml('<StallLoop after="40" seconds="2.0"/>')


async def test_loop_stall_zeroes_the_base_within_the_deadman_bound():
    driver = SimDriver("apartment", "burger", seed=1)
    runtime = AutonomyRuntime(driver, register=[register_fault_nodes])  # real-time loop
    runtime.load_tree(STALL_TREE)
    base = BaseRecorder(driver.sim)
    deadman = runtime.config.gate.deadman_timeout
    StallLoop.stalled_at = None
    await runtime.start()
    assert runtime.watchdog is not None and runtime.watchdog.running
    try:
        while StallLoop.stalled_at is None or time.monotonic() < StallLoop.stalled_at + 2.3:
            await asyncio.sleep(0.05)
    finally:
        await runtime.stop()
    stalled = StallLoop.stalled_at
    moving = [r for r in base.received if r.wall < stalled and not r.is_zero]
    assert moving, "the robot was driving before the stall"
    trip = runtime.watchdog.trips[0]
    assert trip.refreshed <= stalled  # the last refresh was before the stalling tick
    zeros = [r for r in base.after(trip.refreshed) if r.is_zero]
    assert zeros, "no zero reached the base during the stall"
    latency = zeros[0].wall - trip.refreshed
    print(f"stall-to-zero latency {latency * 1e3:.1f} ms (dead-man {deadman * 1e3:.0f} ms)")
    assert latency <= deadman + 0.020
    assert zeros[0].wall < stalled + 2.0  # during the stall, not after it
    assert base.received[-1].is_zero  # shutdown ends at zero
    base.assert_safe(runtime.context.robot.max_linear, runtime.context.robot.max_angular)


def test_watchdog_fires_once_per_stall_and_only_when_moving():
    zeros = []
    dog = LoopWatchdog(lambda: zeros.append(time.monotonic()), 0.05)
    dog.start()
    try:
        time.sleep(0.12)
        assert zeros == []  # stopped robot: nothing to zero
        dog.refresh()
        with dog.lock:
            dog.note_sent(True)
        time.sleep(0.15)
        assert len(zeros) == 1 and zeros[0] - dog.trips[0].refreshed <= 0.05 + 0.02
        time.sleep(0.1)
        assert len(zeros) == 1  # once per stall
    finally:
        dog.stop()
    assert not dog.running


@pytest.mark.virtual_time
async def test_virtual_time_runs_have_no_watchdog_unless_asked(make_runtime):
    assert make_runtime().watchdog is None  # a real-time stall stops virtual time too
    assert make_runtime(config=RuntimeConfig(gate=GateConfig(watchdog=True))).watchdog is not None
    baseline = RuntimeConfig(gate=GateConfig(passthrough=True, watchdog=True))
    assert make_runtime(config=baseline).watchdog is None  # the baseline has no dead-man at all
