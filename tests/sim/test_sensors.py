"""Sensor drivers: rates, stamps, IMU, odometry, localization, battery, determinism of streams."""

from __future__ import annotations

import asyncio
import math

import numpy as np
import pytest

from bt_runtime.runtime.messages import ComponentState
from sim import Simulator
from sim.robot import load_profile
from sim.sensors import compose, inverse, soc_after
from sim.testing import Recorder, run_virtual
from sim.world import world_from_dict

TOPICS = ["scan", "imu", "odom", "pose", "battery", "bumper", "ground_truth", "cmd_vel_out"]


def open_world(spawn=(0.0, 0.0, 0.0), dock=None):
    data = {
        "name": "open", "bounds": {"xmin": -10, "ymin": -10, "xmax": 10, "ymax": 10},
        "spawn": {"x": spawn[0], "y": spawn[1], "yaw": spawn[2]},
        "obstacles": [{"type": "polygon", "points": [[5, -5], [5.2, -5], [5.2, 5], [5, 5]]}],
    }
    if dock:
        data["dock"] = {"x": dock[0], "y": dock[1], "yaw": 0.0}
    return world_from_dict(data)


def room_world(spawn=(0.0, 0.0, 0.0)):
    """A 7 x 7 m room: walls within the lidar's range from anywhere inside, for scan matching."""
    walls = [[[-3.5, -3.5], [3.5, -3.5]], [[3.5, -3.5], [3.5, 3.5]], [[3.5, 3.5], [-3.5, 3.5]],
             [[-3.5, 3.5], [-3.5, -3.5]]]
    return world_from_dict({
        "name": "room", "bounds": {"xmin": -4, "ymin": -4, "xmax": 4, "ymax": 4},
        "spawn": {"x": spawn[0], "y": spawn[1], "yaw": spawn[2]},
        "obstacles": [{"type": "segment", "a": a, "b": b, "thickness": 0.1} for a, b in walls]})


async def drive(sim, v, w, duration, period=0.1):
    loop = asyncio.get_running_loop()
    end = loop.time() + duration
    while loop.time() < end - 1e-9:
        sim.command(v, w)
        await asyncio.sleep(period)


def run_sim(sim, body, topics=TOPICS):
    async def main():
        rec = Recorder(sim, topics)
        await sim.start()
        await body(sim)
        await sim.stop()
        return rec

    return run_virtual(main)


def test_rates_and_stamps():
    sim = Simulator(open_world(), "burger", seed=0)
    rec = run_sim(sim, lambda s: asyncio.sleep(2.0 + 1e-6))
    counts = {t: len(rec[t]) for t in TOPICS}
    assert counts == {"scan": 10, "imu": 100, "odom": 100, "pose": 20, "battery": 2, "bumper": 20,
                      "ground_truth": 21, "cmd_vel_out": 0}
    assert np.allclose(np.diff(rec.stamps("scan")), 0.2)
    assert np.allclose(np.diff(rec.stamps("imu")), 0.02)
    assert rec.stamps("scan")[0] == pytest.approx(0.2)
    info = {c.name: c for c in sim.components()}
    assert set(info) == {"lidar", "imu", "odom", "bumper", "battery", "localization"}
    assert info["lidar"].expected_rate_hz == 5 and info["lidar"].streams == ("scan",)
    assert all(c.state is ComponentState.ACTIVE for c in info.values())


def test_rosbot_rates():
    sim = Simulator(open_world(), "rosbot2", seed=0)
    rec = run_sim(sim, lambda s: asyncio.sleep(1.0 + 1e-6), ["scan", "odom"])
    assert len(rec["scan"]) == 10 and len(rec["odom"]) == 20
    assert len(rec["scan"][0].ranges) == 400 and rec["scan"][0].range_max == 8.0


def test_imu_and_odometry_while_turning_and_driving():
    sim = Simulator(open_world(), "burger", seed=1)

    async def body(s):
        await drive(s, 0.2, 0.0, 5.0)
        await drive(s, 0.0, 1.0, 2.0)

    rec = run_sim(sim, body)
    imu = rec["imu"]
    turning = [m for m in imu if 5.5 < m.stamp < 7.0]
    assert np.mean([m.yaw_rate for m in turning]) == pytest.approx(1.0, abs=0.01)
    assert abs(imu[-1].yaw - sim.pose.yaw) < 0.03
    cruising = [m for m in imu if 1.0 < m.stamp < 4.9]
    assert abs(np.mean([m.accel_x for m in cruising])) < 0.01
    starting = [m for m in imu if m.stamp < 0.15]
    assert max(m.accel_x for m in starting) == pytest.approx(1.0, abs=0.1)  # the accel limit
    # centripetal acceleration would show in accel_y: none while turning in place
    odom = rec["odom"][-1]
    x_true = sim.pose.x - sim.spawn.x
    assert odom.pose.x == pytest.approx(x_true, rel=0.02)
    assert abs(odom.pose.y) < 0.05


