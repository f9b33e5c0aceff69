"""A frozen odometry or localization pose with fresh timestamps is stale data when the robot is
told to move and the scan or the IMU shows that it does; a robot standing still or blocked
(commanded, but nothing shows motion) raises no alarm."""

from __future__ import annotations

import asyncio

import numpy as np
import pytest

from bt_runtime.runtime.messages import Imu, LaserScan, Pose2D, Twist
from bt_runtime.runtime.motion_check import MotionWitness
from bt_runtime.runtime.supervisor import Health
from sim.faults import parse_fault


class Clock:
    t = 0.0

    def __call__(self) -> float:
        return self.t


def _scan(t: float, ranges) -> LaserScan:
    return LaserScan(t, -np.pi, 2 * np.pi / len(ranges), 0.1, 10.0, np.asarray(ranges, dtype=float))


def _run(witness: MotionWitness, clock: Clock, seconds: float, *, command: Twist, scan_step: float,
         yaw_rate: float, pose_step: float, seed: int = 0) -> list[str | None]:
    """Feed 10 Hz scans (ranges drifting by ``scan_step`` per scan, plus noise), a 100 Hz IMU and
    20 Hz poses (moving by ``pose_step`` each) for ``seconds``; the frozen check's answers."""
    rng = np.random.default_rng(seed)
    base = np.linspace(1.0, 4.0, 360)
    answers, x = [], 0.0
    for k in range(int(seconds * 100)):
        clock.t = k / 100
        witness.on_command(command)
        witness.on_imu(Imu(clock.t, yaw_rate + rng.normal(0, 0.01), 0.0, 0.0))
        if k % 10 == 0:
            witness.on_scan(_scan(clock.t, base - scan_step * k / 10 + rng.normal(0, 0.015, 360)))
        if k % 5 == 0:
            x += pose_step
            answers.append(witness.frozen("odom", Pose2D(x, 0.0)))
    return answers


@pytest.mark.parametrize(("case", "command", "scan_step", "yaw_rate", "pose_step", "alarm"), [
    ("frozen while driving: the scan changes", Twist(0.25, 0.0), 0.025, 0.0, 0.0, True),
    ("frozen while turning: the IMU feels it", Twist(0.0, 0.8), 0.0, 0.8, 0.0, True),
    ("standing still", Twist(0.0, 0.0), 0.0, 0.0, 0.0, False),
    ("blocked: commanded, nothing moves", Twist(0.25, 0.0), 0.0, 0.0, 0.0, False),
    ("driving, the pose follows", Twist(0.25, 0.0), 0.025, 0.0, 0.0125, False),
])
def test_a_frozen_pose_is_reported_only_when_other_sensors_show_motion(case, command, scan_step, yaw_rate,
                                                                      pose_step, alarm):
    clock = Clock()
    answers = _run(MotionWitness(clock), clock, 4.0, command=command, scan_step=scan_step, yaw_rate=yaw_rate,
                   pose_step=pose_step)
    problems = [a for a in answers if a is not None]
    if not alarm:
        assert problems == [], case
        return
    assert problems and problems[0].startswith("stale data: pose frozen"), case
    first = answers.index(problems[0])
    assert 1.0 <= first * 0.05 <= 2.0  # after the hold, not at once, not late
    assert all(a is not None for a in answers[first:])  # latched while the pose stays put


def test_a_reported_pose_clears_when_it_moves_again():
    clock = Clock()
    witness = MotionWitness(clock)
    _run(witness, clock, 3.0, command=Twist(0.25, 0.0), scan_step=0.025, yaw_rate=0.0, pose_step=0.0)
    assert witness.frozen("odom", Pose2D(0.0, 0.0)) is not None
    assert witness.frozen("odom", Pose2D(0.01, 0.0)) is None  # a restarted driver publishes again


async def _drive(rt, goal: Pose2D, seconds: float, until=None) -> None:
    """Navigate towards ``goal`` (commands go through the gate, as the tree's would) for up to
    ``seconds``, or until ``until()``."""
    handle = rt.driver.navigation.navigate_to_pose(goal)
    try:
        for _ in range(int(seconds * 10)):
            await asyncio.sleep(0.1)
            if until is not None and until():
                break
    finally:
        handle.cancel()


async def test_frozen_odometry_while_driving_fails_it_with_the_reason_and_a_restart_cures_it(make_runtime):
    rt = make_runtime(seed=3)
    await rt.start()
    sim = rt.driver.sim
    try:
        await asyncio.sleep(1.0)
        sim.faults.schedule(3.0, parse_fault({"kind": "stall", "component": "odom", "mode": "frozen",
                                              "duration": 60.0}))
        await _drive(rt, Pose2D(1.5, -2.0), 10.0,
                     until=lambda: any(e.state is Health.FAILED for e in rt.supervisor.events_of("odom")))
        failed = [e for e in rt.supervisor.events_of("odom") if e.state is Health.FAILED]
        assert failed and "pose frozen" in failed[0].reason, rt.supervisor.events_of("odom")
        assert 4.0 <= failed[0].t <= 6.0  # the hold and the timeout after the fault, not later
        assert await rt.supervisor.restart("odom")
        assert rt.supervisor.health("odom") is Health.OK
    finally:
        await rt.stop()


async def test_a_blocked_robot_pushing_against_what_it_cannot_see_raises_no_alarm(make_runtime):
    rt = make_runtime(seed=4)
    await rt.start()
    sim = rt.driver.sim
    try:
        await asyncio.sleep(1.0)
        sim.faults.apply(parse_fault({"kind": "invisible_obstacle", "ahead": 0.02, "width": 0.6, "depth": 0.3}))
        before = sim.pose  # the truth, for judging the test only
        commanded = []
        rt.driver.subscribe("cmd_vel_out", lambda m: commanded.append(abs(m.linear)))
        await _drive(rt, Pose2D(1.5, -2.0), 6.0)  # commanded forward, going nowhere
        assert before.distance_to(sim.pose) < 0.05 and max(commanded) > 0.1  # blocked, though told to go
        await asyncio.sleep(1.0)  # standing still after it
    finally:
        await rt.stop()
    assert not [e for e in rt.supervisor.events if e.state is Health.FAILED]
