"""The data backup: bounded ring buffers and their queries."""

from __future__ import annotations

import asyncio

from bt_runtime.runtime.backup import RingBuffer
from bt_runtime.runtime.config import BackupConfig, RuntimeConfig
from bt_runtime.runtime.messages import Twist


def test_ring_buffer_queries_and_bound():
    rb = RingBuffer(5)
    for i in range(12):
        rb.append(float(i), i)
    assert len(rb) == 5 and rb.total == 12
    assert rb.latest() == 11 and rb.latest_stamped() == (11.0, 11)
    assert rb.last_n(3) == [9, 10, 11] and rb.last_n(50) == [7, 8, 9, 10, 11]
    assert rb.since(9.0) == [9, 10, 11] and rb.since(100.0) == []
    assert rb.window(8.0, 10.0) == [8, 9]
    assert RingBuffer(3).latest() is None


async def test_memory_stays_bounded_over_a_long_run(make_runtime):
    sizes = {"scan": 10, "imu": 20, "odom": 20, "pose": 20, "bumper": 20, "battery": 5, "cmd_vel": 30,
             "nav_cmd_vel": 10}
    rt = make_runtime(config=RuntimeConfig(backup=BackupConfig(sizes=sizes)))
    await rt.start()
    await asyncio.sleep(5.0)
    first = rt.backup.memory_bytes()
    await asyncio.sleep(60.0)
    second = rt.backup.memory_bytes()
    for stream, size in sizes.items():
        buf = rt.backup.buffers.get(stream)
        if buf is not None:
            assert len(buf) <= size
    assert rt.backup.buffers["imu"].total > 3000  # many more messages than kept
    assert second <= first * 1.05
    await rt.stop()


async def test_queries_the_tree_uses(make_runtime):
    rt = make_runtime()
    await rt.start()
    gate, backup = rt.gate, rt.backup
    await asyncio.sleep(1.5)
    t0 = rt.clock()
    for _ in range(50):
        gate.set_tree_command(0.1, 0.05)
        await asyncio.sleep(0.01)
    gate.clear_tree_command()
    motion = backup.recent_motion(0.6)
    # the gate ramps up to the command at the robot's acceleration limits, then holds it
    assert motion and motion[-1][1] == Twist(0.1, 0.05)
    assert all(0 < c.linear <= 0.1 and 0 < c.angular <= 0.05 for _, c in motion)
    assert all(t >= t0 for t, _ in backup.commands_since(t0))
    scans = backup.since("scan", rt.clock() - 1.0)
    assert 4 <= len(scans) <= 6
    assert backup.latest("pose") is not None and backup.age("pose") < 0.2
    await asyncio.sleep(1.0)
    assert backup.last_good_pose is not None
    await rt.stop()
