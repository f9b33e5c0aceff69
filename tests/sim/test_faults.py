"""Faults: each one's effect, scheduling, the fault log."""

from __future__ import annotations

import asyncio
import math

import numpy as np
import pytest
import structlog
from pydantic import ValidationError

from bt_runtime.runtime.messages import ComponentState
from sim import Simulator
from sim.faults import Crash, InvisibleObstacle, Push, RestartPolicy, parse_fault
from sim.testing import Recorder, run_virtual
from sim.world import world_from_dict

ALL = ["scan", "imu", "odom", "pose", "battery", "bumper", "component_state"]


def open_world(spawn=(0.0, 0.0, 0.0), extra=()):
    return world_from_dict({
        "name": "open", "bounds": {"xmin": -10, "ymin": -10, "xmax": 10, "ymax": 10},
        "spawn": {"x": spawn[0], "y": spawn[1], "yaw": spawn[2]},
        "goals": {"target": {"x": 3.0, "y": 0.0}},
        "obstacles": [{"type": "polygon", "name": "wall", "points": [[3.3, -5], [3.5, -5], [3.5, 5], [3.3, 5]]},
                      *extra]})


async def drive(sim, v, w, duration, period=0.1):
    loop = asyncio.get_running_loop()
    end = loop.time() + duration
    while loop.time() < end - 1e-9:
        sim.command(v, w)
        await asyncio.sleep(period)


def run_sim(sim, body, topics=ALL):
    out = {}

    async def main():
        rec = Recorder(sim, topics)
        await sim.start()
        out["result"] = await body(sim)
        await sim.stop()
        return rec

    rec = run_virtual(main)
    return rec, out.get("result")


def test_crash_stops_messages_and_restart_brings_them_back_after_the_delay():
    sim = Simulator(open_world(), "burger", seed=0, restart_delays={"lidar": 1.5})

    async def body(s):
        await asyncio.sleep(1.0)
        s.faults.crash("lidar")
        assert s.component_state("lidar") is ComponentState.INACTIVE
        await asyncio.sleep(2.0)
        task = s.faults.restart("lidar")
        await asyncio.sleep(0.5)
        assert s.component_state("lidar") is ComponentState.STARTING
        ok = await task
        t_up = asyncio.get_running_loop().time()
        await asyncio.sleep(1.0)
        return ok, t_up

    rec, (ok, t_up) = run_sim(sim, body)
    assert ok and t_up == pytest.approx(4.5)
    stamps = np.array(rec.stamps("scan"))
    assert not np.any((stamps > 1.0 + 1e-9) & (stamps < 4.5 - 1e-9))
    # back on its 5 Hz grid once up: 4.6, 4.8, ... 5.4
    assert np.allclose(stamps[stamps > 4.5], [4.6, 4.8, 5.0, 5.2, 5.4])
    assert len(stamps[stamps <= 1.0]) in (4, 5)
    states = [(c.name, c.state.value) for c in rec["component_state"]]
    assert states == [("lidar", "inactive"), ("lidar", "starting"), ("lidar", "active")]
    # other sensors were not affected
    assert len(rec["imu"]) in (274, 275)
    kinds = [r.kind for r in sim.faults.log]
    assert kinds == ["crash", "restart", "restart_result"] and sim.faults.log[-1].details["ok"]
    assert sim.faults.log[0].t == pytest.approx(1.0)


def test_fail_next_n_restarts():
    sim = Simulator(open_world(), "burger", seed=0, restart_delay=0.2)

    async def body(s):
        s.faults.set_restart_policy("imu", fail_next=2, delay=0.3)
        s.faults.crash("imu")
        results = [await s.restart("imu") for _ in range(3)]
        await asyncio.sleep(0.2)
        return results

    rec, results = run_sim(sim, body)
    assert results == [False, False, True]
    assert sim.component("imu").fail_next == 0
    stamps = rec.stamps("imu")
    assert stamps and stamps[0] >= 0.9 - 1e-9 and stamps[-1] > 1.05


def test_restart_of_a_running_component_and_concurrent_restarts_join():
    sim = Simulator(open_world(), "burger", seed=0, restart_delay=0.5)

    async def body(s):
        await asyncio.sleep(0.3)
        t1 = s.component("odom").restart()
        t2 = s.component("odom").restart()
        assert t1 is t2
        return await t1

    rec, ok = run_sim(sim, body)
    stamps = np.array(rec.stamps("odom"))
    assert ok and not np.any((stamps > 0.3 + 1e-9) & (stamps < 0.8 - 1e-9))


def test_crash_during_restart_fails_it():
    sim = Simulator(open_world(), "burger", seed=0, restart_delay=1.0)

    async def body(s):
        task = s.component("lidar").restart()
        await asyncio.sleep(0.5)
        s.crash("lidar")
        await asyncio.sleep(0)
        return await task

    rec, ok = run_sim(sim, body)
    assert ok is False and sim.component_state("lidar") is ComponentState.INACTIVE


