"""Streams delivered at the tick (``deliver_at_tick``, ros2/dds.py): while the node holds, a
held reader's samples wait for ``deliver_held()`` without waking the loop; any other sample
still wakes it at once and takes the waiting ones along in arrival order; a held sample never
waits longer than ``HOLD_MAX``; the gate's streams cannot be configured to wait."""

from __future__ import annotations

import asyncio

import pytest

pytest.importorskip("cyclonedds")

from bt_runtime.runtime.ros2 import dds  # noqa: E402
from bt_runtime.runtime.ros2.config import Ros2Config  # noqa: E402
from tests.helpers import dds_domain  # noqa: E402


class FakeReader:
    def __init__(self, name: str, got: list, held: bool):
        self.name, self.got, self.held = name, got, held

    def _deliver(self, samples: list, now: float) -> None:
        self.got.extend((self.name, s, now) for s in samples)


@pytest.fixture(autouse=True)
def loopback(monkeypatch):
    monkeypatch.setenv("CYCLONEDDS_URI", dds.loopback_config())


def run(main):
    loop = asyncio.new_event_loop()
    try:
        return loop.run_until_complete(main())
    finally:
        loop.close()


def test_held_samples_wait_for_the_tick_and_others_wake_the_loop_at_once():
    async def main():
        loop = asyncio.get_running_loop()
        node = dds.DdsNode(dds_domain(), loop=loop)
        got: list = []
        imu, scan = FakeReader("imu", got, held=True), FakeReader("scan", got, held=False)
        try:
            node.set_hold(True)
            node.post(imu, [1], 0.0)
            node.post(imu, [2], 0.01)
            assert not node._wake_pending  # no wake-up for held samples
            await asyncio.sleep(0.01)
            assert got == []
            node.deliver_held()  # the tick
            assert got == [("imu", 1, 0.0), ("imu", 2, 0.01)]
            got.clear()
            node.post(imu, [3], 0.02)
            node.post(scan, [4], 0.021)  # the safety path's stream wakes the loop
            assert node._wake_pending
            await asyncio.sleep(0.01)
            assert got == [("imu", 3, 0.02), ("scan", 4, 0.021)]  # arrival order, nothing left waiting
            got.clear()
            node.post(imu, [5], 1.0)
            node.post(imu, [6], 1.0 + dds.HOLD_MAX)  # the tick did not come: the oldest waited long enough
            assert node._wake_pending
            await asyncio.sleep(0.01)
            assert got == [("imu", 5, 1.0), ("imu", 6, 1.0 + dds.HOLD_MAX)]
            got.clear()
            node.post(imu, [7], 2.0)
            node.set_hold(False)  # the tick loop stopped: what waits is delivered, nothing waits any more
            await asyncio.sleep(0.01)
            assert got == [("imu", 7, 2.0)]
            node.post(imu, [8], 2.1)
            assert node._wake_pending
        finally:
            node.close()

    run(main)


def test_without_hold_a_held_reader_wakes_the_loop_as_any_other():
    async def main():
        node = dds.DdsNode(dds_domain(), loop=asyncio.get_running_loop())
        got: list = []
        try:
            node.post(FakeReader("odom", got, held=True), [1], 0.0)
            assert node._wake_pending
            await asyncio.sleep(0.01)
            assert got == [("odom", 1, 0.0)]
        finally:
            node.close()

    run(main)


@pytest.mark.parametrize("stream", ["scan", "bumper", "nav_cmd_vel", "cmd_vel_input/teleop", "lock/estop"])
def test_the_gates_streams_cannot_wait_for_the_tick(stream):
    with pytest.raises(ValueError, match="must wake the loop at once"):
        Ros2Config(deliver_at_tick=["imu", stream])


def test_imu_and_odom_wait_for_the_tick_by_default():
    assert Ros2Config().deliver_at_tick == ["imu", "odom"]


def test_an_at_tick_reader_is_read_by_the_tick_while_held_and_by_a_timer_otherwise(loopback):
    """The real reader: no listener; while the node holds, nothing arrives until the tick's
    deliver_held(), and each sample is stamped between the previous read and this one; without
    hold, a timer reads it every POLL_PERIOD."""
    from bt_runtime.runtime.ros2 import idl

    if dds.ddspy_take is None:
        pytest.skip("this Cyclone binding has no ddspy_take: at_tick readers keep their listener")
    qos = dds.QosProfile(reliable=True, depth=100)

    async def main():
        loop = asyncio.get_running_loop()
        node = dds.DdsNode(dds_domain(), loop=loop)
        got: list = []
        try:
            reader = node.subscription("at_tick_imu", idl.Imu, qos, lambda samples, now: got.extend(
                (s.header.stamp.sec, now) for s in samples), at_tick=True)
            assert reader.polled
            writer = node.publisher("at_tick_imu", idl.Imu, qos)
            deadline = loop.time() + 10
            while not writer.get_matched_subscriptions():
                assert loop.time() < deadline, "reader and writer did not match"
                await asyncio.sleep(0.01)
            node.set_hold(True)
            node.deliver_held()
            since = loop.time()
            for i in range(5):
                writer.write(idl.Imu(header=idl.Header(stamp=idl.Time(i, 0), frame_id="imu")))
            await asyncio.sleep(0.1)
            assert got == []  # held: no listener, no timer
            node.deliver_held()
            now = loop.time()
            assert [sec for sec, _ in got] == [0, 1, 2, 3, 4]
            assert all(since <= stamp <= now for _, stamp in got)
            got.clear()
            node.set_hold(False)
            writer.write(idl.Imu(header=idl.Header(stamp=idl.Time(9, 0), frame_id="imu")))
            deadline = loop.time() + 2
            while not got and loop.time() < deadline:
                await asyncio.sleep(0.005)
            assert [sec for sec, _ in got] == [9]
        finally:
            node.close()

    run(main)
