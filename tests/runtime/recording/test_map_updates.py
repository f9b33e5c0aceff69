"""/map is recorded at start and again when the navigation map changes (a collision mark), each
teleop command goes on its own topic, and the drops of a full queue are counted, not waited for."""

from __future__ import annotations

import asyncio

import numpy as np
import pytest

pytest.importorskip("foxglove")
AnyReader = pytest.importorskip("rosbags.highlevel").AnyReader

from bt_runtime.runtime.app import AutonomyRuntime  # noqa: E402
from bt_runtime.runtime.clock import run as run_loop  # noqa: E402
from bt_runtime.runtime.recording.cli import Recording  # noqa: E402
from bt_runtime.runtime.recording.config import RecordingOptions  # noqa: E402
from sim.driver import SimDriver  # noqa: E402
from sim.recording import recording_hooks  # noqa: E402

TREE = """<root BTCPP_format="4"><BehaviorTree ID="Main"><Sleep msec="100000"/></BehaviorTree></root>"""


def _record(folder, options: RecordingOptions, body) -> dict:
    async def main() -> dict:
        driver = SimDriver("apartment", "burger", seed=1)
        runtime = AutonomyRuntime(driver)
        runtime.load_tree(TREE)
        recording = Recording(bag=folder, options=options).start(runtime, recording_hooks(driver))
        await runtime.start()
        await body(driver)
        await runtime.stop()
        return recording.stop()

    return run_loop(main(), virtual=True)


def test_a_collision_mark_records_the_map_again(tmp_path):
    async def body(driver) -> None:
        await asyncio.sleep(1.0)
        await driver.navigation.add_obstacle(1.0, 0.5, 0.3)
        await asyncio.sleep(1.0)

    report = _record(tmp_path / "bag", RecordingOptions(), body)
    assert report["messages"]["/map"] == 2
    with AnyReader([tmp_path / "bag"]) as reader:
        maps = [reader.deserialize(raw, c.msgtype) for c, _t, raw in
                reader.messages([c for c in reader.connections if c.topic == "/map"])]
    before, after = (np.asarray(m.data) for m in maps)
    assert maps[0].info.width * maps[0].info.height == before.size
    assert int((after == 100).sum()) > int((before == 100).sum()), "the mark is in the second map"


def test_a_full_queue_drops_and_counts(tmp_path, monkeypatch):
    async def body(driver) -> None:
        await asyncio.sleep(2.0)

    from bt_runtime.runtime.recording import pipeline

    # a writer that never runs (on virtual time the writer is the loop's drain): the queue fills up
    monkeypatch.setattr(pipeline.RecordPipeline, "drain", lambda self: None)
    report = _record(tmp_path / "bag", RecordingOptions(queue_size=100), body)
    assert report["dropped"].get("/odom", 0) > 0 and report["dropped"].get("/imu", 0) > 0
    assert report["message_count"] == 0  # the run went on: 2 s of robot time with nothing written


def test_each_teleop_command_is_recorded_on_its_own_topic(tmp_path):
    sent = [(0.1 * k, -0.05 * k) for k in range(1, 6)]

    async def body(driver) -> None:
        await asyncio.sleep(0.5)
        for linear, angular in sent:
            driver.publish_command_input("teleop", linear, angular)
            await asyncio.sleep(0.2)

    report = _record(tmp_path / "bag", RecordingOptions(), body)
    assert report["messages"]["/cmd_vel/teleop"] == len(sent)
    with AnyReader([tmp_path / "bag"]) as reader:
        conns = [c for c in reader.connections if c.topic == "/cmd_vel/teleop"]
        assert conns[0].msgtype == "geometry_msgs/msg/Twist"
        got = [(m.linear.x, m.angular.z) for m in
               (reader.deserialize(raw, c.msgtype) for c, _t, raw in reader.messages(conns))]
    assert got == sent  # float64 on the wire: exact


def test_a_small_queue_is_drained_before_it_fills(tmp_path):
    """On virtual time a bag alone is drained every 5 robot s, or sooner when a quarter of the
    queue is used: a queue of 400 (about 2 robot s of this run) drops nothing in 12 s."""
    async def body(driver) -> None:
        await asyncio.sleep(12.0)

    report = _record(tmp_path / "bag", RecordingOptions(queue_size=400), body)
    assert report["dropped"] == {}
    assert 100 <= report["max_queued"] < 400
    assert report["messages"]["/odom"] >= 12 * 45