def test_stall_silent_and_stale():
    sim = Simulator(open_world(), "burger", seed=0)

    async def body(s):
        await asyncio.sleep(1.0)
        s.faults.stall("imu", 1.0, mode="silent")
        s.faults.stall("odom", 1.0, mode="stale")
        await asyncio.sleep(2.0)

    rec, _ = run_sim(sim, body)
    imu = np.array(rec.stamps("imu"))
    assert not np.any((imu > 1.0 + 1e-9) & (imu < 2.0 - 1e-9)) and imu[-1] > 2.9
    assert sim.component_state("imu") is ComponentState.ACTIVE
    odom = rec["odom"]
    during = [m for m in odom if m is not odom[-1] and m.stamp <= 1.0 + 1e-9][-51:]
    assert len({id(m) for m in during}) == 1 or len({m.stamp for m in during[1:]}) == 1
    assert len(odom) >= 149  # it kept publishing: the same old message again and again
    assert odom[-1].stamp > 2.9


def test_corrupt_nan_and_garbage():
    sim = Simulator(open_world(), "burger", seed=0)

    async def body(s):
        s.faults.corrupt("lidar", 0.5, mode="nan")
        s.faults.corrupt("imu", 0.5, mode="garbage")
        s.faults.corrupt("battery", 2.0, mode="nan")
        await asyncio.sleep(1.05)

    rec, _ = run_sim(sim, body)
    scans = rec["scan"]
    assert np.all(np.isnan(scans[0].ranges)) and np.all(np.isnan(scans[1].ranges))
    assert np.isfinite(scans[-1].ranges).any() and not np.isnan(scans[-1].ranges).any()
    bad = [m for m in rec["imu"] if m.stamp < 0.5]
    assert max(abs(m.accel_x) for m in bad) > 10
    assert math.isnan(rec["battery"][0].percentage)


def test_noise_burst():
    sim = Simulator(open_world(), "burger", seed=0)

    async def body(s):
        s.faults.noise_burst("lidar", 1.0, factor=20)
        await asyncio.sleep(2.0)

    rec, _ = run_sim(sim, body)
    front = np.array([m.ranges[0] for m in rec["scan"]])
    noisy, calm = front[:4], front[5:]
    assert np.std(noisy) > 5 * np.std(calm)


def test_wheel_slip_makes_odometry_over_read():
    sim = Simulator(open_world(spawn=(-3.0, 0.0, 0.0)), "burger", seed=0)

    async def body(s):
        s.faults.wheel_slip(1.3, duration=3.0)
        await drive(s, 0.2, 0.0, 3.0)
        x_odom = s.odom.x
        await drive(s, 0.2, 0.0, 2.0)
        return x_odom

    rec, x_at_3 = run_sim(sim, body)
    truth_at_3 = 0.2 * 3.0 - 0.5 * 0.2 * 0.2  # accel from rest
    assert x_at_3 == pytest.approx(1.3 * truth_at_3, rel=0.03)
    assert sim.odom.x - x_at_3 == pytest.approx(0.4, rel=0.03)  # back to normal


def test_push_makes_contact_and_imu_spike():
    sim = Simulator(open_world(), "burger", seed=0)

    async def body(s):
        await asyncio.sleep(1.0)
        s.faults.apply(Push(impulse=0.4, direction=math.pi / 2))  # shoved to its left
        await asyncio.sleep(1.0)

    rec, _ = run_sim(sim, body)
    contacts = [c for c in rec["bumper"] if c.in_contact]
    assert contacts and contacts[0].stamp == pytest.approx(1.0, abs=0.011)
    names = [sim.profile.bumper.segments[i].name for i in contacts[0].segments]
    assert names == ["right"]  # hit from its right
    assert rec["bumper"][-1].in_contact is False
    imu = rec["imu"]
    spike = max(abs(m.accel_y) for m in imu if 1.0 <= m.stamp < 1.2)
    calm = max(abs(m.accel_y) for m in imu if m.stamp < 0.9)
    assert spike > 5.0 and calm < 0.1
    assert 0.005 < sim.pose.y < 0.1  # it moved a little to its left, then traction held it
    assert sim.odom.x == 0.0 and sim.odom.y == 0.0  # the wheels did not turn


def test_invisible_obstacle_blocks_the_body_not_the_lidar():
    sim = Simulator(open_world(spawn=(0.0, 0.0, 0.0)), "burger", seed=0)

    async def body(s):
        await asyncio.sleep(0.5)
        before = s.lidar.true_ranges().copy()
        name = s.faults.invisible_obstacle(ahead=0.3)
        after = s.lidar.true_ranges()
        await drive(s, 0.2, 0.0, 4.0)
        return name, before, after

    rec, (name, before, after) = run_sim(sim, body)
    assert np.array_equal(before, after)  # the lidar does not see it
    # the body stops at it: near face at radius + 0.3 ahead of the spawn pose
    assert sim.pose.x == pytest.approx(0.3, abs=0.01)
    assert sim.events_of("collision")[0].data["obstacle"] == f"dyn:{name}"
    assert any(c.in_contact for c in rec["bumper"])
    # the lidar still reads the wall at 3.3 m behind it
    assert rec["scan"][-1].ranges[0] == pytest.approx(3.3 - sim.pose.x + 0.032, abs=0.05)
    ob = sim.dynamic_obstacles[name]
    assert ob.blocks_body and not ob.blocks_lidar