def test_odometry_zero_while_standing():
    sim = Simulator(open_world(), "burger", seed=1)
    rec = run_sim(sim, lambda s: asyncio.sleep(1.0), ["odom"])
    assert all(m.pose == rec["odom"][0].pose for m in rec["odom"])
    assert rec["odom"][0].pose.x == 0.0


def _pose_errors(rec) -> list[tuple[float, float]]:
    truth = {round(m.stamp, 3): m.pose for m in rec["ground_truth"]}
    return [(m.stamp, m.pose.distance_to(truth[round(m.stamp, 3)])) for m in rec["pose"]
            if round(m.stamp, 3) in truth]


def test_localization_tracks_truth_and_needs_odometry():
    sim = Simulator(room_world(spawn=(1.0, 0.0, 0.5)), "burger", seed=2)
    odom_after: list = []

    async def body(s):
        await drive(s, 0.2, 0.3, 3.0)
        s.crash("odom")
        await drive(s, 0.2, 0.3, 2.0)
        await s.restart("odom")
        odom_after.append(s.odom.pose())
        await drive(s, 0.2, 0.3, 6.0)

    rec = run_sim(sim, body, ["pose", "ground_truth"])
    errs = _pose_errors(rec)
    assert max(e for t, e in errs if t <= 3.0) < 0.05  # tracking while everything works
    stamps = np.array(rec.stamps("pose"))
    assert not np.any((stamps > 3.5 + 1e-9) & (stamps < 6.0 - 1e-9))  # down 0.5 s after odom (and its restart)
    # the restarted odometry counts from zero; localization copes with the jump: it resumes from
    # its last estimate (0.4 m behind the robot, which moved meanwhile), re-converges, no snap
    assert odom_after[0].x == 0.0 and odom_after[0].y == 0.0
    after = [(t, e) for t, e in errs if t > 6.0]
    assert after[0][1] > 0.25
    assert max(e for t, e in after if t < 6.5) > 0.15  # not at the truth half a second later
    assert max(e for t, e in after if t > 10.0) < 0.05  # converged a few seconds later


def test_localization_dead_reckons_without_lidar():
    sim = Simulator(open_world(), "burger", seed=3)

    async def body(s):
        await drive(s, 0.2, 0.0, 2.0)
        s.crash("lidar")
        s.faults.wheel_slip(1.5)
        await drive(s, 0.2, 0.0, 3.0)

    rec = run_sim(sim, body, ["pose"])
    last = rec["pose"][-1]
    # odometry over-reads by 50%: the estimate runs ahead of the truth
    assert last.pose.x - sim.pose.x > 0.2
    assert last.covariance > rec["pose"][5].covariance


@pytest.mark.parametrize("fault", [{"kind": "crash", "component": "lidar"},
                                   {"kind": "stall", "component": "lidar", "duration": 3.0, "mode": "frozen"},
                                   {"kind": "corrupt", "component": "lidar", "duration": 3.0, "mode": "nan"},
                                   {"kind": "corrupt", "component": "lidar", "duration": 3.0, "mode": "garbage"}])
def test_localization_judges_the_scans_it_gets_and_reconverges_after(fault):
    """A crashed, frozen, NaN or garbage lidar: localization sees it in the data (no fault flag
    is read), dead-reckons with the slipping odometry, then re-converges over seconds."""
    sim = Simulator(room_world(spawn=(-2.0, 0.0, 0.0)), "burger", seed=4)

    async def body(s):
        await drive(s, 0.2, 0.0, 1.0)
        s.faults.apply(fault)
        s.faults.wheel_slip(1.3)
        await drive(s, 0.2, 0.0, 3.0)
        s.faults.wheel_slip(1.0)
        if fault["kind"] == "crash":
            await s.restart("lidar")
        await drive(s, 0.1, 0.0, 6.0)

    rec = run_sim(sim, body, ["pose", "ground_truth"])
    modes = [(e.t, e.data["mode"]) for e in sim.events_of("localization_mode")]
    assert modes[0][1] == "dead_reckoning" and 1.0 <= modes[0][0] <= 1.6
    assert modes[1][1] == "scan_matching"
    back = modes[1][0]
    errs = _pose_errors(rec)
    at_return = max(e for t, e in errs if back - 0.2 <= t <= back)
    assert at_return > 0.15  # drifted while dead reckoning
    assert max(e for t, e in errs if back + 0.3 <= t <= back + 0.6) > 0.5 * at_return  # no snap
    assert max(e for t, e in errs if t > back + 5.0) < 0.05


def test_pose_algebra():
    a = (1.0, 2.0, 0.7)
    from bt_runtime.runtime.messages import Pose2D

    p = Pose2D(*a)
    q = Pose2D(0.3, -0.2, 1.1)
    r = compose(inverse(p), compose(p, q))
    assert (r.x, r.y, r.yaw) == pytest.approx((q.x, q.y, q.yaw))


def test_battery_formula():
    # SoC -= P/V * dt / 3600 / C * 100
    assert soc_after(100.0, 11.1, 11.1, 1.0, 3600.0) == pytest.approx(0.0)
    assert soc_after(80.0, 10.0, 12.0, 2.0, 60.0) == pytest.approx(80.0 - 10 / 12 * 60 / 3600 / 2 * 100)
    assert soc_after(1.0, 100.0, 10.0, 1.0, 3600.0) == 0.0


