"""Same seed, world and faults -> bit-identical runs on the VirtualTimeLoop."""

from __future__ import annotations

import asyncio
import math

import numpy as np

from sim import Simulator
from sim.faults import InvisibleObstacle, NoiseBurst, Push, WheelSlip
from sim.scripted import WaypointFollower
from sim.testing import Recorder, run_virtual
from tests.paths import ROOT


def one_run(seed: int, world: str = "apartment"):
    sim = Simulator(world, "burger", seed=seed)
    sim.faults.schedule(2.0, Push(impulse=0.3, direction=math.pi / 2))
    sim.faults.schedule(3.0, WheelSlip(left=1.1, right=0.95, duration=3.0))
    sim.faults.schedule(4.0, {"kind": "crash", "component": "lidar"})
    sim.faults.schedule(5.0, {"kind": "restart", "component": "lidar"})
    sim.faults.schedule(6.0, NoiseBurst(component="imu", duration=1.0))
    sim.faults.schedule(7.0, InvisibleObstacle(ahead=0.4))
    waypoints = [(0.0, -2.0), (0.5, -3.0), (-1.0, -3.5)]

    async def main():
        rec = Recorder(sim, ["scan", "imu", "odom", "pose", "bumper", "battery"])
        follower = WaypointFollower(sim, waypoints)
        await sim.start()
        await follower.run(timeout=12.0)
        await sim.stop()
        return rec

    rec = run_virtual(main)
    return sim, rec


def flat(rec, topic):
    out = []
    for m in rec[topic]:
        if topic == "scan":
            out.append(np.concatenate([[m.stamp], m.ranges]))
        elif topic == "imu":
            out.append([m.stamp, m.yaw_rate, m.accel_x, m.accel_y, m.yaw])
        elif topic == "odom":
            out.append([m.stamp, m.pose.x, m.pose.y, m.pose.yaw, m.twist.linear, m.twist.angular])
        elif topic == "pose":
            out.append([m.stamp, m.pose.x, m.pose.y, m.pose.yaw, m.covariance])
    return np.array(out, dtype=float)


def test_same_seed_is_bit_identical():
    a, ra = one_run(11)
    b, rb = one_run(11)
    ta, tb = a.trajectory(), b.trajectory()
    assert len(ta) > 100
    assert np.array_equal(ta, tb)
    for topic in ("scan", "imu", "odom", "pose"):
        fa, fb = flat(ra, topic), flat(rb, topic)
        assert fa.shape == fb.shape and np.array_equal(fa, fb, equal_nan=True), topic
    assert [(e.t, e.kind) for e in a.events] == [(e.t, e.kind) for e in b.events]
    assert [(r.t, r.kind) for r in a.faults.log] == [(r.t, r.kind) for r in b.faults.log]
    assert a.battery.soc == b.battery.soc


def test_different_seed_differs():
    a, ra = one_run(11)
    c, rc = one_run(12)
    assert not np.array_equal(flat(ra, "scan")[:, 1:], flat(rc, "scan")[:, 1:])


def test_the_run_did_what_the_faults_say():
    sim, rec = one_run(11)
    kinds = [r.kind for r in sim.faults.log if r.kind != "restart_result"]
    assert kinds[:6] == ["push", "wheel_slip", "crash", "restart", "noise_burst", "invisible_obstacle"]
    assert any(c.in_contact for c in rec["bumper"])
    assert sim.dynamic_obstacles


def test_loop_time_is_the_only_clock():
    """Nothing in sim reads the wall clock for simulation time (perf_counter is accounting)."""
    import re

    root = ROOT / "sim"
    for path in root.rglob("*.py"):
        if "nav" in path.parts:
            continue
        text = path.read_text()
        assert not re.search(r"time\.time\(|time\.monotonic\(|datetime\.now\(", text), path


def test_runs_on_a_plain_asyncio_loop_too():
    """Real time (briefly): the physics task keeps up and stamps come from the loop clock."""
    sim = Simulator("round_obstacles", "burger", seed=0)

    async def main():
        loop = asyncio.get_running_loop()
        rec = Recorder(sim, ["imu"])
        t0 = loop.time()
        await sim.start()
        await asyncio.sleep(0.3)
        await sim.stop()
        return rec, t0

    rec, t0 = asyncio.run(main())
    stamps = rec.stamps("imu")
    assert 10 <= len(stamps) <= 16 and stamps[0] > t0
