"""NavHandle.update_path: a running follow_path takes a new path the way Nav2's controller
server accepts a preempting FollowPath goal (the BT's FollowPath re-sends on every replan)."""

from __future__ import annotations

import asyncio
import contextlib

import numpy as np

from bt_runtime.runtime.clock import run
from bt_runtime.runtime.messages import ActionStatus, NavErrorCode, Path, Pose2D
from sim.bus import Bus
from sim.nav.stack import NavStack
from tests.sim.nav.fixtures import KinematicRobot, small_world

START = Pose2D(1.0, 1.0, 0.0)


@contextlib.asynccontextmanager
async def rig(**robot_kw):
    world = small_world()
    bus = Bus()
    robot = KinematicRobot(bus, world, START, **robot_kw).start()
    nav = NavStack(bus, world)
    await nav.start()
    await asyncio.sleep(0.3)
    try:
        yield robot, nav
    finally:
        await nav.stop()
        await robot.stop()


def straight(x0: float, y0: float, x1: float, y1: float, stamp: float = 0.0) -> Path:
    n = max(2, int(np.hypot(x1 - x0, y1 - y0) / 0.05))
    pts = np.column_stack([np.linspace(x0, x1, n), np.linspace(y0, y1, n),
                           np.full(n, np.arctan2(y1 - y0, x1 - x0))])
    return Path(stamp, pts)


def test_update_path_keeps_the_action_and_follows_the_new_path():
    async def main():
        async with rig() as (robot, nav):
            h = nav.follow_path(straight(1.0, 1.0, 3.0, 1.0))
            await asyncio.sleep(2.0)
            assert h.update_path(straight(robot.pose.x, robot.pose.y, 3.0, 2.0, stamp=1.0))
            res = await h
            assert res.status is ActionStatus.SUCCEEDED, res
            assert robot.pose.distance_to(Pose2D(3.0, 2.0)) <= 0.25
            assert not h.update_path(straight(1, 1, 2, 1))  # done: the caller sends a new goal
            assert not nav.wait(0.1).update_path(straight(1, 1, 2, 1))  # not a follow_path
    run(main())


def test_path_updates_do_not_reset_the_progress_checker():
    """Replanning every second must not hide a robot that makes no progress (Nav2: 105 after
    movement_time_allowance, whatever the path updates)."""
    async def main():
        async with rig() as (robot, nav):
            robot.held = True
            loop = asyncio.get_running_loop()
            t0 = loop.time()
            h = nav.follow_path(straight(1.0, 1.0, 3.0, 1.0))
            k = 0
            while not h.done():
                await asyncio.sleep(1.0)
                k += 1
                h.update_path(straight(1.0, 1.0, 3.0, 1.0, stamp=float(k)))
            res = h.result()
            assert res.error_code is NavErrorCode.FAILED_TO_MAKE_PROGRESS
            assert 9.9 <= loop.time() - t0 <= 11.5
    run(main())
