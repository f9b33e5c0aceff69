"""The recording's small typestore carries ROS 2 Jazzy's definitions: same type hashes, and
CDR that rosbags' full Jazzy store reads back."""

from __future__ import annotations

import pytest

pytest.importorskip("rosbags")

from bt_runtime.runtime.messages import Imu, Odometry, Pose2D, Twist  # noqa: E402
from bt_runtime.runtime.recording import convert, types  # noqa: E402
from bt_runtime.runtime.recording.msgdefs import DEFINITIONS  # noqa: E402


@pytest.fixture(scope="module")
def jazzy():
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_JAZZY)


@pytest.mark.parametrize("typename", sorted(DEFINITIONS))
def test_same_type_hash_as_jazzy(jazzy, typename):
    assert types.type_hash(typename) == jazzy.hash_rihs01(typename)


def test_nav2_tree_log_schema_names_its_fields():
    text = types.schema("nav2_msgs/msg/BehaviorTreeLog")
    assert text.startswith("builtin_interfaces/Time timestamp\nnav2_msgs/BehaviorTreeStatusChange[] event_log")
    assert "uint16 uid" in text and "string current_status" in text


def test_converted_messages_read_back_with_the_jazzy_store(jazzy):
    state = convert.ConvertState()
    odom = Odometry(12.5, Pose2D(1.0, -2.0, 0.5), Twist(0.2, -0.1))
    (topic, typename, msg), (tf_topic, tf_type, tf) = convert.odom(state, "/odom", 12.5, odom)
    back = jazzy.deserialize_cdr(msg, typename)
    assert (back.header.stamp.sec, back.header.stamp.nanosec) == (12, 500_000_000)
    assert (back.pose.pose.position.x, back.pose.pose.position.y) == (1.0, -2.0)
    assert back.twist.twist.linear.x == 0.2 and back.twist.twist.angular.z == -0.1
    tf_back = jazzy.deserialize_cdr(tf, tf_type)
    assert (tf_back.transforms[0].header.frame_id, tf_back.transforms[0].child_frame_id) == ("odom", "base_link")
    imu = convert.imu(state, "/imu", 1.0, Imu(1.0, 0.3, 0.1, 0.0, yaw=0.0))[0]
    assert jazzy.deserialize_cdr(imu[2], imu[1]).angular_velocity.z == 0.3


def test_localized_pose_gives_map_to_odom_that_composes_to_it():
    from bt_runtime.runtime.messages import LocalizedPose

    state = convert.ConvertState()
    convert.odom(state, "/odom", 1.0, Odometry(1.0, Pose2D(1.0, 0.0, 0.0), Twist()))
    (_, tf_type, tf), = convert.localized(state, "/tf", 1.0, LocalizedPose(1.0, Pose2D(3.0, 1.0, 0.0)))
    t = types.typestore().deserialize_cdr(tf, tf_type).transforms[0].transform.translation
    assert (t.x, t.y) == (2.0, 1.0)  # map -> odom: 2 m along x, 1 m along y


def test_the_recording_store_makes_only_the_cdr_serializer_and_still_reads_back(jazzy):
    """The lean get_msgdef is in use with this rosbags (a version that moves its generators falls
    back to rosbags' own, and this test says so), and what it does not make up front still works."""
    store = types.typestore()
    assert "get_msgdef" in vars(store), "rosbags' full code generation is in use: check types._lean_get_msgdef"
    state = convert.ConvertState()
    imu = convert.imu(state, "/imu", 1.0, Imu(2.5, 0.3, 0.1, -0.2, yaw=1.0))[0]
    back = store.deserialize_cdr(imu[2], imu[1])  # deserializer made on first use
    assert back.angular_velocity.z == 0.3 and back.header.stamp.sec == 2
    data = convert.log_line(state, 3.0, 20, "gate", "nav -> tree")
    assert store.deserialize_cdr(data, "rcl_interfaces/msg/Log").msg == "nav -> tree"
    log = jazzy.deserialize_cdr(data, "rcl_interfaces/msg/Log")
    assert types.serialize(log, "rcl_interfaces/msg/Log") == data  # rosbags' serializer, on first use
    assert data == jazzy.serialize_cdr(jazzy.deserialize_cdr(data, "rcl_interfaces/msg/Log"), "rcl_interfaces/msg/Log")
    assert store.get_msgdef("rcl_interfaces/msg/Log").size_ros1 == jazzy.get_msgdef("rcl_interfaces/msg/Log").size_ros1


def test_battery_keeps_the_monitors_charging_status():
    """A robot on its dock is recorded CHARGING (as its monitor said), not judged from the current."""
    from bt_runtime.runtime.messages import POWER_SUPPLY_CHARGING, BatteryState

    state = convert.ConvertState()

    def status(msg: BatteryState) -> int:
        (_, typename, out), = convert.battery(state, "/battery_state", 1.0, msg)
        return types.typestore().deserialize_cdr(out, typename).power_supply_status

    assert status(BatteryState(1.0, 12.0, 40.0, current=-2.0, power_supply_status=POWER_SUPPLY_CHARGING)) == 1
    assert status(BatteryState(1.0, 12.0, 40.0, current=1.5)) == 2  # no status given: drawing current
