"""The same guarantees over DDS (skipped without cyclonedds): what a base subscribed to
``cmd_vel`` receives when the runtime's loop stalls for 2 s, and when a driving
``run --driver ros2`` gets SIGTERM. The "base" is a DDS participant of its own, timestamping
each sample on Cyclone's receive thread (so a blocked event loop does not skew it)."""

from __future__ import annotations

import asyncio
import os
import signal
import subprocess
import sys
import time

import pytest

pytest.importorskip("cyclonedds")

from bt_runtime.runtime.app import AutonomyRuntime  # noqa: E402
from bt_runtime.runtime.config import RuntimeConfig  # noqa: E402
from bt_runtime.runtime.ros2 import Ros2Config, Ros2Driver, dds, idl  # noqa: E402
from tests.helpers import dds_domain, tree_xml  # noqa: E402
from tests.paths import ROOT  # noqa: E402
from tests.safety.support import Received, StallLoop, register_fault_nodes  # noqa: E402


@pytest.fixture(autouse=True)
def loopback(monkeypatch):
    monkeypatch.setenv("CYCLONEDDS_URI", dds.loopback_config())


@pytest.fixture
def domain() -> int:
    return dds_domain()


class DdsBase:
    """A participant subscribed to ``cmd_vel``: every sample with its receive time."""

    def __init__(self, domain: int):
        self.node = dds.DdsNode(domain, loop=asyncio.get_running_loop())
        self.received: list[Received] = []
        self.node.subscription("cmd_vel", idl.Twist, dds.QosProfile(reliable=False, depth=10), self._on)

    def _on(self, samples: list, now: float) -> None:  # ``now``: loop.time() (= monotonic) at receipt
        self.received.extend(Received(now, now, float(m.linear.x), float(m.angular.z)) for m in samples)

    def close(self) -> None:
        self.node.close()


async def test_loop_stall_zero_reaches_the_base_over_dds(domain):
    base = DdsBase(domain)
    driver = Ros2Driver(Ros2Config(domain_id=domain))
    # no lidar on this bench: collision_monitor-style zones would (rightly) stop a robot without a scan
    runtime = AutonomyRuntime(driver, RuntimeConfig(safety_zones={"enabled": False}), realtime=True,
                              register=[register_fault_nodes])
    runtime.load_tree(tree_xml('<StallLoop after="60" seconds="2.0"/>'))
    StallLoop.stalled_at = None
    await runtime.start()
    try:
        while StallLoop.stalled_at is None or time.monotonic() < StallLoop.stalled_at + 2.3:
            await asyncio.sleep(0.05)
    finally:
        await runtime.stop()
        await asyncio.sleep(0.2)
        base.close()
    stalled = StallLoop.stalled_at
    assert any(r.wall < stalled and not r.is_zero for r in base.received), "driving before the stall"
    trip = runtime.watchdog.trips[0]
    zeros = [r for r in base.received if r.wall >= trip.refreshed and r.is_zero]
    latency = zeros[0].wall - trip.refreshed
    deadman = runtime.config.gate.deadman_timeout
    print(f"DDS stall-to-zero latency {latency * 1e3:.1f} ms (dead-man {deadman * 1e3:.0f} ms)")
    assert latency <= deadman + 0.020 and zeros[0].wall < stalled + 2.0
    assert base.received[-1].is_zero


async def test_sigterm_to_a_driving_ros2_run_ends_at_zero_on_the_wire(domain, tmp_path):
    base = DdsBase(domain)
    tree = tmp_path / "tree.xml"
    tree.write_text(tree_xml('<Drive linear="0.15"/>'), encoding="utf-8")
    # no Nav2 on this bench: without this the run first waits 5 s for lifecycle services nobody serves
    ros2_config = tmp_path / "ros2.yaml"
    ros2_config.write_text("lifecycle:\n  bringup:\n    enabled: false\n", encoding="utf-8")
    env = dict(os.environ, PYTHONPATH=str(ROOT), ROS_DOMAIN_ID=str(domain))
    proc = subprocess.Popen([sys.executable, "-m", "bt_runtime", "run", str(tree), "--driver", "ros2",
                             "--ros2-config", str(ros2_config), "--ready-timeout", "0.2", "--no-progress", "--collision-monitor", "off", "--register", "tests.safety.support:register_fault_nodes"],
                            cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 30
        while not any(r.linear > 0.1 for r in base.received):
            assert time.monotonic() < deadline and proc.poll() is None, "the run never drove"
            await asyncio.sleep(0.05)
        sent = time.monotonic()
        proc.send_signal(signal.SIGTERM)
        while proc.poll() is None:
            assert time.monotonic() < sent + 5.0, "no exit within 5 s of SIGTERM"
            await asyncio.sleep(0.05)
        took = time.monotonic() - sent
        await asyncio.sleep(0.2)
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.communicate()
        base.close()
    zero = next(r for r in base.received if r.wall >= sent and r.is_zero)
    print(f"DDS SIGTERM: zero on the wire {1e3 * (zero.wall - sent):.1f} ms after the signal, exit after {took:.2f} s")
    assert base.received[-1].is_zero, "the last cmd_vel is zero"
