"""Every command is checked at the gate, whatever its source: non-finite values never reach
the base (zero instead; repeated, the sender fails), and speed and acceleration stay within
the robot's limits and the speed limit. Judged from what the simulated base received."""

from __future__ import annotations

import asyncio
import math

import pytest

from bt_runtime.runtime.messages import Pose2D, Twist
from tests.helpers import tree_xml
from tests.safety.support import BaseRecorder, register_fault_nodes

pytestmark = pytest.mark.virtual_time


def check_base(rt, base: BaseRecorder) -> None:
    robot = rt.context.robot
    base.assert_safe(robot.max_linear, robot.max_angular)
    base.assert_accel_limited(robot.max_linear_accel, robot.max_angular_accel)


@pytest.mark.parametrize("value", ["0.0/0.0", "1.0/0.0", "-1.0/0.0"])
async def test_nonfinite_tree_command_is_refused_and_the_sender_fails(make_runtime, value):
    xml = tree_xml(f'<Sequence><Script code="s := {value}"/><Drive linear="{{s}}"/></Sequence>')
    rt = make_runtime(xml, register=[register_fault_nodes])
    base = BaseRecorder(rt.driver.sim)
    await rt.start()
    await asyncio.sleep(1.0)
    await rt.stop()
    check_base(rt, base)
    assert all(r.is_zero for r in base.received)
    refused = rt.gate.refused["tree"]
    assert refused.total >= 3 and not math.isfinite(refused.last[0])
    assert rt.tick_loop.stats.errors >= 1  # the node that kept sending it failed
    assert "non-finite velocity command" in str(rt.tick_loop.last_error)


async def test_absurd_navigation_commands_are_clamped(make_runtime):
    rt = make_runtime()
    base = BaseRecorder(rt.driver.sim)
    await rt.start()
    for _ in range(100):
        rt.driver.sim.bus.publish("nav_cmd_vel", Twist(19.0, -40.0))
        await asyncio.sleep(0.02)
    await rt.stop()
    check_base(rt, base)
    robot = rt.context.robot
    assert max(r.linear for r in base.received) == pytest.approx(robot.max_linear)
    assert min(r.angular for r in base.received) >= -robot.max_angular - 1e-9


async def test_repeated_nonfinite_navigation_commands_cancel_navigation(make_runtime):
    rt = make_runtime()
    base = BaseRecorder(rt.driver.sim)
    await rt.start()
    await asyncio.sleep(0.5)
    spawn = rt.driver.sim.spawn
    handle = rt.driver.navigation.navigate_to_pose(Pose2D(spawn.x + 1.0, spawn.y, spawn.yaw))
    await asyncio.sleep(1.0)
    for _ in range(3):
        rt.driver.sim.bus.publish("nav_cmd_vel", Twist(math.nan, 0.0))
    await asyncio.sleep(0.5)
    assert handle.done() and not handle.result().succeeded  # the node waiting for it would fail
    assert rt.gate.refused["nav"].total == 3
    await rt.stop()
    check_base(rt, base)


async def test_estop_release_ramps_up_instead_of_jumping(make_runtime):
    rt = make_runtime(tree_xml('<Drive linear="0.2"/>'), register=[register_fault_nodes])
    base = BaseRecorder(rt.driver.sim)
    await rt.start()
    await asyncio.sleep(0.5)
    rt.gate.emergency_stop("test")
    await asyncio.sleep(0.3)
    rt.gate.release("test")
    await asyncio.sleep(0.5)
    await rt.stop()
    check_base(rt, base)
    assert max(r.linear for r in base.received) == pytest.approx(0.2)


async def test_speed_limit_applies_to_every_source_and_refuses_nan(make_runtime):
    rt = make_runtime(tree_xml('<Drive linear="0.2" angular="1.0"/>'), register=[register_fault_nodes])
    base = BaseRecorder(rt.driver.sim)
    await rt.start()
    rt.gate.set_speed_limit(0.05, 0.3, reason="test")
    await asyncio.sleep(0.5)
    with pytest.raises(ValueError, match="speed limit"):
        rt.gate.set_speed_limit(math.nan, None)
    await rt.stop()
    check_base(rt, base)
    assert all(abs(r.linear) <= 0.05 + 1e-12 and abs(r.angular) <= 0.3 + 1e-12 for r in base.received)