def test_invisible_obstacle_at_a_pose_and_validation():
    sim = Simulator(open_world(), "burger", seed=0)
    name = sim.faults.invisible_obstacle(x=1.0, y=1.0, radius=0.2, name="rock")
    assert name == "rock" and sim.dynamic_obstacles["rock"].distance(1.0, 1.0) < 0
    with pytest.raises(ValidationError):
        InvisibleObstacle(x=1.0)
    with pytest.raises(ValueError, match="exists already"):
        sim.faults.invisible_obstacle(x=2.0, y=2.0, name="rock")


def test_block_corridor_blocks_body_and_lidar_until_removed():
    sim = Simulator(open_world(spawn=(0.0, 0.0, 0.0)), "burger", seed=0)

    async def body(s):
        name = s.faults.block_corridor((1.0, -1.0), (1.0, 1.0), thickness=0.1)
        await drive(s, 0.2, 0.0, 6.0)
        x_blocked = s.pose.x
        scan_blocked = s.bus.latest("scan").ranges[0]
        s.faults.remove_obstacle(name)
        await drive(s, 0.2, 0.0, 3.0)
        return x_blocked, scan_blocked

    rec, (x_blocked, scan_blocked) = run_sim(sim, body)
    assert x_blocked == pytest.approx(0.95 - 0.105, abs=0.01)
    assert scan_blocked == pytest.approx(0.95 - x_blocked + 0.032, abs=0.04)
    assert sim.pose.x > 1.2
    kinds = [r.kind for r in sim.faults.log]
    assert kinds == ["block_corridor", "remove_obstacle"]


def test_goal_inside_an_obstacle():
    sim = Simulator(open_world(), "burger", seed=0)
    name = sim.faults.obstacle_at(goal="target", radius=0.4)
    ob = sim.dynamic_obstacles[name]
    assert ob.distance(3.0, 0.0) < 0 and ob.blocks_lidar and ob.blocks_body
    raster = sim.rasterize(0.05, layer="body", dynamic=True)
    assert raster.data[raster.world_to_cell(3.0, 0.0)] == 1
    assert sim.rasterize(0.05, layer="body").data[raster.world_to_cell(2.8, 0.0)] == 0


def test_battery_faults():
    sim = Simulator(open_world(), "burger", seed=0)

    async def body(s):
        s.faults.set_battery(40.0)
        await asyncio.sleep(1.05)
        s.faults.drain_battery(10.0)
        await asyncio.sleep(1.0)
        s.faults.drain_battery(power=1000.0, duration=2.0)
        soc0 = s.battery.soc
        await asyncio.sleep(2.0)
        soc1 = s.battery.soc
        await asyncio.sleep(2.0)
        return soc0, soc1

    rec, (soc0, soc1) = run_sim(sim, body, ["battery"])
    percent = [m.percentage for m in rec["battery"]]
    assert 39.5 < percent[0] < 40.5 and 29.5 < percent[1] < 30.5  # measured, with noise
    idle = sim.battery.idle_power_w
    assert soc0 - soc1 == pytest.approx((1000.0 + idle) / 11.0 * 2 / 3600 / 1.8 * 100, rel=0.05)
    assert sim.battery.power == pytest.approx(idle)  # the drain ended


def test_schedule_and_fault_specs():
    sim = Simulator(open_world(), "burger", seed=0)
    sim.faults.schedule(1.0, {"kind": "crash", "component": "lidar"})
    sim.faults.schedule(2.0, Crash(component="imu"))
    sim.faults.schedule(2.5, RestartPolicy(component="lidar", delay=0.2))
    sim.faults.schedule(3.0, {"kind": "restart", "component": "lidar"})
    with pytest.raises(ValidationError):
        parse_fault({"kind": "stall", "component": "imu", "duration": -1})
    with pytest.raises(ValidationError):
        parse_fault({"kind": "explode"})

    async def body(s):
        await asyncio.sleep(4.0)

    with structlog.testing.capture_logs() as logs:
        rec, _ = run_sim(sim, body)
    log = sim.faults.log
    assert [(r.kind, round(r.t, 6)) for r in log] == [
        ("crash", 1.0), ("crash", 2.0), ("restart_policy", 2.5), ("restart", 3.0), ("restart_result", 3.2)]
    stamps = np.array(rec.stamps("scan"))
    assert not np.any((stamps > 1.0 + 1e-9) & (stamps < 3.2 - 1e-9)) and stamps[-1] > 3.5
    assert sim.component_state("imu") is ComponentState.INACTIVE
    faults_logged = [e for e in logs if e.get("event") == "fault"]
    assert [e["fault"] for e in faults_logged] == ["crash", "crash", "restart_policy", "restart"]
    assert faults_logged[0]["sim_time"] == 1.0
    assert [e.data["fault"] for e in sim.events_of("fault")] == ["crash", "crash", "restart_policy", "restart"]


def test_unknown_component():
    sim = Simulator(open_world(), "burger", seed=0)
    with pytest.raises(KeyError, match="components"):
        sim.faults.crash("sonar")
