"""Physics and the base: no tunnelling, stalls, command timeout, acceleration limits."""

from __future__ import annotations

import asyncio
import math

import numpy as np
import pytest

from sim import Simulator
from sim.robot import load_profile
from sim.testing import Recorder, run_virtual
from sim.world import world_from_dict

# a corridor along +x with a wall at x = 1.0 .. 1.15 in front of the robot
WALL = {"type": "polygon", "name": "wall", "points": [[1.0, -2], [1.15, -2], [1.15, 2], [1.0, 2]]}


def corridor(*extra, spawn=(0.0, 0.0, 0.0)):
    return world_from_dict({
        "name": "corridor", "bounds": {"xmin": -3, "ymin": -3, "xmax": 3, "ymax": 3},
        "spawn": {"x": spawn[0], "y": spawn[1], "yaw": spawn[2]},
        "obstacles": [WALL, {"type": "polygon", "points": [[-2, -2], [-1.85, -2], [-1.85, 2], [-2, 2]]},
                      *extra]})


async def drive(sim: Simulator, v: float, w: float, duration: float, period: float = 0.1) -> None:
    loop = asyncio.get_running_loop()
    end = loop.time() + duration
    while loop.time() < end - 1e-9:
        sim.command(v, w)
        await asyncio.sleep(period)


@pytest.mark.parametrize("robot, v, w", [
    ("burger", 1e9, 0.0), ("burger", math.inf, 0.0), ("burger", 50.0, 30.0), ("burger", -1e6, 1e6),
    ("burger", math.nan, 1.0), ("rosbot2", 1e9, 0.0), ("rosbot2", -1e9, 0.1)])
def test_absurd_commands_never_tunnel(robot, v, w):
    sim = Simulator(corridor(), robot, seed=1)

    async def main():
        await sim.start()
        await drive(sim, v, w, 6.0)
        await sim.stop()

    run_virtual(main)
    tr = sim.trajectory()
    r = sim.profile.radius
    assert np.all(tr[:, 1] <= 1.0 - r + 0.005)
    assert np.all(tr[:, 1] >= -1.85 + r - 0.005)
    assert np.all(np.hypot(np.diff(tr[:, 1]), np.diff(tr[:, 2])) <= sim.profile.max_linear * 0.1 + 1e-6)
    if not math.isnan(v) and abs(v) > 1 and abs(w) < 1:  # it drove into a wall and stayed there
        assert len(sim.events_of("collision")) >= 1


def test_huge_pushes_never_tunnel():
    sim = Simulator(corridor(), "burger", seed=1, max_body_speed=3.0)

    async def main():
        await sim.start()
        for _ in range(20):
            sim.apply_impulse(500.0, 0.0)  # 500 m/s worth of push on a 1 kg robot
            await asyncio.sleep(0.05)
        await sim.stop()

    run_virtual(main)
    tr = sim.trajectory()
    # thrown at the wall at the 3 m/s body-speed cap, again and again: at most ~1 cm overlap
    assert np.all(tr[:, 1] <= 1.0 - sim.profile.radius + 0.012)
    assert sim.pose.x > 0.8  # it did get thrown at the wall


def test_stall_against_wall_odometry_drifts_truth_stays():
    sim = Simulator(corridor(), "burger", seed=2)

    async def main():
        rec = Recorder(sim, ["odom", "bumper", "imu"])
        await sim.start()
        await drive(sim, 0.2, 0.0, 10.0)
        await sim.stop()
        return rec

    rec = run_virtual(main)
    tr = sim.trajectory()
    r = sim.profile.radius
    # the impact shows in the IMU as a deceleration spike
    hit = sim.events_of("collision")[0].t
    assert min(m.accel_x for m in rec["imu"] if hit - 0.05 < m.stamp < hit + 0.05) < -5.0
    assert max(abs(m.accel_x) for m in rec["imu"] if 1.0 < m.stamp < hit - 0.1) < 0.2
    stalled = tr[tr[:, 0] > 6.0]
    # ground truth: pinned at the wall, not moving
    assert np.all(np.abs(stalled[:, 1] - (1.0 - r)) < 0.005)
    assert np.all(np.abs(stalled[:, 4]) < 0.01)
    # wheel odometry: kept counting the wheels' travel (~0.2 m/s for ~10 s)
    odom = rec["odom"][-1]
    assert odom.pose.x > 1.8 and odom.twist.linear > 0.15
    assert odom.pose.x - (sim.pose.x - sim.spawn.x) > 0.9
    # the bumper's front segment is pressed (which segment, never where or how hard)
    pressed = [c for c in rec["bumper"] if c.in_contact]
    front = [i for i, seg in enumerate(sim.profile.bumper.segments) if seg.name == "front"]
    assert pressed and pressed[-1].segments == tuple(front)
    assert not hasattr(pressed[-1], "point") and not hasattr(pressed[-1], "impulse")
    hit_event = sim.events_of("collision")[0]
    assert hit_event.data["obstacle"].endswith("wall")
    assert hit_event.data["body_speed"] == pytest.approx(0.2, abs=0.01)  # the speed at impact


def test_backing_off_releases_the_bumper():
    sim = Simulator(corridor(spawn=(0.8, 0.0, 0.0)), "burger", seed=2)

    async def main():
        rec = Recorder(sim, ["bumper"])
        await sim.start()
        await drive(sim, 0.2, 0.0, 1.5)
        await drive(sim, -0.2, 0.0, 1.0)
        await sim.stop()
        return rec

    rec = run_virtual(main)
    states = [c.in_contact for c in rec["bumper"]]
    assert True in states and states[-1] is False
    assert sim.events_of("collision_end")


