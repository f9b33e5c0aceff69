"""The robot's own time over DDS: messages keep their header stamps, logs carry ROS time.

``sim-robot`` stamps each sensor message with the time it was taken (ROS time). A driver
fault that republishes an old message (``stall``, mode ``stale``) must reach the supervisor
as old data and be reported as stale, as it is in the in-process simulator; log lines of a
ROS 2 run give ``sim_time`` in ROS time, so they line up with the robot's logs and bags, and so
does a recording of the run (``--record``): its log times and header stamps are ROS time.
"""

import asyncio
import importlib.util
import io
import json
import time

import pytest

pytest.importorskip("cyclonedds")

from bt_runtime.logging_setup import configure_logging  # noqa: E402
from bt_runtime.runtime.app import AutonomyRuntime  # noqa: E402
from bt_runtime.runtime.ros2 import Ros2Config, Ros2Driver, dds, idl  # noqa: E402
from bt_runtime.runtime.supervisor import Health  # noqa: E402
from tests.helpers import IDLE_TREE, SimRobotProcess, dds_domain, wait_until  # noqa: E402


@pytest.fixture
def domain(monkeypatch) -> int:
    monkeypatch.setenv("CYCLONEDDS_URI", dds.loopback_config())
    return dds_domain()


async def test_republished_old_data_is_stale_and_logs_carry_ros_time(domain, tmp_path):
    robot = SimRobotProcess(domain)
    try:
        await robot.ready()
        logs = io.StringIO()
        configure_logging(stream=logs, json=True, level="info")
        driver = Ros2Driver(Ros2Config(domain_id=domain))
        runtime = AutonomyRuntime(driver, realtime=True)
        runtime.load_tree(IDLE_TREE)
        loop = asyncio.get_running_loop()
        recording = None
        if importlib.util.find_spec("foxglove") is not None:  # the [record] extra: record this run too
            from bt_runtime.runtime.recording.cli import Recording

            recording = Recording(bag=tmp_path / "bag").start(runtime)
        wall_start = time.time()
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
            if recording is not None:
                recording.stop()
    finally:
        robot.stop()
    if recording is not None:
        _assert_bag_in_ros_time(tmp_path / "bag", wall_start, time.time())
    lines = [json.loads(line) for line in logs.getvalue().splitlines() if line.startswith("{")]
    started = next(line for line in lines if line["event"] == "runtime_started")
    stopped = next(line for line in lines if line["event"] == "runtime_stopped")
    assert abs(stopped["sim_time"] - time.time()) < 30  # ROS time (epoch seconds), not the loop's clock
    assert 0 < stopped["sim_time"] - started["sim_time"] < 60


def _assert_bag_in_ros_time(bag, wall_start: float, wall_end: float) -> None:
    """Log times and the sensors' header stamps are ROS time (here the system clock), as the
    robot's own bags are: they line up by stamp."""
    from rosbags.highlevel import AnyReader

    stamped = {"/odom", "/imu", "/scan"}
    seen = set()
    with AnyReader([bag]) as reader:
        for connection, log_time, raw in reader.messages():
            assert wall_start - 1 <= log_time * 1e-9 <= wall_end + 1, connection.topic
            if connection.topic in stamped:
                stamp = reader.deserialize(raw, connection.msgtype).header.stamp
                assert wall_start - 1 <= stamp.sec + stamp.nanosec * 1e-9 <= log_time * 1e-9 + 0.05, connection.topic
                seen.add(connection.topic)
    assert seen == stamped
