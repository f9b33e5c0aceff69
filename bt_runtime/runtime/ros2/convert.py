"""ROS 2 messages <-> the runtime's messages: poses and quaternions, the validating sensor
converter (a message that fails its limits raises ``Drop``), paths and Nav2 error codes.

``sim/ros2_robot.py`` (the simulated robot on the other side of DDS) uses the same pose helpers,
so both ends of the wire agree on the conventions.
"""

from __future__ import annotations

import math

import numpy as np

from ..messages import (
    BatteryState,
    Contact,
    Imu,
    LaserScan,
    LocalizedPose,
    NavErrorCode,
    Odometry,
    Path,
    Pose2D,
    Twist,
    yaw_from_quaternion,
)
from . import idl
from .config import Ros2Config

E = NavErrorCode


def yaw_of(q: idl.Quaternion) -> float:
    return yaw_from_quaternion(q.x, q.y, q.z, q.w)


def quaternion_of(yaw: float) -> idl.Quaternion:
    return idl.Quaternion(0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0))


def pose2d_of(pose: idl.Pose) -> Pose2D:
    return Pose2D(pose.position.x, pose.position.y, yaw_of(pose.orientation))


def pose_msg(p: Pose2D) -> idl.Pose:
    return idl.Pose(position=idl.Point(p.x, p.y, 0.0), orientation=quaternion_of(p.yaw))


def _finite(*values: float) -> bool:
    # a finite sum has no inf or NaN in it (either would make the sum one); a sum that
    # overflowed is checked value by value
    return math.isfinite(sum(values)) or all(math.isfinite(v) for v in values)


def scan_values_of(m: idl.LaserScan) -> tuple:
    """What ``Converter.scan_values`` reads of a LaserScan."""
    return (m.angle_min, m.angle_max, m.angle_increment, m.range_min, m.range_max,
            np.asarray(m.ranges, dtype=np.float32), len(m.intensities))


def imu_values_of(m: idl.Imu) -> tuple:
    """What ``Converter.imu_values`` reads of an Imu."""
    w, a, q = m.angular_velocity, m.linear_acceleration, m.orientation
    return (w.x, w.y, w.z, a.x, a.y, a.z, q.x, q.y, q.z, q.w, m.orientation_covariance[0])


def odom_values_of(m: idl.Odometry) -> tuple:
    """What ``Converter.odom_values`` reads of an Odometry."""
    p, q, t = m.pose.pose.position, m.pose.pose.orientation, m.twist.twist
    return (p.x, p.y, q.x, q.y, q.z, q.w, t.linear.x, t.angular.z)


class Drop(Exception):  # noqa: N818 - a verdict, not an error
    """A message that fails validation."""


