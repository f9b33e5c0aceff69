"""The motion-mismatch contact detector (nodes/stall.py): IMU against the wheels, no truth."""

from __future__ import annotations

import math

import pytest

from bt_runtime.runtime.backup import DataBackup
from bt_runtime.runtime.messages import Imu, Odometry, Pose2D, RobotInfo, Twist
from nodes.stall import MotionMismatch


class Ctx:
    """What the detector reads: the data backup, the clock, the robot's limits."""

    def __init__(self, healthy: bool = True):
        self.t = 0.0
        self.backup = DataBackup(None, clock=lambda: self.t)
        self.robot = RobotInfo(max_linear_accel=1.0)
        self.supervisor = _Supervisor(healthy)
        self._k = 0

    def clock(self):
        return self.t

    def drive(self, seconds: float, v, ax, ay=0.0, wz=0.0, imu_noise: bool = True, odom_v=None):
        """IMU at 50 Hz, odometry at 20 Hz; ``v``/``ax``/``ay`` may be functions of time."""
        end = self.t + seconds
        while self.t < end - 1e-9:
            self.t = round(self.t + 0.01, 6)
            self._k += 1
            at = lambda f: f(self.t) if callable(f) else f  # noqa: E731
            if self._k % 2 == 0:
                jitter = 0.001 * math.sin(self._k * 1.7) if imu_noise else 0.0
                self.backup.record("imu", Imu(self.t, at(wz), at(ax) + jitter, at(ay) - jitter))
            if self._k % 5 == 0:
                speed = at(v if odom_v is None else odom_v)
                wheel = speed * (1 + 0.01 * math.sin(self._k)) if speed else 0.0
                self.backup.record("odom", Odometry(self.t, Pose2D(0, 0, 0), Twist(wheel, at(wz))))


class _Supervisor:
    def __init__(self, healthy: bool):
        self.components = {"imu": None, "odom": None}
        self.healthy = healthy

    def is_healthy(self, name):
        return self.healthy


def sense(ctx, detector):
    return detector(ctx, threshold=1.0, stall_speed=0.08, stall_window=0.4, window=0.25)


def ramp(t0, v0, v1, a=1.0):
    """Wheel speed ramping from v0 to v1 at ``a`` from t0 (the base's acceleration limit)."""
    def v(t):
        dv = min(abs(v1 - v0), a * max(0.0, t - t0))
        return v0 + math.copysign(dv, v1 - v0)
    return v


def test_normal_driving_accelerating_turning_and_braking_is_no_contact():
    ctx, detect = Ctx(), MotionMismatch()
    ctx.drive(1.0, 0.0, 0.0)
    up = ramp(ctx.t, 0.0, 0.25)
    t0 = ctx.t
    ctx.drive(0.5, up, lambda t: 1.0 if t - t0 < 0.25 else 0.0)  # accelerate at the limit
    assert sense(ctx, detect) is None
    ctx.drive(2.0, 0.25, 0.0, ay=0.25 * 0.8, wz=0.8)  # a curve: v * w sideways
    assert sense(ctx, detect) is None
    t0, down = ctx.t, ramp(ctx.t, 0.25, 0.0)
    ctx.drive(0.5, down, lambda t: -1.0 if t - t0 < 0.25 else 0.0)  # brake at the limit
    ctx.drive(1.0, 0.0, 0.0, ay=0.0, wz=1.5)  # turn in place
    assert sense(ctx, detect) is None and detect.event is None


def test_a_glancing_push_below_the_impact_threshold_is_a_contact_on_that_side():
    """V0004 of seed 2026: a ROSbot at 0.125 m/s brushed the box's corner with its left front;
    the IMU showed (-1.3, -2.1) m/s^2 for one sample, far below the 6 m/s^2 impact threshold."""
    ctx, detect = Ctx(), MotionMismatch()
    ctx.drive(1.0, 0.125, 0.0)
    ctx.drive(0.02, 0.125, -1.31, ay=-2.1)
    bearing, kind = sense(ctx, detect)
    assert kind == "push" and 0.5 < bearing < math.pi / 2 + 0.1  # front-left
    ctx.drive(0.5, 0.125, 0.0)
    assert sense(ctx, detect) is None  # forgotten after the window


def test_wheels_turning_while_the_body_stops_is_blocked_ahead():
    """A slow, soft stop (no spike beyond the base's own deceleration) while the wheels keep
    their speed: something holds the robot, in the direction of travel."""
    ctx, detect = Ctx(), MotionMismatch()
    ctx.drive(1.0, 0.1, 0.0)
    t0 = ctx.t
    ctx.drive(0.3, 0.1, lambda t: -0.9 if t - t0 < 0.11 else 0.0)
    bearing, kind = sense(ctx, detect)
    assert kind == "blocked" and bearing == pytest.approx(0.0)
    back = Ctx()
    back.drive(1.0, -0.1, 0.0)
    t0 = back.t
    back.drive(0.3, -0.1, lambda t: 0.9 if t - t0 < 0.11 else 0.0)
    bearing, kind = sense(back, MotionMismatch())
    assert kind == "blocked" and bearing == pytest.approx(math.pi)


def test_frozen_odometry_or_a_failed_sensor_never_reads_as_a_contact():
    """A frozen odometry driver re-stamps one reading: the wheels' speed is unknown, so the
    robot braking while odometry still says 0.2 m/s is no evidence of anything."""
    ctx, detect = Ctx(), MotionMismatch()
    ctx.drive(1.0, 0.2, 0.0)
    frozen = Twist(0.2, 0.0)
    t0 = ctx.t
    while ctx.t < t0 + 0.6:
        ctx.t = round(ctx.t + 0.02, 6)
        ctx.backup.record("imu", Imu(ctx.t, 0.0, -0.9 + 0.001 * math.sin(ctx.t * 50), 0.0))
        ctx.backup.record("odom", Odometry(ctx.t, Pose2D(0, 0, 0), frozen))
    assert sense(ctx, detect) is None
    sick = Ctx(healthy=False)
    sick.drive(1.0, 0.125, 0.0)
    sick.drive(0.02, 0.125, -1.31, ay=-4.0)
    assert sense(sick, MotionMismatch()) is None
