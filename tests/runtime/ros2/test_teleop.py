"""Teleop over real DDS: ``sim-robot`` in its own process, the runtime with ``Ros2Driver`` and
trees/autonomy.xml in this one, and a joystick written here as a plain DDS publisher on
``cmd_vel_teleop`` (geometry_msgs/Twist) with an e-stop on ``e_stop`` (std_msgs/Bool): the
default gate inputs and locks, plus a TwistStamped input above teleop.

One robot process for the story: navigation drives to a goal; teleop takes over (the robot
turns in place as the joystick says); the ``e_stop`` lock stops it while the joystick keeps
pushing; released, teleop drives again; silent, it hands the robot back; the runtime's own
emergency stop beats it too. Judged from what reached ``cmd_vel`` and from odometry.
"""

import asyncio
import contextlib

import pytest

pytest.importorskip("cyclonedds")

from bt_runtime.runtime.app import AutonomyRuntime  # noqa: E402
from bt_runtime.runtime.config import GateConfig, RuntimeConfig  # noqa: E402
from bt_runtime.runtime.messages import Pose2D  # noqa: E402
from bt_runtime.runtime.ros2 import Ros2Config, Ros2Driver, dds, idl  # noqa: E402
from tests.helpers import SimRobotProcess, dds_domain, wait_until  # noqa: E402
from tests.paths import ROOT  # noqa: E402

TURN = 0.6  # rad/s: the joystick turns in place, which navigation never asks for on a straight run


@pytest.fixture(autouse=True)
def loopback(monkeypatch):
    monkeypatch.setenv("CYCLONEDDS_URI", dds.loopback_config())


def twist(linear: float, angular: float) -> idl.Twist:
    return idl.Twist(linear=idl.Vector3(linear, 0.0, 0.0), angular=idl.Vector3(0.0, 0.0, angular))


async def test_teleop_outranks_navigation_and_loses_to_the_e_stop():
    import nodes

    domain = dds_domain()
    robot = SimRobotProcess(domain, "--robot", "burger", duration=90)
    node = None
    joystick_task = None
    try:
        await robot.ready()
        driver = Ros2Driver(Ros2Config(domain_id=domain))
        inputs = {"teleop": {"topic": "cmd_vel_teleop", "priority": 100, "timeout": 0.5},  # the default
                  "pad": {"topic": "cmd_vel_pad", "priority": 150, "timeout": 0.5, "stamped": True}}
        config = RuntimeConfig(gate=GateConfig(inputs=inputs))
        runtime = AutonomyRuntime(driver, config, realtime=True, register=[nodes.register_all])
        runtime.load_tree(ROOT / "trees" / "autonomy.xml")
        await runtime.start()
        gate = runtime.gate
        try:
            node = dds.DdsNode(domain)
            wheels: list[tuple[float, float]] = []  # what reached the robot's cmd_vel
            node.subscription("cmd_vel", idl.Twist, dds.QosProfile(reliable=False, depth=50),
                              lambda samples, _now: wheels.extend((m.linear.x, m.angular.z) for m in samples))
            joystick = node.publisher("cmd_vel_teleop", idl.Twist)
            pad = node.publisher("cmd_vel_pad", idl.TwistStamped)
            e_stop = node.publisher("e_stop", idl.Bool)
            names = [c.name for c in driver.components()]
            await wait_until(lambda: runtime.supervisor.all_healthy(names), 15, "components healthy")
            await wait_until(lambda: joystick.get_matched_subscriptions() and e_stop.get_matched_subscriptions(),
                             10, "the runtime to read cmd_vel_teleop and e_stop")
            assert driver.lock_publishers() == {"e_stop": 1}  # reliable reader, reliable writer

            def odom() -> tuple[float, float]:
                m = driver.latest.get("odom")
                return (m.twist.linear, m.twist.angular) if m is not None else (0.0, 0.0)

            # 1. navigation drives towards a goal
            runtime.send_goal(Pose2D(3.5, -2.5, 0.0))
            await wait_until(lambda: gate.source == "nav" and odom()[0] > 0.1, 20, "navigation to drive")

            # 2. the joystick (20 Hz) outranks it: the robot turns in place
            async def push():
                while True:
                    joystick.write(twist(0.0, TURN))
                    await asyncio.sleep(0.05)

            joystick_task = asyncio.ensure_future(push())
            await wait_until(lambda: gate.source == "teleop" and wheels and wheels[-1] == (0.0, TURN), 5,
                             "teleop's command on cmd_vel")
            await wait_until(lambda: abs(odom()[0]) < 0.03 and abs(odom()[1] - TURN) < 0.15, 5,
                             "the robot to turn in place")
            assert gate.switches[-1].reason == "teleop input (priority 100)"

            # 3. the e_stop lock stops it while the joystick keeps pushing
            e_stop.write(idl.Bool(True))
            await wait_until(lambda: gate.source == "lock" and wheels[-1] == (0.0, 0.0), 3, "the e_stop lock")
            await wait_until(lambda: abs(odom()[0]) < 0.02 and abs(odom()[1]) < 0.05, 5, "the robot to stop")
            await asyncio.sleep(0.5)
            assert wheels[-1] == (0.0, 0.0) and gate.source != "teleop"  # "lock" (or "idle" if starved)
            e_stop.write(idl.Bool(False))
            await wait_until(lambda: gate.source == "teleop" and wheels[-1] == (0.0, TURN), 3, "teleop again")

            # 3b. a TwistStamped input of higher priority outranks teleop while it speaks
            async def push_pad():
                while True:
                    pad.write(idl.TwistStamped(header=idl.Header(stamp=idl.Time.now(), frame_id="base_link"),
                                               twist=twist(0.0, -TURN)))
                    await asyncio.sleep(0.05)

            pad_task = asyncio.ensure_future(push_pad())
            try:
                await wait_until(lambda: gate.source == "pad" and wheels[-1] == (0.0, -TURN), 5, "the pad's command")
            finally:
                pad_task.cancel()
            await wait_until(lambda: gate.source == "teleop", 3, "teleop after the pad's timeout")

            # 4. the joystick falls silent: after its 0.5 s timeout it no longer drives
            joystick_task.cancel()
            silent_from = len(gate.switches)
            await wait_until(lambda: gate.source != "teleop", 3, "teleop to time out")
            assert gate.switches[silent_from].previous == "teleop"

            # 5. the runtime's own emergency stop (the supervisor's, the tree's) beats it too
            joystick_task = asyncio.ensure_future(push())
            await wait_until(lambda: gate.source == "teleop" and wheels[-1] == (0.0, TURN), 5, "teleop again")
            gate.emergency_stop("test: e-stop over teleop")
            await wait_until(lambda: wheels[-1] == (0.0, 0.0), 3, "zero on cmd_vel")
            await asyncio.sleep(0.5)
            assert gate.source == "estop" and wheels[-1] == (0.0, 0.0)
            assert all(abs(v) <= 0.22 + 1e-9 and abs(w) <= 2.84 + 1e-9 for v, w in wheels)
        finally:
            if joystick_task is not None:
                joystick_task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await joystick_task
            await runtime.stop()
    finally:
        if node is not None:
            node.close()
        robot.stop()
