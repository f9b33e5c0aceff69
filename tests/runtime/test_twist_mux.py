"""The gate's twist_mux-style inputs and locks on the virtual-time loop: who wins (priority,
freshness, ties), what locks mask (lower priorities only; a silent lock with a timeout locks),
that the emergency stop and the dead-man stand above teleop, and that every input is still
refused when non-finite and clamped to the robot's limits."""

from __future__ import annotations

import asyncio
import contextlib
import math

from bt_runtime.runtime.config import GateConfig, RuntimeConfig
from bt_runtime.runtime.messages import Twist


def config(**gate) -> RuntimeConfig:
    return RuntimeConfig(gate=GateConfig(**gate))


@contextlib.asynccontextmanager
async def publishing(publish, period=0.05):
    """Call ``publish()`` every ``period`` seconds while inside the block (a 20 Hz joystick)."""

    async def loop():
        while True:
            publish()
            await asyncio.sleep(period)

    task = asyncio.get_running_loop().create_task(loop())
    try:
        yield
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task


async def test_teleop_outranks_tree_and_navigation_then_hands_back(make_runtime):
    rt = make_runtime()
    await rt.start()
    gate, driver = rt.gate, rt.driver
    async with publishing(lambda: driver.sim.bus.publish("nav_cmd_vel", Twist(0.1, 0.0))):
        await asyncio.sleep(0.3)
        assert gate.source == "nav"
        async with publishing(lambda: driver.publish_command_input("teleop", -0.05, 0.3)):
            await asyncio.sleep(0.3)
            assert gate.source == "teleop" and gate.last_output == Twist(-0.05, 0.3)
            for _ in range(20):  # the tree's own command loses to teleop too
                gate.set_tree_command(0.2, 0.0)
                await asyncio.sleep(0.01)
            assert gate.source == "teleop" and gate.last_output == Twist(-0.05, 0.3)
            gate.clear_tree_command()
        t_last = rt.clock()
        await asyncio.sleep(0.7)  # teleop's timeout (0.5 s) passes: navigation drives again
        assert gate.source == "nav"
    back = [s for s in gate.switches if s.previous == "teleop"][0]
    assert back.source == "nav" and t_last + 0.5 - 0.06 <= back.t <= t_last + 0.5 + 0.01
    to_teleop = [s for s in gate.switches if s.source == "teleop"][0]
    assert to_teleop.previous == "nav" and to_teleop.reason == "teleop input (priority 100)"
    await rt.stop()


async def test_emergency_stop_and_e_stop_lock_beat_teleop(make_runtime):
    rt = make_runtime()
    await rt.start()
    gate, driver = rt.gate, rt.driver
    async with publishing(lambda: driver.publish_command_input("teleop", 0.1, 0.0)):
        await asyncio.sleep(0.3)
        assert gate.source == "teleop" and gate.last_output == Twist(0.1, 0.0)
        gate.emergency_stop("supervisor: lidar DEAD")
        assert gate.last_output.is_zero
        await asyncio.sleep(0.2)
        assert gate.source == "estop" and gate.last_output.is_zero
        gate.release("supervisor: lidar DEAD")
        await asyncio.sleep(0.3)
        assert gate.source == "teleop" and not gate.last_output.is_zero
        driver.publish_lock("e_stop", True)  # the default lock, priority 255
        assert gate.last_output.is_zero  # at once, not at the next tick
        await asyncio.sleep(0.3)
        assert gate.source == "lock" and gate.last_output.is_zero
        switch = gate.switches[-1]
        assert switch.source == "lock" and "e_stop" in switch.reason and "teleop" in switch.reason
        driver.publish_lock("e_stop", False)
        await asyncio.sleep(0.3)
        assert gate.source == "teleop" and gate.last_output == Twist(0.1, 0.0)
    await rt.stop()


async def test_teleop_cannot_drive_a_silent_tree(make_runtime):
    """DESIGN: nothing reaches the wheels when the tree stops ticking; teleop included."""
    rt = make_runtime()
    await rt.start(tick=False)
    gate, driver = rt.gate, rt.driver
    async with publishing(lambda: driver.publish_command_input("teleop", 0.1, 0.0)):
        await asyncio.sleep(0.5)
        assert gate.source == "deadman" and gate.last_output.is_zero
    await rt.stop()


