"""The receive path's hand-off (ros2/dds.py): samples that arrive while the loop is busy reach
their readers' callbacks complete and in arrival order, in one pass of the loop (one wake-up),
stamped with their receive time; samples posted after a closed loop do not raise into Cyclone."""

from __future__ import annotations

import asyncio
import time

import pytest

pytest.importorskip("cyclonedds")

from bt_runtime.runtime import clock  # noqa: E402
from bt_runtime.runtime.ros2 import dds, idl  # noqa: E402
from tests.helpers import dds_domain  # noqa: E402

QOS = dds.QosProfile(reliable=True, depth=100)


@pytest.fixture(autouse=True)
def loopback(monkeypatch):
    monkeypatch.setenv("CYCLONEDDS_URI", dds.loopback_config())


def test_a_burst_while_the_loop_is_busy_is_delivered_in_order_in_one_pass():
    domain = dds_domain()

    async def main():
        loop = asyncio.get_running_loop()
        node = dds.DdsNode(domain, loop=loop)
        got: list[tuple[str, int, float]] = []
        for topic in ("inbox_a", "inbox_b"):
            node.subscription(topic, idl.Imu, QOS, lambda samples, now, topic=topic: got.extend(
                (topic, s.header.stamp.sec, now) for s in samples))
        writers = {topic: node.publisher(topic, idl.Imu, QOS) for topic in ("inbox_a", "inbox_b")}
        deadline = loop.time() + 10
        while not all(w.get_matched_subscriptions() for w in writers.values()):
            assert loop.time() < deadline, "reader and writer did not match"
            await asyncio.sleep(0.01)
        await asyncio.sleep(0.05)
        wakeups = node.wakeups
        sent = []
        before = loop.time()
        for i in range(40):  # the loop is busy in this callback throughout the burst
            topic = "inbox_a" if i % 3 else "inbox_b"
            writers[topic].write(idl.Imu(header=idl.Header(stamp=idl.Time(i, 0), frame_id="imu")))
            sent.append((topic, i))
        time.sleep(0.2)  # receive threads post everything meanwhile
        after = loop.time()
        deadline = loop.time() + 5
        while len(got) < len(sent) and loop.time() < deadline:
            await asyncio.sleep(0.01)
        node.close()
        return sent, got, node.wakeups - wakeups, before, after

    sent, got, wakeups, before, after = clock.run(main, virtual=False)
    assert [(topic, i) for topic, i, _ in got] == sent
    assert all(before <= now <= after for _, _, now in got)  # stamped on arrival, not on delivery
    assert wakeups <= 2  # one pass for the burst (two if the first sample raced the others)


def test_posting_to_a_closed_loop_raises_runtime_error_and_clears_the_wake_up():
    domain = dds_domain()
    loop = asyncio.new_event_loop()
    node = dds.DdsNode(domain, loop=loop)
    try:
        loop.close()
        with pytest.raises(RuntimeError):
            node.post(None, [1], 0.0)  # type: ignore[arg-type]
        assert not node._wake_pending
    finally:
        node.close()