def test_command_timeout_stops_the_robot():
    sim = Simulator(corridor(spawn=(-1.0, 0.0, 0.0)), "burger", seed=3)

    async def main():
        rec = Recorder(sim, ["cmd_vel_out"])
        await sim.start()
        await drive(sim, 0.2, 0.0, 1.0)  # last command at t = 0.9
        await asyncio.sleep(2.0)
        await sim.stop()
        return rec

    rec = run_virtual(main)
    tr = sim.trajectory()
    t_last = 0.9
    moving = tr[(tr[:, 0] > 0.5) & (tr[:, 0] < t_last + 0.5)]
    assert np.all(moving[:, 4] > 0.19)  # still driving until the timeout
    stopped = tr[tr[:, 0] > t_last + 0.5 + 0.2 / 1.0 + 0.05]
    assert np.all(np.abs(stopped[:, 4]) < 1e-3)
    assert rec["cmd_vel_out"][-1].is_zero  # the timeout is visible on cmd_vel_out
    assert len(sim.events_of("cmd_timeout")) == 1
    assert sim.events_of("cmd_timeout")[0].t == pytest.approx(t_last + 0.5, abs=0.011)


@pytest.mark.parametrize("name", ["burger", "rosbot2"])
def test_acceleration_limits(name):
    profile = load_profile(name)
    sim = Simulator(corridor(spawn=(-1.5, 0.0, 0.0)), profile, seed=4, trajectory_hz=100)

    async def main():
        await sim.start()
        await drive(sim, profile.max_linear, 0.0, 0.6, period=0.05)
        await drive(sim, 0.0, profile.max_angular, 1.0, period=0.05)
        await sim.stop()

    run_virtual(main)
    tr = sim.trajectory()
    dt = np.diff(tr[:, 0])
    acc = np.diff(tr[:, 4]) / dt
    alpha = np.diff(tr[:, 5]) / dt
    assert acc.max() <= profile.max_linear_accel * 1.05 + 0.05
    assert np.abs(alpha).max() <= profile.max_angular_accel * 1.05 + 0.1
    assert tr[:, 4].max() <= profile.max_linear + 1e-3
    assert np.abs(tr[:, 5]).max() <= profile.max_angular * 1.001
    # and it does reach the top speed
    assert tr[:, 4].max() > min(profile.max_linear, profile.max_linear_accel * 0.6) * 0.95


def test_commands_are_clamped_and_published():
    sim = Simulator(corridor(), "burger", seed=0)

    async def main():
        rec = Recorder(sim, ["cmd_vel_out"])
        await sim.start()
        out = sim.command(5.0, 0.0)
        out2 = sim.command(0.1, 100.0)
        await sim.stop()
        return rec, out, out2

    rec, out, out2 = run_virtual(main)
    assert out.linear == pytest.approx(0.22) and out.angular == 0
    # the wheel limit keeps the curvature
    assert out2.linear / out2.angular == pytest.approx(0.1 / 2.84)
    assert [m.linear for m in rec["cmd_vel_out"]] == [out.linear, out2.linear]


def test_rosbot_drives_at_025():
    sim = Simulator(corridor(spawn=(-1.5, 0.0, 0.0)), "rosbot2", seed=0)

    async def main():
        rec = Recorder(sim, ["cmd_vel_out"])
        await sim.start()
        await drive(sim, 0.25, 0.0, 1.5)
        await drive(sim, 0.25, 0.5, 1.5)
        await sim.stop()
        return rec

    rec = run_virtual(main)
    tr = sim.trajectory()
    assert tr[14, 4] == pytest.approx(0.25, abs=0.005)  # t = 1.4: straight at 0.25 m/s
    assert tuple(tr[-1, 4:6]) == pytest.approx((0.25, 0.5), abs=0.01)  # and 0.25 m/s with 0.5 rad/s
    assert rec["cmd_vel_out"][-1].linear == 0.25 and rec["cmd_vel_out"][-1].angular == 0.5


def test_turning_in_place_follows_the_command():
    sim = Simulator(corridor(spawn=(-0.5, 0.0, 0.0)), "burger", seed=0)

    async def main():
        await sim.start()
        await drive(sim, 0.0, 1.0, 3.0)
        await sim.stop()

    run_virtual(main)
    tr = sim.trajectory()
    assert np.hypot(tr[-1, 1] + 0.5, tr[-1, 2]) < 0.01
    assert tr[-1, 5] == pytest.approx(1.0, abs=0.01)


def test_an_error_in_the_step_stops_the_sim_visibly():
    sim = Simulator(corridor(), "burger", seed=0)

    def broken(msg):
        raise ValueError("subscriber bug")

    async def main():
        sim.subscribe("imu", broken)
        await sim.start()
        await asyncio.sleep(0.5)
        assert not sim.running
        await sim.stop()

    with pytest.raises(RuntimeError, match="stopped on an error") as ei:
        run_virtual(main)
    assert isinstance(ei.value.__cause__, ValueError)
    assert sim.events_of("sim_failed")[0].data["step"] == 2


def test_external_force_moves_a_standing_robot_against_traction():
    sim = Simulator(corridor(spawn=(-1.0, 0.0, 0.0)), "burger", seed=0)

    async def main():
        await sim.start()
        sim.apply_force(0.0, 5.0, 1.0)  # below the burger's traction (7.8 N): holds
        await asyncio.sleep(1.5)
        y_weak = sim.pose.y
        sim.apply_force(0.0, 20.0, 0.5)  # above it: slides sideways
        await asyncio.sleep(1.0)
        await sim.stop()
        return y_weak

    y_weak = run_virtual(main)
    assert abs(y_weak) < 1e-3
    assert sim.pose.y > 0.1
    assert sim.odom.y == 0.0  # the wheels never turned
