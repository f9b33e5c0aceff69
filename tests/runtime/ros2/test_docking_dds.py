"""Docking on a ROS 2 robot over DDS: ``sim-robot`` serves opennav_docking's ``dock_robot`` and
``undock_robot`` actions; the runtime's ``Ros2Driver`` calls them through its navigation client.
The robot starts 1 m in front of the apartment's dock with a low battery (a ``set_battery``
fault on ``sim/fault``); docking succeeds, the battery messages that came over DDS report
CHARGING and a rising charge, undocking backs out to the staging pose (the simulator's ground
truth, read by the test only). One sim-robot process for every check."""

import json
import math

import pytest

pytest.importorskip("cyclonedds")

from bt_runtime.runtime.app import AutonomyRuntime  # noqa: E402
from bt_runtime.runtime.messages import POWER_SUPPLY_CHARGING, ActionStatus  # noqa: E402
from bt_runtime.runtime.ros2 import Ros2Config, Ros2Driver, dds, idl  # noqa: E402
from tests.helpers import IDLE_TREE, SimRobotProcess, dds_domain  # noqa: E402
from tests.helpers import wait_until as wait_for  # noqa: E402

STAGING = (-3.9, -1.0)  # the apartment's dock (-4.6, -1.0) facing west, staging 0.7 m behind it


@pytest.fixture(autouse=True)
def loopback(monkeypatch):
    monkeypatch.setenv("CYCLONEDDS_URI", dds.loopback_config())


async def test_dock_robot_and_undock_robot_over_dds():
    domain = dds_domain()
    robot = SimRobotProcess(domain, "--robot", "burger", "--spawn=-3.6,-1.0,3.1416", "--nav-autostart",
                            duration=90.0)
    try:
        await robot.ready()
        driver = Ros2Driver(Ros2Config(domain_id=domain))
        runtime = AutonomyRuntime(driver, realtime=True)
        runtime.load_tree(IDLE_TREE)  # ticks, so the gate passes the docking server's commands
        truth: list[tuple[float, float]] = []
        await runtime.start()
        try:
            node = driver.node
            node.subscription("sim/ground_truth", idl.PoseStamped, dds.DEFAULT,
                              lambda s, now: truth.extend((m.pose.position.x, m.pose.position.y) for m in s))
            faults = node.publisher("sim/fault", idl.String, dds.DEFAULT)
            await wait_for(lambda: truth and runtime.backup.latest("battery") is not None, 30, "robot data")
            faults.write(idl.String(json.dumps({"kind": "set_battery", "soc": 30.0})))
            await wait_for(lambda: runtime.backup.latest("battery").percentage < 40, 10, "the battery at 30 %")
            nav = driver.navigation
            states = []
            docked = await nav.dock_robot(dock_id="home_dock", feedback=lambda fb: states.append(fb.state))
            at_dock = truth[-1]
            first = runtime.backup.latest("battery")
            await wait_for(lambda: runtime.backup.latest("battery").percentage > first.percentage + 0.3, 40,
                           "the charge to rise")
            charging = runtime.backup.latest("battery")
            undocked = await nav.undock_robot()
            at_staging = truth[-1]
            unknown = await nav.dock_robot(dock_id="kitchen_dock")
        finally:
            await runtime.stop()
    finally:
        robot.stop()
    assert docked.status is ActionStatus.SUCCEEDED, docked
    assert 3 in states and 4 in states  # CONTROLLING, WAIT_FOR_CHARGE (feedback over DDS)
    assert math.hypot(at_dock[0] + 4.6, at_dock[1] + 1.0) < 0.08  # ground truth: on the dock
    assert first.power_supply_status == POWER_SUPPLY_CHARGING and charging.percentage > first.percentage
    assert undocked.status is ActionStatus.SUCCEEDED, undocked
    assert math.hypot(at_staging[0] - STAGING[0], at_staging[1] - STAGING[1]) < 0.15
    assert (unknown.status, int(unknown.error_code)) == (ActionStatus.ABORTED, 901)
    assert "home_dock" in unknown.error_msg
