"""RobotClock: header stamps (the robot's ROS time) onto the loop clock, and back for logs.

The driver used to stamp messages on receipt, so a sensor driver republishing an old reading
looked fresh; these pin what the estimate must survive: transport delay, a stream that lags,
a broken stamp, a zero stamp, and the robot's clock stepping back or ahead.
"""

import pytest

pytest.importorskip("cyclonedds")

from bt_runtime.runtime.ros2.robot_clock import RobotClock  # noqa: E402

ROS0 = 1_764_000_000.0  # a ROS time (system clock) at loop time 0


def test_header_stamps_map_onto_the_loop_clock_through_delay():
    clock = RobotClock()
    assert clock.to_robot(5.0) is None  # nothing seen yet
    # 10 ms of delay on the first message, 2 ms on the next: the smaller delay sets the offset,
    # and a later message with more delay is stamped earlier than its receipt
    assert clock.to_loop("scan", ROS0 + 1.00, 1.010) == pytest.approx(1.010)
    assert clock.to_loop("odom", ROS0 + 1.05, 1.052) == pytest.approx(1.052)
    assert clock.to_loop("scan", ROS0 + 1.10, 1.120) == pytest.approx(1.102)
    assert clock.to_robot(2.0) == pytest.approx(ROS0 + 2.0 - 0.002)


def test_republished_old_stamps_look_old_and_do_not_move_the_clock():
    clock = RobotClock()
    for k in range(100):  # odom fresh at 50 Hz; from 0.6 s the IMU driver republishes one message
        t = k * 0.02
        clock.to_loop("odom", ROS0 + t, t + 0.001)
        imu = clock.to_loop("imu", ROS0 + (t if t < 0.6 else 0.5), t + 0.001)
    assert imu == pytest.approx(0.5, abs=0.002)  # it stays as old as it is
    assert clock.to_robot(2.0) == pytest.approx(ROS0 + 2.0 - 0.001)


def test_zero_stamps_keep_their_receipt_time():
    clock = RobotClock()
    assert clock.to_loop("battery", 0.0, 3.25) == 3.25
    assert clock.unstamped == {"battery"}
    assert clock.to_robot(3.25) is None


def test_one_stream_with_a_stamp_far_ahead_does_not_move_the_clock():
    clock = RobotClock()
    clock.to_loop("scan", ROS0 + 1.0, 1.0)
    assert clock.to_loop("imu", ROS0 + 500.0, 1.01) == 1.01  # never later than its receipt
    clock.to_loop("scan", ROS0 + 1.02, 1.02)
    assert clock.to_robot(1.02) == pytest.approx(ROS0 + 1.02)


def test_a_jump_ahead_seen_by_two_streams_is_taken():
    clock = RobotClock()
    clock.to_loop("scan", ROS0 + 1.0, 1.0)
    clock.to_loop("scan", ROS0 + 101.0, 1.01)
    clock.to_loop("odom", ROS0 + 101.005, 1.015)
    assert clock.to_robot(1.02) == pytest.approx(ROS0 + 101.01, abs=0.01)


def test_a_clock_stepping_back_is_followed_within_two_windows():
    clock = RobotClock(window=1.0)
    for k in range(50):
        clock.to_loop("odom", ROS0 + k * 0.02, k * 0.02)
    for k in range(50, 200):  # a simulation restarted: ROS time 100 s earlier from here on
        t = k * 0.02
        stamp = clock.to_loop("odom", ROS0 - 100.0 + t, t)
    assert stamp == pytest.approx(t)
    assert clock.to_robot(t) == pytest.approx(ROS0 - 100.0 + t)