async def test_locks_mask_lower_priorities_only_and_silent_locks_lock(make_runtime):
    inputs = {"joystick": {"topic": "joy_vel", "priority": 100, "timeout": 0.5},
              "keyboard": {"topic": "key_vel", "priority": 90, "timeout": 0.5}}
    locks = {"pause": {"topic": "pause", "priority": 100, "timeout": 0.0},
             "heartbeat": {"topic": "hb", "priority": 50, "timeout": 0.3}}
    rt = make_runtime(config=config(inputs=inputs, locks=locks))
    await rt.start()
    gate, driver = rt.gate, rt.driver
    async with publishing(lambda: driver.sim.bus.publish("nav_cmd_vel", Twist(0.1, 0.0))):
        await asyncio.sleep(0.3)
        # the heartbeat lock has a timeout and has not spoken yet: locked, masks navigation (10 < 50)
        assert gate.source == "lock" and "heartbeat (no message yet" in gate.switches[-1].reason
        async with publishing(lambda: driver.publish_lock("heartbeat", False), period=0.1):
            await asyncio.sleep(0.3)
            assert gate.source == "nav"
            async with publishing(lambda: driver.publish_command_input("keyboard", 0.05, 0.0)):
                await asyncio.sleep(0.2)
                assert gate.source == "keyboard"
                driver.publish_lock("pause", True)  # 100 masks the keyboard (90), not the joystick (100)
                await asyncio.sleep(0.1)
                assert gate.source == "lock"
                async with publishing(lambda: driver.publish_command_input("joystick", 0.07, 0.0)):
                    await asyncio.sleep(0.3)
                    assert gate.source == "joystick" and gate.last_output == Twist(0.07, 0.0)
                driver.publish_lock("pause", False)
                await asyncio.sleep(0.6)  # the joystick's last command goes stale
                assert gate.source == "keyboard"
            await asyncio.sleep(0.6)
            assert gate.source == "nav"
        t_silent = rt.clock()
        await asyncio.sleep(0.6)  # the heartbeat lock falls silent: locked again 0.3 s later
        assert gate.source == "lock"
    relocked = [s for s in gate.switches if s.source == "lock"][-1]
    assert "heartbeat (silent for" in relocked.reason
    assert t_silent - 0.1 + 0.3 <= relocked.t <= t_silent + 0.3 + 0.01  # the gate woke up for it
    await rt.stop()


async def test_ties_timeout_zero_and_the_tree_entry(make_runtime):
    inputs = {"b_pad": {"topic": "b", "priority": 60, "timeout": 0.5},
              "a_pad": {"topic": "a", "priority": 60, "timeout": 0.0},
              "tree": {"priority": 60, "timeout": 0.2}}
    rt = make_runtime(config=config(inputs=inputs))
    assert rt.config.gate.priorities == {"tree": 60, "nav": 10} and set(rt.gate.mux.inputs) == {"a_pad", "b_pad"}
    await rt.start()
    gate, driver = rt.gate, rt.driver
    async with publishing(lambda: driver.publish_command_input("b_pad", 0.05, 0.0)):
        await asyncio.sleep(0.2)
        assert gate.source == "b_pad"
        driver.publish_command_input("a_pad", 0.03, 0.0)  # once: timeout 0 never goes stale
        await asyncio.sleep(0.1)
        assert gate.source == "a_pad"  # equal priorities: the first name wins, as in twist_mux
        for _ in range(10):
            gate.set_tree_command(0.02, 0.0)
            await asyncio.sleep(0.01)
        assert gate.source == "tree"  # ties: the tree ranks first
        gate.clear_tree_command()
    await asyncio.sleep(5.0)
    assert gate.source == "a_pad" and gate.last_output == Twist(0.03, 0.0)
    await rt.stop()


async def test_teleop_is_refused_when_non_finite_and_clamped(make_runtime):
    rt = make_runtime()
    await rt.start()
    gate, driver = rt.gate, rt.driver
    limit = rt.context.robot.max_linear
    async with publishing(lambda: driver.sim.bus.publish("nav_cmd_vel", Twist(0.1, 0.0))):
        async with publishing(lambda: driver.publish_command_input("teleop", 5.0, 0.0)):
            await asyncio.sleep(0.5)
            assert gate.source == "teleop" and math.isclose(gate.last_output.linear, limit, rel_tol=1e-9)
        async with publishing(lambda: driver.publish_command_input("teleop", math.nan, 0.0)):
            await asyncio.sleep(0.3)
            # refused: teleop holds zero while fresh, navigation does not take over
            assert gate.source == "teleop" and gate.last_output.is_zero
            assert gate.refused["teleop"].total >= 5
        await asyncio.sleep(0.7)
        assert gate.source == "nav"
    await rt.stop()


async def test_a_dead_critical_component_stops_teleop(make_runtime):
    """The supervisor's DEAD e-stop (odometry failed two restarts) beats a joystick that keeps pushing."""
    rt = make_runtime()
    await rt.start()
    gate, driver, sim = rt.gate, rt.driver, rt.driver.sim
    sim.faults.set_restart_policy("odom", delay=0.2, fail_next=5)
    async with publishing(lambda: driver.publish_command_input("teleop", 0.1, 0.0)):
        await asyncio.sleep(0.5)
        assert gate.source == "teleop" and gate.last_output == Twist(0.1, 0.0)
        sim.crash("odom")
        await asyncio.sleep(1.2)
        assert gate.source == "teleop"  # failed, not yet dead: the operator keeps control
        assert await rt.supervisor.restart("odom") is False
        assert await rt.supervisor.restart("odom") is False
        assert "odom dead" in gate.estop_reasons and gate.last_output.is_zero
        await asyncio.sleep(0.5)
        assert gate.source == "estop" and gate.last_output.is_zero
    await rt.stop()
