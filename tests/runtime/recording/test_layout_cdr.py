"""Differential: the high-rate messages encoded by patching (``layout.py``) are the bytes rosbags'
own serializer gives for the same values, and decode (with rosbags' Jazzy store) to them.

Random values (seeded) in every slot, including negative times' neighbours, large seconds,
yaw across the circle and frame names of odd lengths (which move every later slot)."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest

pytest.importorskip("rosbags")

from bt_runtime.runtime.messages import Imu, LaserScan, LocalizedPose, Odometry, Pose2D, Twist  # noqa: E402
from bt_runtime.runtime.recording import convert as C  # noqa: E402
from bt_runtime.runtime.recording.config import Frames  # noqa: E402
from bt_runtime.runtime.recording.layout import Layout  # noqa: E402
from bt_runtime.runtime.recording.types import serialize  # noqa: E402

FRAMES = [Frames(), Frames(map="m", odom="odometry_frame", base="base_footprint", laser="lidar_link", imu="imu")]


@pytest.fixture(scope="module")
def jazzy():
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_JAZZY)


def _time(t: float):
    return C.stamp(t)


def _reference_odometry(frame: str, child: str, m: Odometry):
    msg = C.Odometry(header=C.Header(stamp=_time(m.stamp), frame_id=frame), child_frame_id=child,
                     pose=C.PoseWithCovariance(pose=C.pose(m.pose.x, m.pose.y, m.pose.yaw), covariance=C.COV36),
                     twist=C.TwistWithCovariance(twist=C.twist(m.twist.linear, m.twist.angular), covariance=C.COV36))
    return serialize(msg, "nav_msgs/msg/Odometry")


def _reference_tf(parent: str, child: str, t: float, x: float, y: float, yaw: float):
    return serialize(C.TFMessage(transforms=[C.transform(t, parent, child, x, y, yaw)]), "tf2_msgs/msg/TFMessage")


def _random_odometry(rng: random.Random) -> Odometry:
    return Odometry(rng.uniform(0, 1e6), Pose2D(rng.uniform(-500, 500), rng.uniform(-500, 500), rng.uniform(-7, 7)),
                    Twist(rng.uniform(-2, 2), rng.uniform(-3, 3)))


@pytest.mark.parametrize("frames", FRAMES)
def test_odometry_and_its_tf_are_rosbags_bytes(frames, jazzy):
    rng = random.Random(17)
    state = C.ConvertState(frames=frames, tf_topic="/tf")
    for _ in range(200):
        m = _random_odometry(rng)
        (_, otype, odom), (_, tftype, tf) = C.odom(state, "/odom", 0.0, m)
        assert odom == _reference_odometry(frames.odom, frames.base, m)
        assert tf == _reference_tf(frames.odom, frames.base, m.stamp, m.pose.x, m.pose.y, m.pose.yaw)
    back = jazzy.deserialize_cdr(odom, otype)
    assert back.header.frame_id == frames.odom and back.child_frame_id == frames.base
    sec, ns = divmod(int(round(m.stamp * 1e9)), 10**9)
    assert (back.header.stamp.sec, back.header.stamp.nanosec) == (sec, ns)
    p = back.pose.pose
    assert (p.position.x, p.position.y, p.position.z) == (m.pose.x, m.pose.y, 0.0)
    assert math.isclose(2 * math.atan2(p.orientation.z, p.orientation.w) % math.tau, m.pose.yaw % math.tau,
                        abs_tol=1e-9)
    assert (back.twist.twist.linear.x, back.twist.twist.angular.z) == (m.twist.linear, m.twist.angular)
    assert not back.pose.covariance.any()
    tf_back = jazzy.deserialize_cdr(tf, tftype).transforms[0]
    assert (tf_back.header.frame_id, tf_back.child_frame_id) == (frames.odom, frames.base)
    assert (tf_back.transform.translation.x, tf_back.transform.translation.y) == (m.pose.x, m.pose.y)


@pytest.mark.parametrize("frames", FRAMES)
def test_localized_pose_and_ground_truth_are_rosbags_bytes(frames):
    rng = random.Random(3)
    state = C.ConvertState(frames=frames)
    for _ in range(100):
        m = _random_odometry(rng)
        C.odom(state, "/odom", 0.0, m)
        loc = LocalizedPose(m.stamp, Pose2D(rng.uniform(-50, 50), rng.uniform(-50, 50), rng.uniform(-4, 4)))
        (_, _, tf), = C.localized(state, "/tf", 0.0, loc)
        ox, oy, oyaw = state.odom_pose
        yaw = loc.pose.yaw - oyaw
        x = loc.pose.x - (math.cos(yaw) * ox - math.sin(yaw) * oy)
        y = loc.pose.y - (math.sin(yaw) * ox + math.cos(yaw) * oy)
        assert tf == _reference_tf(frames.map, frames.odom, loc.stamp, x, y, yaw)
        (_, _, truth), = C.odometry_like(state, "/sim/ground_truth", 0.0, m)
        assert truth == _reference_odometry(frames.map, frames.base, m)
        state.pose_topics["/sim/ground_truth"] = "/sim/ground_truth/pose"
        (_, _, truth), (topic, typename, pose) = C.odometry_like(state, "/sim/ground_truth", 0.0, m)
        reference = C.PoseStamped(header=C.Header(stamp=_time(m.stamp), frame_id=frames.map),
                                  pose=C.pose(m.pose.x, m.pose.y, m.pose.yaw))
        assert (topic, typename) == ("/sim/ground_truth/pose", "geometry_msgs/msg/PoseStamped")
        assert pose == serialize(reference, typename)
        del state.pose_topics["/sim/ground_truth"]


@pytest.mark.parametrize("frames", FRAMES)
def test_imu_is_rosbags_bytes(frames, jazzy):
    rng = random.Random(5)
    state = C.ConvertState(frames=frames)
    for _ in range(200):
        m = Imu(rng.uniform(0, 1e5), rng.uniform(-3, 3), rng.uniform(-9, 9), rng.uniform(-9, 9), rng.uniform(-7, 7))
        (_, typename, data), = C.imu(state, "/imu", 0.0, m)
        ref = C.Imu(header=C.Header(stamp=_time(m.stamp), frame_id=frames.imu), orientation=C.quat(m.yaw),
                    orientation_covariance=C.COV9, angular_velocity=C.Vector3(x=0.0, y=0.0, z=m.yaw_rate),
                    angular_velocity_covariance=C.COV9,
                    linear_acceleration=C.Vector3(x=m.accel_x, y=m.accel_y, z=0.0),
                    linear_acceleration_covariance=C.COV9)
        assert data == serialize(ref, typename)
    back = jazzy.deserialize_cdr(data, typename)
    assert back.angular_velocity.z == m.yaw_rate and back.linear_acceleration.y == m.accel_y


def test_twist_is_rosbags_bytes():
    rng = random.Random(7)
    state = C.ConvertState()
    for _ in range(100):
        m = Twist(rng.uniform(-5, 5), rng.uniform(-5, 5))
        (_, typename, data), = C.command(state, "/cmd_vel", 0.0, m)
        assert data == serialize(C.twist(m.linear, m.angular), typename)


@pytest.mark.parametrize("n", [0, 1, 360, 721])
def test_scan_is_rosbags_bytes(n, jazzy):
    rng = np.random.default_rng(11)
    state = C.ConvertState(frames=FRAMES[1])
    for k in range(5):
        ranges = rng.uniform(0.1, 12.0, n)
        ranges[rng.random(n) < 0.1] = np.inf  # nothing hit
        m = LaserScan(100.0 + k * 0.2, -math.pi, 2 * math.pi / max(n, 1), 0.12, 12.0, ranges)
        (_, typename, data), = C.scan(state, "/scan", 0.0, m)
        ref = C.LaserScan(header=C.Header(stamp=_time(m.stamp), frame_id="lidar_link"), angle_min=m.angle_min,
                          angle_max=m.angle_min + m.angle_increment * max(n - 1, 0),
                          angle_increment=m.angle_increment, time_increment=0.0, scan_time=0.0,
                          range_min=m.range_min, range_max=m.range_max, ranges=ranges.astype(np.float32),
                          intensities=C.EMPTY32)
        assert data == serialize(ref, typename)
    back = jazzy.deserialize_cdr(data, typename)
    assert np.array_equal(back.ranges, ranges.astype(np.float32)) and back.header.frame_id == "lidar_link"


def test_a_slot_of_the_wrong_width_or_kind_is_refused():
    msg = C.Log(stamp=_time(0.0), level=20, name="a", msg="b", file="", function="", line=0)
    with pytest.raises(ValueError, match="field name does not take a 'd' value"):
        Layout("rcl_interfaces/msg/Log", msg, [(("name",), "d")])
    tf = C.TFMessage(transforms=[C.transform(0.0, "a", "b", 0.0, 0.0, 0.0)])
    with pytest.raises(ValueError, match="transforms.0.transform.translation.x is not a fixed 'I' slot"):
        Layout("tf2_msgs/msg/TFMessage", tf, [(("transforms", 0, "transform", "translation", "x"), "I")])
    with pytest.raises(ValueError, match="not in wire order"):
        C.Layout("geometry_msgs/msg/Twist", C.twist(0.0, 0.0), [(("angular", "z"), "d"), (("linear", "x"), "d")])
