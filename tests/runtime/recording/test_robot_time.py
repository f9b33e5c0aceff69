"""A driver with its own clock (``robot_time``, as the ROS 2 driver has) gets a bag in robot time:
every log time and every header stamp is the driver's time, not the event loop's."""

from __future__ import annotations

import asyncio

import pytest

pytest.importorskip("foxglove")
AnyReader = pytest.importorskip("rosbags.highlevel").AnyReader

from bt_runtime.runtime.app import AutonomyRuntime  # noqa: E402
from bt_runtime.runtime.clock import run as run_loop  # noqa: E402
from bt_runtime.runtime.recording.cli import Recording  # noqa: E402
from sim.driver import SimDriver  # noqa: E402

TREE = """<root BTCPP_format="4"><BehaviorTree ID="Main"><Sleep msec="100000"/></BehaviorTree></root>"""
OFFSET = 1_700_000_000.25  # robot time - loop time: an epoch clock, as ROS time is


def _stamp_s(msg) -> float | None:
    for holder in (getattr(msg, "header", None), msg):
        stamp = getattr(holder, "stamp", None)
        if stamp is not None:
            return stamp.sec + stamp.nanosec * 1e-9
    transforms = getattr(msg, "transforms", None)
    if transforms:
        return _stamp_s(transforms[0])
    return None


def test_bag_stamps_and_log_times_are_the_drivers_robot_time(tmp_path):
    bag = tmp_path / "bag"

    async def main() -> tuple[float, float]:
        driver = SimDriver("apartment", "burger", seed=1)
        driver.robot_time = lambda loop_time: loop_time + OFFSET  # the robot's clock, as Ros2Driver gives it
        runtime = AutonomyRuntime(driver)
        runtime.load_tree(TREE)
        recording = Recording(bag=bag).start(runtime)
        start = runtime.clock()
        await runtime.start()
        await asyncio.sleep(2.0)
        await runtime.stop()
        recording.stop()
        return start, runtime.clock()

    start, end = run_loop(main(), virtual=True)
    seen: set[str] = set()
    with AnyReader([bag]) as reader:
        for connection, log_time, raw in reader.messages():
            msg = reader.deserialize(raw, connection.msgtype)
            seen.add(connection.topic)
            assert start + OFFSET - 1e-6 <= log_time * 1e-9 <= end + OFFSET + 1e-6, connection.topic
            stamp = _stamp_s(msg)
            if stamp is not None:  # the header says when the data was taken: at or before it was logged
                assert start + OFFSET - 0.5 <= stamp <= log_time * 1e-9 + 1e-6, connection.topic
    assert {"/odom", "/imu", "/scan", "/tf", "/tf_static", "/diagnostics"} <= seen
