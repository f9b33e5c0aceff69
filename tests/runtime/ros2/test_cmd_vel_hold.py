"""The ROS 2 driver keeps a standing base's repeated zeros off the wire (no DDS traffic: the
driver's cmd_vel writer is replaced by one that keeps what it is given)."""

import time

import pytest

pytest.importorskip("cyclonedds")

from bt_runtime.runtime.ros2 import Ros2Config, Ros2Driver, idl  # noqa: E402


class KeptWriter:
    def __init__(self):
        self.written: list[tuple[float, float]] = []

    def write(self, msg) -> None:
        self.written.append((msg.linear.x, msg.angular.z))


def driver_with_writer(period: float) -> tuple[Ros2Driver, KeptWriter, list]:
    driver = Ros2Driver(Ros2Config(topics={"cmd_vel": {"zero_repeat_period": period}}))
    writer = KeptWriter()
    driver._cmd_writer, driver._cmd_type = writer, idl.Twist
    announced: list = []
    driver.subscribe("cmd_vel_out", lambda twist: announced.append((twist.linear, twist.angular)))
    return driver, writer, announced


def test_repeated_zeros_are_held_but_every_change_goes_out_at_once():
    driver, writer, announced = driver_with_writer(period=60.0)
    driver.send_velocity(0.2, 0.1)
    driver.send_velocity(0.2, 0.1)  # a repeated motion command is always written
    driver.send_velocity(0.0, 0.0)  # the first zero: written at once
    for _ in range(10):
        driver.send_velocity(0.0, 0.0)  # the base stands: held
    driver.send_velocity(0.1, 0.0)
    driver.send_velocity(0.0, 0.0)
    assert writer.written == [(0.2, 0.1), (0.2, 0.1), (0.0, 0.0), (0.1, 0.0), (0.0, 0.0)]
    assert driver.zeros_held == 10
    assert len(announced) == 15, "every command is announced on cmd_vel_out: zero is in force either way"


def test_a_held_zero_is_repeated_after_the_period_and_emergency_zero_always_writes():
    driver, writer, _ = driver_with_writer(period=0.05)
    driver.send_velocity(0.0, 0.0)
    driver.send_velocity(0.0, 0.0)
    time.sleep(0.06)
    driver.send_velocity(0.0, 0.0)  # keep-alive of the standing base
    driver.emergency_zero()
    assert writer.written == [(0.0, 0.0)] * 3


def test_period_zero_writes_every_command():
    driver, writer, _ = driver_with_writer(period=0.0)
    for _ in range(5):
        driver.send_velocity(0.0, 0.0)
    assert len(writer.written) == 5
