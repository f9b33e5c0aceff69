"""The robot's own time over DDS: messages keep their header stamps, logs carry ROS time.

``sim-robot`` stamps each sensor message with the time it was taken (ROS time). A driver
fault that republishes an old message (``stall``, mode ``stale``) must reach the supervisor
as old data and be reported as stale, as it is in the in-process simulator; log lines of a
ROS 2 run give ``sim_time`` in ROS time, so they line up with the robot's logs and bags.
"""

import asyncio
import io
import itertools
import json
import os
import time

import pytest

pytest.importorskip("cyclonedds")

from bt_runtime.logging_setup import configure_logging  # noqa: E402
from bt_runtime.runtime.app import AutonomyRuntime  # noqa: E402
from bt_runtime.runtime.ros2 import Ros2Config, Ros2Driver, dds, idl  # noqa: E402
from bt_runtime.runtime.supervisor import Health  # noqa: E402
from tests.helpers import IDLE_TREE, SimRobotProcess, wait_until  # noqa: E402

_DOMAINS = itertools.count()


@pytest.fixture
def domain(monkeypatch) -> int:
    monkeypatch.setenv("CYCLONEDDS_URI", dds.loopback_config())
    return 100 + (os.getpid() + 43 * next(_DOMAINS) + 29) % 100


async def test_republished_old_data_is_stale_and_logs_carry_ros_time(domain):
    robot = SimRobotProcess(domain)
    try:
        await robot.ready()
        logs = io.StringIO()
        configure_logging(stream=logs, json=True, level="info")
        driver = Ros2Driver(Ros2Config(domain_id=domain))
        runtime = AutonomyRuntime(driver, realtime=True)
        runtime.load_tree(IDLE_TREE)
        loop = asyncio.get_running_loop()
        await runtime.start()
        try:
            await wait_until(lambda: runtime.supervisor.all_healthy(["imu", "odom", "lidar"]), 15,
                             "imu, odom and lidar healthy")
            assert abs(driver.robot_time(loop.time()) - time.time()) < 0.5  # ROS time = the system clock here
            fault = driver.node.publisher("sim/fault", idl.String)
            fault.write(idl.String(json.dumps({"kind": "stall", "component": "imu", "duration": 4.0,
                                               "mode": "stale"})))

            def imu_stale() -> bool:
                return any(e.state is Health.FAILED and "stale" in e.reason
                           for e in runtime.supervisor.events_of("imu"))

            await wait_until(imu_stale, 10, "the supervisor to report the IMU's stale data")
            assert runtime.supervisor.health("odom") is Health.OK  # the other streams stay fresh
        finally:
            await runtime.stop()
    finally:
        robot.stop()
    lines = [json.loads(line) for line in logs.getvalue().splitlines() if line.startswith("{")]
    started = next(line for line in lines if line["event"] == "runtime_started")
    stopped = next(line for line in lines if line["event"] == "runtime_stopped")
    assert abs(stopped["sim_time"] - time.time()) < 30  # ROS time (epoch seconds), not the loop's clock
    assert 0 < stopped["sim_time"] - started["sim_time"] < 60
