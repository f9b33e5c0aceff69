"""The decision gate: priorities, speed limit, dead-man, stale sources, logged switches."""

from __future__ import annotations

import asyncio
import contextlib

from bt_runtime.runtime.config import GateConfig, RuntimeConfig
from bt_runtime.runtime.messages import Twist


async def hold(gate, linear, angular, seconds=0.3):
    """Keep commanding (a tree command goes stale after 0.2 s) while the gate ramps up to it."""
    for _ in range(round(seconds / 0.01)):
        gate.set_tree_command(linear, angular)
        await asyncio.sleep(0.01)


def sent_commands(rt):
    out = []
    rt.driver.sim.subscribe("cmd_vel_out", lambda t: out.append((rt.clock(), t)))
    return out


async def test_priority_estop_over_tree_over_nav(make_runtime):
    rt = make_runtime()
    await rt.start()
    gate, bus = rt.gate, rt.driver.sim.bus
    await asyncio.sleep(0.1)

    async def nav_publisher():
        while True:
            bus.publish("nav_cmd_vel", Twist(0.1, 0.0))
            await asyncio.sleep(0.05)

    nav = asyncio.get_running_loop().create_task(nav_publisher())
    await asyncio.sleep(0.2)  # commands ramp up at the robot's acceleration limit (1 m/s^2)
    assert gate.source == "nav" and gate.last_output == Twist(0.1, 0.0)
    await hold(gate, -0.05, 0.2, 0.15)
    assert gate.source == "tree" and gate.last_output == Twist(-0.05, 0.2)
    gate.emergency_stop("test")
    assert gate.last_output.is_zero  # an explicit zero goes out at once
    await asyncio.sleep(0.05)
    assert gate.source == "estop" and gate.last_output.is_zero
    gate.release("test")
    gate.set_tree_command(-0.05, 0.2)
    await asyncio.sleep(0.02)
    assert gate.source == "tree"
    gate.clear_tree_command()
    await asyncio.sleep(0.02)
    assert gate.source == "nav"
    reasons = [(s.previous, s.source) for s in gate.switches]
    assert ("nav", "tree") in reasons and ("tree", "estop") in reasons and ("tree", "nav") in reasons
    assert all(s.reason for s in gate.switches)
    nav.cancel()
    await rt.stop()


async def test_speed_limit_scales_commands_keeping_curvature(make_runtime):
    rt = make_runtime()
    await rt.start()
    gate = rt.gate
    gate.set_speed_limit(0.1, 0.5, reason="lidar degraded")
    await hold(gate, 0.2, 0.4)  # commands ramp up at the robot's acceleration limits
    out = gate.last_output
    assert abs(out.linear - 0.1) < 1e-12 and abs(out.angular - 0.2) < 1e-12
    await hold(gate, 0.0, 2.0)
    assert gate.last_output == Twist(0.0, 0.5)
    gate.set_speed_limit(None)
    await hold(gate, 0.2, 0.4)
    assert gate.last_output == Twist(0.2, 0.4)
    await rt.stop()


async def test_deadman_when_the_tick_task_dies(make_runtime):
    rt = make_runtime()
    commands = sent_commands(rt)
    await rt.start()
    gate = rt.gate

    async def keep_driving():
        while True:
            gate.set_tree_command(0.15, 0.0)
            await asyncio.sleep(0.02)

    driver_task = asyncio.get_running_loop().create_task(keep_driving())
    await asyncio.sleep(0.5)
    assert gate.source == "tree"
    rt.tick_task.cancel()  # the tree dies; something else still asks to drive
    with contextlib.suppress(asyncio.CancelledError):
        await rt.tick_task
    killed_at = rt.clock()
    await asyncio.sleep(0.3)
    zero_after = [t for t, c in commands if t >= killed_at and c.is_zero]
    moving_after = [t for t, c in commands if t > killed_at + gate.config.deadman_timeout + 0.01 and not c.is_zero]
    assert zero_after and zero_after[0] - killed_at <= gate.config.deadman_timeout + 0.01 + 1e-9
    assert not moving_after
    assert any(s.source == "deadman" for s in gate.switches)
    driver_task.cancel()
    await rt.stop()


async def test_stale_navigation_source_gives_zero(make_runtime):
    rt = make_runtime()
    await rt.start()
    gate, bus = rt.gate, rt.driver.sim.bus
    await asyncio.sleep(0.1)
    bus.publish("nav_cmd_vel", Twist(0.2, 0.0))  # one command, then a stack that went quiet
    await asyncio.sleep(0.02)
    assert gate.source == "nav"
    await asyncio.sleep(gate.config.nav_stale_timeout + 0.02)
    assert gate.source == "idle" and gate.last_output.is_zero
    await rt.stop()


async def test_blocked_navigation_is_held_off(make_runtime):
    rt = make_runtime()
    await rt.start()
    gate, bus = rt.gate, rt.driver.sim.bus
    gate.allow_navigation(False, "navigation cancelled")
    for _ in range(10):  # a stack that ignores the cancel keeps publishing
        bus.publish("nav_cmd_vel", Twist(0.2, 0.0))
        await asyncio.sleep(0.03)
        assert gate.last_output.is_zero
    gate.allow_navigation(True)
    for _ in range(10):
        bus.publish("nav_cmd_vel", Twist(0.2, 0.0))
        await asyncio.sleep(0.03)  # ramping up at 1 m/s^2
    assert gate.last_output == Twist(0.2, 0.0)
    await rt.stop()


async def test_passthrough_baseline_forwards_navigation_like_nav2(make_runtime):
    rt = make_runtime(config=RuntimeConfig(gate=GateConfig(passthrough=True)))
    commands = sent_commands(rt)
    await rt.start()
    rt.tick_task.cancel()  # no tree heartbeat needed in the baseline
    await asyncio.sleep(0.3)
    rt.driver.sim.bus.publish("nav_cmd_vel", Twist(0.1, 0.1))
    assert commands[-1][1] == Twist(0.1, 0.1)
    await rt.stop()


async def test_robot_actually_stops_after_estop(make_runtime):
    rt = make_runtime()
    await rt.start()
    gate, sim = rt.gate, rt.driver.sim
    for _ in range(100):
        gate.set_tree_command(0.2, 0.0)
        await asyncio.sleep(0.01)
    assert sim.twist.linear > 0.15
    gate.emergency_stop("obstacle")
    await asyncio.sleep(0.5)
    assert abs(sim.twist.linear) < 1e-3
    await rt.stop()