def test_battery_integration_matches_the_model():
    profile = load_profile("burger")
    sim = Simulator(open_world(), profile, seed=0)
    rec = run_sim(sim, lambda s: asyncio.sleep(100.0 + 1e-6), ["battery"])
    b = profile.battery
    idle = sim.battery.idle_power_w  # this unit's truth, not the profile's nominal value
    assert idle != b.idle_power_w and abs(idle / b.idle_power_w - 1) <= 0.1
    soc = b.initial_soc
    for _ in range(10000):
        soc = soc_after(soc, idle, b.voltage(soc), b.capacity_ah, 0.01)
    assert sim.battery.soc == pytest.approx(soc, rel=1e-9)
    last = rec["battery"][-1]
    assert len(rec["battery"]) == 100
    assert last.percentage == pytest.approx(soc, abs=0.5)  # measured, with noise
    readings = [m.percentage for m in rec["battery"]]
    assert any(a < b for a, b in zip(readings, readings[1:]))  # noise: not monotone
    assert math.isnan(last.power) and math.isnan(last.current)  # no current or power sensor
    # and that is (close to) the paper's formula with a constant voltage
    assert 100 - sim.battery.soc == pytest.approx(idle / 12.6 * 100 / 3600 / 1.8 * 100, rel=0.01)


def test_battery_consumption_differs_per_seed_within_ten_percent():
    nominal = load_profile("rosbot2").battery
    units = [Simulator(open_world(), "rosbot2", seed=seed).battery for seed in range(8)]
    for name in ("idle_power_w", "k_linear", "k_angular"):
        values = [getattr(u, name) for u in units]
        assert len(set(values)) == 8
        assert all(abs(v / getattr(nominal, name) - 1) <= 0.1 for v in values)
    again = Simulator(open_world(), "rosbot2", seed=3).battery
    assert again.k_linear == units[3].k_linear  # seeded


def test_battery_draws_more_when_driving_and_charges_at_the_dock():
    sim = Simulator(open_world(dock=(0.0, 0.0)), "burger", seed=0)

    async def body(s):
        await asyncio.sleep(10.0)
        soc_idle = s.battery.soc
        await drive(s, 0.2, 0.0, 10.0)
        soc_drive = s.battery.soc
        return soc_idle, soc_drive

    out = {}

    async def wrapper(s):
        out["socs"] = await body(s)

    sim.faults.set_battery(50.0)
    rec = run_sim(sim, wrapper, ["battery"])
    soc_idle, soc_drive = out["socs"]
    assert soc_idle > 50.0  # charging while docked
    assert sim.events_of("charging_started")
    assert soc_drive < soc_idle  # driving (off the dock) drains it
    assert any(m.current < 0 for m in rec["battery"])  # the charger's current while docked


def test_depleted_battery_stops_the_base():
    sim = Simulator(open_world(), "burger", seed=0)

    async def body(s):
        s.faults.set_battery(0.001)
        await drive(s, 0.2, 0.0, 3.0)

    run_sim(sim, body, [])
    assert sim.events_of("battery_depleted")
    assert sim.twist.linear == pytest.approx(0.0, abs=1e-6)
    assert sim.pose.x < 0.2


def test_random_streams_are_independent_per_name():
    a = Simulator(open_world(), "burger", seed=7)
    b = Simulator(open_world(), "burger", seed=7)
    assert np.array_equal(a.rng("lidar").standard_normal(5), b.rng("lidar").standard_normal(5))
    assert not np.array_equal(a.rng("lidar").standard_normal(5), a.rng("imu").standard_normal(5))
    c = Simulator(open_world(), "burger", seed=8)
    assert not np.array_equal(a.rng("lidar").standard_normal(5), c.rng("lidar").standard_normal(5))


def test_ground_truth_topic_and_trajectory():
    sim = Simulator(open_world(), "burger", seed=0)
    rec = run_sim(sim, lambda s: drive(s, 0.2, 0.0, 1.0), ["ground_truth"])
    tr = sim.trajectory()
    assert tr.shape[1] == 7 and len(tr) == len(rec["ground_truth"])
    assert tr[-1, 1] == rec["ground_truth"][-1].pose.x
    assert math.isclose(tr[1, 0] - tr[0, 0], 0.1)


def test_reset_pose_reinitialises_odometry_and_localization():
    from bt_runtime.runtime.messages import Pose2D

    sim = Simulator(open_world(), "burger", seed=0)

    async def body(s):
        await drive(s, 0.2, 0.0, 2.0)
        s.reset_pose(Pose2D(-2.0, 3.0, 1.0))
        await asyncio.sleep(0.5)

    rec = run_sim(sim, body, ["odom", "pose"])
    assert (sim.pose.x, sim.pose.y) == pytest.approx((-2.0, 3.0), abs=1e-3)
    assert rec["odom"][-1].pose.x == pytest.approx(0.0, abs=1e-3)
    assert rec["pose"][-1].pose.distance_to(Pose2D(-2.0, 3.0)) < 0.1
