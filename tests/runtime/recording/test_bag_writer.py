"""A bag alone is written by ``bag_writer.BagWriter`` (one fused function per stream); the bag
it makes of a run's queue is the generic path's (``RecordPipeline._write_one``, the converters)
message for message: the same channels, the same topic, log time, sequence and bytes of every
message in every segment, the same metadata.yaml and counts."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

pytest.importorskip("foxglove")
make_reader = pytest.importorskip("mcap.reader").make_reader

from bt_runtime.runtime.app import AutonomyRuntime  # noqa: E402
from bt_runtime.runtime.clock import run as run_loop  # noqa: E402
from bt_runtime.runtime.messages import Pose2D  # noqa: E402
from bt_runtime.runtime.recording import pipeline as pipeline_module  # noqa: E402
from bt_runtime.runtime.recording.bag import Rosbag2Bag  # noqa: E402
from bt_runtime.runtime.recording.channels import ChannelSet  # noqa: E402
from bt_runtime.runtime.recording.cli import Recording  # noqa: E402
from bt_runtime.runtime.recording.convert import ConvertState  # noqa: E402
from sim.driver import SimDriver  # noqa: E402
from sim.recording import recording_hooks  # noqa: E402
from tests.paths import ROOT  # noqa: E402


@pytest.fixture(scope="module")
def queued(tmp_path_factory) -> list[tuple]:
    """Every item a recording of the autonomy tree driving to yard_east queued in 8 robot s
    (every kind: sensors, map -> odom, commands, plan, tree log, diagnostics, events, truth)."""
    from bt_runtime.cli.registration import registrations

    items: list[tuple] = []
    drain = pipeline_module.RecordPipeline.drain

    def capture(self) -> None:
        items.extend(self.queue)
        drain(self)

    async def main() -> None:
        driver = SimDriver("apartment", "burger", seed=0)
        runtime = AutonomyRuntime(driver, register=registrations(argparse.Namespace(register=[], no_nodes=False)))
        runtime.load_tree(ROOT / "trees" / "autonomy.xml")
        goal = driver.sim.world.goal("yard_east")
        runtime.tree.root_blackboard.set("goal", Pose2D(goal.x, goal.y, 0.0))
        runtime.tree.root_blackboard.set("goal_status", "PENDING")
        recording = Recording(bag=tmp_path_factory.mktemp("run") / "bag").start(runtime, recording_hooks(driver))
        await runtime.start()
        import asyncio

        await asyncio.sleep(8.0)
        await runtime.stop()
        recording.stop()

    pipeline_module.RecordPipeline.drain = capture
    try:
        run_loop(main(), virtual=True)
    finally:
        pipeline_module.RecordPipeline.drain = drain
    return items


def _write(folder: Path, items: list[tuple], *, generic: bool) -> tuple[list, str, dict]:
    """The items through a pipeline in drains of 300, a segment closed after the third."""
    bag = Rosbag2Bag(folder, ChannelSet())
    pipeline = pipeline_module.RecordPipeline(bag=bag, state=ConvertState())
    if generic:
        pipeline._bag_writer = None
    pipeline.start(on_loop=True)
    for k, i in enumerate(range(0, len(items), 300)):
        pipeline.queue.extend(items[i:i + 300])
        pipeline.drain()
        if k == 2:
            bag.flush()
    pipeline.stop()
    assert pipeline.errors == 0
    segments = []
    for name in sorted(p.name for p in folder.glob("*.mcap")):
        with open(folder / name, "rb") as f:
            reader = make_reader(f)
            channels = [(c.id, c.topic, c.message_encoding, c.metadata, reader.get_summary().schemas[c.schema_id].name)
                        for c in reader.get_summary().channels.values()]
            messages = [(channel.topic, m.log_time, m.publish_time, m.sequence, m.data)
                        for _s, channel, m in reader.iter_messages(log_time_order=False)]
        segments.append((name, channels, messages))
    return segments, (folder / "metadata.yaml").read_text(), dict(pipeline.written)


def test_the_bag_writer_writes_the_generic_paths_bag(queued, tmp_path):
    kinds = {item[0] for item in queued}
    assert {"odom", "pose", "imu", "command", "odometry", "scan", "plan", "tree_log", "diagnostics",
            "battery", "map", "tf_static"} <= kinds
    generic = _write(tmp_path / "generic" / "bag", queued, generic=True)
    fused = _write(tmp_path / "fused" / "bag", queued, generic=False)
    assert len(generic[0]) == 2 and sum(len(s[2]) for s in generic[0]) > len(queued)
    for ours, theirs in zip(fused[0], generic[0], strict=True):
        assert ours[0] == theirs[0]
        assert ours[1] == theirs[1]  # channels: ids, topics, QoS metadata, schemas
        assert ours[2] == theirs[2]  # every message, in order
    assert fused[1] == generic[1]  # metadata.yaml: segments, spans, counts per topic
    assert fused[2] == generic[2]