class Converter:
    """ROS messages -> runtime messages, with the validation limits of the config."""

    def __init__(self, config: Ros2Config):
        self.v = config.validation

    def scan(self, m: idl.LaserScan, now: float) -> LaserScan:
        return self.scan_values(scan_values_of(m), now)

    def scan_values(self, values: tuple, now: float) -> LaserScan:
        """``scan`` on what it reads: angle_min, angle_max, angle_increment, range_min,
        range_max, the ranges as a float32 array, the number of intensities."""
        v = self.v
        angle_min, angle_max, increment, range_min, range_max, ranges, intensities = values
        n = len(ranges)
        if n == 0 or n > v.max_scan_beams:
            raise Drop(f"{n} beams")
        if not _finite(angle_min, angle_max, increment, range_min, range_max):
            raise Drop("non-finite scan geometry")
        if increment == 0 or not (0 <= range_min < range_max <= v.max_range):
            raise Drop("absurd scan geometry")
        expected = (angle_max - angle_min) / increment + 1
        if abs(expected - n) > 1.5:
            raise Drop(f"{n} ranges for {expected:.0f} beams")
        if intensities and intensities != n:
            raise Drop("intensities and ranges differ in size")
        nan = np.isnan(ranges)
        if nan.mean() > v.max_nan_fraction:
            raise Drop(f"{int(nan.sum())} of {n} ranges NaN")
        finite = ranges[np.isfinite(ranges)]
        if finite.size and (finite.min() < 0 or finite.max() > 10 * range_max):
            raise Drop("ranges out of bounds")
        return LaserScan(now, float(angle_min), float(increment), float(range_min), float(range_max), ranges)

    def imu(self, m: idl.Imu, now: float) -> Imu:
        return self.imu_values(imu_values_of(m), now)

    def imu_values(self, values: tuple, now: float) -> Imu:
        """``imu`` on the numbers it reads (``sensor_wire.py`` takes them from the bytes):
        angular velocity, linear acceleration, orientation (x, y, z, w), orientation_covariance[0]."""
        v = self.v
        wx, wy, wz, ax, ay, az, qx, qy, qz, qw, cov0 = values
        if not _finite(wx, wy, wz, ax, ay, az, qx, qy, qz, qw):
            raise Drop("non-finite imu")
        if abs(wz) > v.max_yaw_rate or max(abs(ax), abs(ay), abs(az)) > v.max_accel:
            raise Drop("absurd imu")
        norm = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
        known = cov0 != -1.0 and norm > 0
        if known and abs(norm - 1.0) > 0.1:
            raise Drop("orientation is not a unit quaternion")
        return Imu(now, float(wz), float(ax), float(ay), yaw_from_quaternion(qx, qy, qz, qw) if known else 0.0)

    def odom(self, m: idl.Odometry, now: float) -> Odometry:
        return self.odom_values(odom_values_of(m), now)

    def odom_values(self, values: tuple, now: float) -> Odometry:
        """``odom`` on the numbers it reads: position x, y, orientation (x, y, z, w), linear x,
        angular z."""
        v = self.v
        px, py, qx, qy, qz, qw, vx, wz = values
        if not _finite(px, py, qx, qy, qz, qw, vx, wz):
            raise Drop("non-finite odometry")
        if max(abs(px), abs(py)) > v.max_position or abs(vx) > v.max_speed or abs(wz) > v.max_yaw_rate:
            raise Drop("absurd odometry")
        if qx * qx + qy * qy + qz * qz + qw * qw < 1e-6:
            raise Drop("zero quaternion")
        return Odometry(now, Pose2D(px, py, yaw_from_quaternion(qx, qy, qz, qw)), Twist(float(vx), float(wz)))

    def pose(self, m: idl.PoseWithCovarianceStamped, now: float) -> LocalizedPose:
        p, q = m.pose.pose.position, m.pose.pose.orientation
        cov = m.pose.covariance
        if not _finite(p.x, p.y, q.x, q.y, q.z, q.w, cov[0], cov[7], cov[35]):
            raise Drop("non-finite pose")
        if max(abs(p.x), abs(p.y)) > self.v.max_position:
            raise Drop("absurd pose")
        if q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w < 1e-6:
            raise Drop("zero quaternion")
        sigma = math.sqrt(max(0.0, (cov[0] + cov[7]) / 2.0))
        return LocalizedPose(now, Pose2D(p.x, p.y, yaw_of(q)), sigma)

    def battery(self, m: idl.BatteryState, now: float) -> BatteryState:
        if not _finite(m.voltage, m.percentage) or not (0 <= m.voltage <= self.v.max_voltage):
            raise Drop("bad voltage or percentage")
        if not (-0.001 <= m.percentage <= 1.001):
            raise Drop("percentage outside 0..1")
        current = float(m.current) if math.isfinite(m.current) else 0.0
        capacity = float(m.capacity) if math.isfinite(m.capacity) else 0.0
        # ROS: current is negative while discharging; ours is positive when discharging
        return BatteryState(now, float(m.voltage), float(m.percentage) * 100.0, -current,
                            float(m.voltage) * -current, capacity, int(m.power_supply_status))

    def bumper_bool(self, m: idl.Bool, now: float) -> Contact:
        return Contact(now, bool(m.data))

    def bumper_vector(self, m: idl.Vector3Stamped, now: float) -> Contact:
        x, y, z = m.vector.x, m.vector.y, m.vector.z
        if not _finite(x, y, z):
            raise Drop("non-finite contact")
        if x == 0.0 and y == 0.0:
            return Contact(now, False)
        return Contact(now, True, direction=math.atan2(y, x))  # z (force) is not used: a bumper says where, not how hard

    def twist(self, m: idl.Twist, now: float) -> Twist:
        v, w = m.linear.x, m.angular.z
        if not _finite(v, w) or abs(v) > self.v.max_speed or abs(w) > self.v.max_yaw_rate:
            raise Drop("bad velocity command")
        return Twist(float(v), float(w))



# ---------------------------------------------------------------------------------------------
# Nav2 results
# ---------------------------------------------------------------------------------------------

UNKNOWN_CODE = {"navigate_to_pose": E.NAVIGATE_UNKNOWN, "compute_path_to_pose": E.PLANNER_UNKNOWN,
                "follow_path": E.CONTROLLER_UNKNOWN, "spin": E.BEHAVIOR_UNKNOWN, "backup": E.BEHAVIOR_UNKNOWN,
                "drive_on_heading": E.BEHAVIOR_UNKNOWN, "wait": E.BEHAVIOR_UNKNOWN,
                "dock_robot": 999, "undock_robot": 999}  # DockRobot/UndockRobot UNKNOWN
DOCKING = ("dock_robot", "undock_robot")  # their codes (901-907, 999) are passed on as they are
# Jazzy gives BackUp 710.., DriveOnHeading 720.., Wait 740..; the runtime uses Spin's 700..
BEHAVIOR_CODES = {710: E.BEHAVIOR_UNKNOWN, 711: E.BEHAVIOR_TIMEOUT, 712: E.BEHAVIOR_TF_ERROR,
                  713: E.INVALID_INPUT, 714: E.COLLISION_AHEAD, 720: E.BEHAVIOR_UNKNOWN,
                  721: E.BEHAVIOR_TIMEOUT, 722: E.BEHAVIOR_TF_ERROR, 723: E.COLLISION_AHEAD,
                  724: E.INVALID_INPUT, 740: E.BEHAVIOR_UNKNOWN, 741: E.BEHAVIOR_TIMEOUT}


def error_code_of(kind: str, value: int) -> NavErrorCode | int:
    if kind in DOCKING:
        return int(value)
    if value in BEHAVIOR_CODES:
        return BEHAVIOR_CODES[value]
    try:
        return NavErrorCode(value)
    except ValueError:
        return UNKNOWN_CODE[kind]


def path_of(msg: idl.Path, stamp: float) -> Path:
    pts = np.array([[p.pose.position.x, p.pose.position.y, yaw_of(p.pose.orientation)] for p in msg.poses],
                   dtype=float).reshape(-1, 3)
    return Path(stamp, pts)

