"""``run --record``: the bag reads back with rosbags (AnyReader) and, independently, with the
mcap library and mcap-ros2-support, and agrees with the run's summary."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest
import yaml

from tests.paths import ROOT

pytest.importorskip("foxglove")
AnyReader = pytest.importorskip("rosbags.highlevel").AnyReader
make_reader = pytest.importorskip("mcap.reader").make_reader
DecoderFactory = pytest.importorskip("mcap_ros2.decoder").DecoderFactory

EXPECTED_TYPES = {
    "/scan": "sensor_msgs/msg/LaserScan", "/odom": "nav_msgs/msg/Odometry", "/imu": "sensor_msgs/msg/Imu",
    "/tf": "tf2_msgs/msg/TFMessage", "/tf_static": "tf2_msgs/msg/TFMessage", "/map": "nav_msgs/msg/OccupancyGrid",
    "/plan": "nav_msgs/msg/Path", "/cmd_vel": "geometry_msgs/msg/Twist",
    "/cmd_vel/navigation": "geometry_msgs/msg/Twist", "/battery_state": "sensor_msgs/msg/BatteryState",
    "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray", "/behavior_tree_log": "nav2_msgs/msg/BehaviorTreeLog",
    "/supervisor/events": "rcl_interfaces/msg/Log", "/sim/ground_truth": "nav_msgs/msg/Odometry",
    "/sim/ground_truth/pose": "geometry_msgs/msg/PoseStamped",
}


@pytest.fixture(scope="module")
def recorded(tmp_path_factory) -> tuple[Path, dict]:
    out = tmp_path_factory.mktemp("rec")
    bag, summary = out / "run_bag", out / "summary.json"
    result = subprocess.run(
        [sys.executable, "-m", "bt_runtime", "run", "trees/autonomy.xml", "--goal", "yard_east", "--duration", "25",
         "--record", str(bag), "--record-flush", "0.5", "--summary-json", str(summary), "--no-progress"],
        cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert result.returncode in (0, 1), result.stderr
    assert "recording: " in result.stdout
    return bag, json.loads(summary.read_text())


def test_metadata_lists_complete_segments(recorded):
    bag, summary = recorded
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert info["version"] == 9 and info["storage_identifier"] == "mcap"
    assert info["relative_file_paths"] and all((bag / p).is_file() for p in info["relative_file_paths"])
    assert info["message_count"] == summary["recording"]["message_count"] > 0
    assert summary["recording"]["dropped"] == {}


def test_rosbags_reads_topics_types_and_counts(recorded):
    bag, summary = recorded
    with AnyReader([bag]) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        counts = Counter()
        for c in reader.connections:
            counts[c.topic] += c.msgcount
        for topic, msgtype in EXPECTED_TYPES.items():
            assert types.get(topic) == msgtype, topic
        assert dict(counts) == summary["recording"]["messages"]
        assert counts["/supervisor/events"] == summary["supervisor_events"]
        assert counts["/gate/events"] >= summary["gate_switches"]
        tree = [c for c in reader.connections if c.topic == "/behavior_tree_log"]
        first = next(reader.messages(tree))
        log = reader.deserialize(first[2], first[0].msgtype)
        assert log.event_log and log.event_log[0].current_status in ("RUNNING", "SUCCESS", "FAILURE", "IDLE")


def test_mcap_library_decodes_the_same_messages(recorded):
    bag, summary = recorded
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    counts: Counter = Counter()
    twists = []
    for name in info["relative_file_paths"]:
        with open(bag / name, "rb") as f:
            reader = make_reader(f, decoder_factories=[DecoderFactory()])
            assert reader.get_header().profile == "ros2"
            for schema, channel, _message, decoded in reader.iter_decoded_messages():
                assert schema.encoding == "ros2msg" and channel.message_encoding == "cdr"
                counts[channel.topic] += 1
                if channel.topic == "/cmd_vel":
                    twists.append((decoded.linear.x, decoded.angular.z))
    assert dict(counts) == summary["recording"]["messages"]
    assert any(abs(v) > 0.05 for v, _ in twists), "the robot drove: some /cmd_vel is non-zero"
    assert twists[-1] == (0.0, 0.0), "the gate's final zero is recorded"


def _compose(a, b):
    ax, ay, ayaw = a
    bx, by, byaw = b
    c, s = math.cos(ayaw), math.sin(ayaw)
    return (ax + c * bx - s * by, ay + s * bx + c * by, ayaw + byaw)


def _yaw(q) -> float:
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def test_tf_chains_map_to_base_link_near_the_truth(recorded):
    bag, _ = recorded
    links: dict[tuple[str, str], tuple[float, float, float]] = {}
    truth = None
    with AnyReader([bag]) as reader:
        conns = [c for c in reader.connections if c.topic in ("/tf", "/tf_static", "/sim/ground_truth")]
        for conn, _t, raw in reader.messages(conns):
            msg = reader.deserialize(raw, conn.msgtype)
            if conn.topic == "/sim/ground_truth":
                p = msg.pose.pose
                truth = (p.position.x, p.position.y)
                continue
            for tf in msg.transforms:
                tr = tf.transform
                links[(tf.header.frame_id, tf.child_frame_id)] = (tr.translation.x, tr.translation.y, _yaw(tr.rotation))
    assert {("map", "odom"), ("odom", "base_link"), ("base_link", "laser")} <= set(links)
    x, y, _ = _compose(links[("map", "odom")], links[("odom", "base_link")])
    assert truth is not None
    assert math.hypot(x - truth[0], y - truth[1]) < 0.3, (x, y, truth)
