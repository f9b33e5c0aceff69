"""Streams delivered at the tick (``deliver_at_tick``, ros2/dds.py): an at_tick reader has no
listener and is read by ``deliver_held()`` (the tick) while the node holds, by a 10 ms timer
otherwise; samples of listener readers wake the loop at once, and a tick delivers those still
waiting for their wake-up first, in arrival order; without ``ddspy_take`` an at_tick reader keeps
its listener and wakes the loop as any other; the gate's streams cannot be configured to wait."""

from __future__ import annotations

import asyncio

import pytest

pytest.importorskip("cyclonedds")

from bt_runtime.runtime.ros2 import dds, idl  # noqa: E402
from bt_runtime.runtime.ros2.config import Ros2Config  # noqa: E402
from tests.helpers import dds_domain  # noqa: E402


class FakeReader:
    def __init__(self, name: str, got: list):
        self.name, self.got = name, got

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


def test_listener_samples_wake_the_loop_at_once_and_a_tick_takes_those_still_waiting():
    async def main():
        loop = asyncio.get_running_loop()
        node = dds.DdsNode(dds_domain(), loop=loop)
        got: list = []
        pose, scan = FakeReader("pose", got), FakeReader("scan", got)
        try:
            node.set_hold(True)
            node.post(pose, [1], 0.0)
            assert node._wake_pending  # held or not, a listener's sample wakes the loop
            node.post(scan, [2], 0.01)
            node.deliver_held()  # a tick before the wake-up ran: both, in arrival order
            assert got == [("pose", 1, 0.0), ("scan", 2, 0.01)]
            await asyncio.sleep(0.01)  # the wake-up finds nothing left
            assert got == [("pose", 1, 0.0), ("scan", 2, 0.01)] and not node._wake_pending
            node.post(scan, [3], 0.02)
            await asyncio.sleep(0.01)
            assert got[-1] == ("scan", 3, 0.02)
        finally:
            node.close()

    run(main)


def test_without_ddspy_take_an_at_tick_reader_keeps_its_listener(monkeypatch):
    monkeypatch.setattr(dds, "ddspy_take", None)

    async def main():
        node = dds.DdsNode(dds_domain(), loop=asyncio.get_running_loop())
        try:
            reader = node.subscription("imu", idl.Imu, dds.SENSOR_DATA, lambda samples, now: None, at_tick=True)
            assert not reader.polled and reader._listener is not None and node._polled == []
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
