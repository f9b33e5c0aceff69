"""NavStack end to end on virtual time with the kinematic robot (tests/nav_fixture.py)."""

from __future__ import annotations

import asyncio
import contextlib
import math

import numpy as np
import pytest

from bt_runtime.runtime.clock import run
from bt_runtime.runtime.driver import NavigationClient, NavigationHandle
from bt_runtime.runtime.messages import ActionStatus, ComponentState, NavErrorCode, Pose2D, Twist
from sim.bus import Bus
from sim.nav.occupancy import OccupancyGrid
from sim.nav.stack import Heartbeat, NavServiceError, NavStack
from tests.sim.nav.fixtures import HOUSE, KinematicRobot, small_world

E = NavErrorCode
START = Pose2D(1.0, 1.0, 0.0)
GOAL = Pose2D(7.0, 5.0, math.pi / 2)


@contextlib.asynccontextmanager
async def rig(world=None, start=START, nav_map=None, params=None, **robot_kw):
    world = world or small_world()
    bus = Bus()
    robot = KinematicRobot(bus, world, start, **robot_kw).start()
    nav = NavStack(bus, nav_map or world, params=params)
    await nav.start()
    await asyncio.sleep(0.3)  # first poses and scans
    try:
        yield bus, robot, nav
    finally:
        await nav.stop()
        await robot.stop()


def yaw_err(a: float, b: float) -> float:
    return abs((a - b + math.pi) % (2 * math.pi) - math.pi)


def test_protocols():
    async def main():
        async with rig() as (_bus, _robot, nav):
            assert isinstance(nav, NavigationClient)
            h = nav.wait(0.1)
            assert isinstance(h, NavigationHandle)
            await h
    run(main())


def test_navigate_reaches_the_goal_within_tolerance():
    async def main():
        async with rig(scan_noise=0.01) as (bus, robot, nav):
            plans = []
            bus.subscribe("plan", plans.append)
            feedback = []
            h = nav.navigate_to_pose(GOAL, feedback=feedback.append)
            res = await h
            assert res.status is ActionStatus.SUCCEEDED, res
            assert robot.pose.distance_to(GOAL) <= 0.25
            assert yaw_err(robot.pose.yaw, GOAL.yaw) <= 0.25
            assert robot.blocked_steps == 0
            assert len(plans) >= 10  # replanned at 1 Hz
            assert feedback and feedback[-1].distance_remaining < 0.6
            assert h.feedback is feedback[-1]
            speeds = [c.linear for _, c in robot.commands]
            assert max(speeds) <= 0.25 + 1e-9 and robot.commands[-1][1] == Twist(0.0, 0.0)
    run(main())


@pytest.mark.skipif(not HOUSE.exists(), reason="shared/reference/worlds not available")
def test_navigate_across_the_house():
    async def main():
        world = OccupancyGrid.load(HOUSE)
        goal = Pose2D(5.5, -4.3, 0.0)
        async with rig(world, Pose2D(-6.3, -1.5, 0.0), scan_noise=0.01) as (_b, robot, nav):
            res = await nav.navigate_to_pose(goal)
            assert res.succeeded, res
            assert robot.pose.distance_to(goal) <= 0.25 and robot.blocked_steps == 0
    run(main())


def test_replans_around_an_obstacle_the_map_does_not_know():
    async def main():
        world = small_world()
        nav_map = world.copy()
        box = OccupancyGrid.from_shapes([np.array([[5.2, 2.2], [5.8, 2.2], [5.8, 3.8], [5.2, 3.8]])],
                                        bounds=world.bounds)
        world.data[:] = np.maximum(world.data, box.data)
        async with rig(world, nav_map=nav_map, scan_noise=0.01) as (_b, robot, nav):
            goal = Pose2D(7.0, 3.0, 0.0)
            res = await nav.navigate_to_pose(goal)
            assert res.succeeded, res
            assert robot.pose.distance_to(goal) <= 0.25 and robot.blocked_steps == 0
            assert nav.planner.last.method in ("astar", "learned", "dijkstra", "cached")
    run(main())


def test_progress_checker_fails_when_the_robot_is_held():
    async def main():
        async with rig() as (_bus, robot, nav):
            robot.held = True
            loop = asyncio.get_running_loop()
            t0 = loop.time()
            res = await nav.navigate_to_pose(GOAL)
            assert res.error_code is E.FAILED_TO_MAKE_PROGRESS
            assert 9.9 <= loop.time() - t0 <= 11.0
            assert robot.commands[-1][1].is_zero
    run(main())


def test_cancel_stops_commands():
    async def main():
        async with rig() as (_bus, robot, nav):
            h = nav.navigate_to_pose(GOAL)
            await asyncio.sleep(3.0)
            assert not h.done() and any(not c.is_zero for _, c in robot.commands)
            h.cancel()
            res = await h
            assert res.status is ActionStatus.CANCELED
            n = len(robot.commands)
            assert robot.commands[-1][1].is_zero
            await asyncio.sleep(2.0)
            assert len(robot.commands) == n  # nothing more is published
    run(main())


def test_stale_pose_stops_the_controller_then_aborts():
    async def main():
        async with rig() as (_bus, robot, nav):
            loop = asyncio.get_running_loop()
            h = nav.navigate_to_pose(GOAL)
            await asyncio.sleep(3.0)
            robot.publish_pose = False
            t_stale = loop.time()
            res = await h
            assert res.error_code is E.CONTROLLER_TF_ERROR
            moving_after = [t for t, c in robot.commands if t > t_stale + 0.55 and not c.is_zero]
            assert moving_after == []
            assert robot.commands[-1][1].is_zero
            assert 1.0 <= loop.time() - t_stale <= 1.2
    run(main())


def test_a_new_goal_preempts_the_running_one():
    async def main():
        async with rig() as (_bus, robot, nav):
            first = nav.navigate_to_pose(GOAL)
            await asyncio.sleep(2.0)
            second = nav.navigate_to_pose(Pose2D(2.0, 2.0, 0.0))
            r1 = await first
            assert r1.status is ActionStatus.ABORTED and "preempted" in r1.error_msg
            assert (await second).succeeded
    run(main())


def test_phantom_obstacle_until_costmaps_are_cleared():
    async def main():
        async with rig() as (_bus, robot, nav):
            nav.inject_phantom_obstacle(GOAL.x, GOAL.y, 0.7)  # beyond the planner's 0.5 m tolerance
            res = await nav.navigate_to_pose(GOAL)
            assert res.error_code is E.GOAL_OCCUPIED
            nav.inject_phantom_obstacle(4.0, 3.0, 0.5)  # and the door
            res = await nav.compute_path_to_pose(Pose2D(7.0, 1.0))
            assert res.error_code is E.NO_VALID_PATH
            await nav.clear_costmaps()
            res = await nav.compute_path_to_pose(Pose2D(7.0, 1.0))
            assert res.succeeded and len(res.path) > 10
    run(main())


def test_added_obstacles_persist_across_clears():
    async def main():
        async with rig() as (_bus, robot, nav):
            res = await nav.compute_path_to_pose(GOAL)
            assert nav.is_path_valid(res.path)
            await nav.add_obstacle(4.0, 3.0, 0.6)  # closes the door
            assert not nav.is_path_valid(res.path)
            assert nav.path_clearance(res.path) == 0.0
            await nav.clear_costmaps("both")
            again = await nav.compute_path_to_pose(GOAL)
            assert again.error_code is E.NO_VALID_PATH
    run(main())


def test_follow_path_and_desired_speed():
    async def main():
        async with rig() as (_bus, robot, nav):
            nav.set_desired_speed(0.15)
            res = await nav.compute_path_to_pose(Pose2D(3.0, 1.0, 0.0))
            assert res.succeeded
            out = await nav.follow_path(res.path)
            assert out.succeeded and robot.pose.distance_to(Pose2D(3.0, 1.0)) <= 0.25
            assert max(c.linear for _, c in robot.commands) <= 0.15 + 1e-9
            empty = await nav.follow_path(type(res.path)(0.0, np.zeros((0, 3))))
            assert empty.error_code is E.INVALID_PATH
    run(main())


def test_behaviours_move_the_robot():
    async def main():
        async with rig(start=Pose2D(2.0, 1.5, 0.0)) as (_bus, robot, nav):
            y0 = robot.pose.yaw
            assert (await nav.spin(1.57)).succeeded
            assert yaw_err(robot.pose.yaw, y0 + 1.57) < 0.15
            p0 = robot.pose
            assert (await nav.back_up(0.3, 0.15)).succeeded
            assert p0.distance_to(robot.pose) == pytest.approx(0.3, abs=0.05)
            assert robot.pose.y < p0.y  # backwards (facing +y)
            p1 = robot.pose
            assert (await nav.drive_on_heading(0.4, 0.2)).succeeded
            assert p1.distance_to(robot.pose) == pytest.approx(0.4, abs=0.05)
            loop = asyncio.get_running_loop()
            t0 = loop.time()
            assert (await nav.wait(2.0)).succeeded
            assert loop.time() - t0 == pytest.approx(2.0, abs=1e-6)
            assert (await nav.drive_on_heading(0.4, -0.2)).error_code is E.INVALID_INPUT
            assert (await nav.spin(6.0, time_allowance=1.0)).error_code is E.BEHAVIOR_TIMEOUT
    run(main())


def test_backup_into_a_wall_reports_collision_ahead():
    async def main():
        async with rig(start=Pose2D(0.45, 3.0, 0.0)) as (_bus, robot, nav):
            await asyncio.sleep(0.5)
            res = await nav.back_up(1.0, 0.15)
            assert res.error_code is E.COLLISION_AHEAD
            assert robot.blocked_steps == 0 and robot.pose.x > 0.1
    run(main())


def test_heartbeats_and_component_faults():
    async def main():
        async with rig() as (bus, _robot, nav):
            beats: list[Heartbeat] = []
            bus.subscribe("heartbeat/planner_server", beats.append)
            await asyncio.sleep(1.0)
            assert 9 <= len(beats) <= 11
            assert all(s is ComponentState.ACTIVE for s in nav.component_states().values())
            infos = {i.name: i for i in nav.component_infos()}
            assert infos["planner_server"].streams == ("heartbeat/planner_server",)

            # fail planning until restarted
            nav.fail_until_restart("planner_server")
            assert (await nav.compute_path_to_pose(GOAL)).error_code is E.NO_VALID_PATH
            assert (await nav.navigate_to_pose(GOAL)).error_code is E.NO_VALID_PATH
            assert await nav.restart("planner_server", delay=1.0)
            assert (await nav.compute_path_to_pose(GOAL)).succeeded

            # crash: INACTIVE, no heartbeats, requests abort
            nav.crash("planner_server")
            n = len(beats)
            await asyncio.sleep(0.5)
            assert len(beats) == n
            assert nav.component_states()["planner_server"] is ComponentState.INACTIVE
            assert (await nav.compute_path_to_pose(GOAL)).error_code is E.PLANNER_UNKNOWN
            assert not nav.is_path_valid(np.array([[1.0, 1.0], [1.1, 1.0]]))
            with pytest.raises(NavServiceError):
                await nav.clear_costmaps("global")
            restart = nav.restart_in_background("planner_server", delay=2.0)
            await asyncio.sleep(0.5)
            assert nav.component_states()["planner_server"] is ComponentState.STARTING
            assert await restart
            assert nav.component_states()["planner_server"] is ComponentState.ACTIVE

            # hang: accepted, never answered, no heartbeats, until a restart aborts the request
            nav.hang("planner_server")
            n = len(beats)
            req = asyncio.ensure_future(nav.compute_path_to_pose(GOAL))
            await asyncio.sleep(3.0)
            assert not req.done() and len(beats) == n
            assert nav.component_states()["planner_server"] is ComponentState.ACTIVE
            with pytest.raises(NavServiceError):
                await nav.clear_costmaps("global")  # no answer within service_timeout
            await nav.restart("planner_server", delay=0.5)
            res = await req
            assert res.error_code is E.PLANNER_UNKNOWN
            await asyncio.sleep(0.5)
            assert len(beats) > n
    run(main())


def test_controller_crash_aborts_and_silences_navigation():
    async def main():
        async with rig() as (_bus, robot, nav):
            h = nav.navigate_to_pose(GOAL)
            await asyncio.sleep(3.0)
            nav.crash("controller_server")
            res = await h
            assert res.error_code is E.CONTROLLER_UNKNOWN
            n = len(robot.commands)
            assert not robot.commands[-1][1].is_zero  # a dead process publishes nothing
            await asyncio.sleep(1.0)
            assert len(robot.commands) == n
            assert (await nav.follow_path(nav.current_plan)).error_code is E.CONTROLLER_UNKNOWN
            assert await nav.restart("controller_server", delay=0.5)
            assert (await nav.navigate_to_pose(GOAL)).succeeded
    run(main())


def test_hung_planner_during_navigation_keeps_following_the_old_path():
    async def main():
        async with rig() as (_bus, robot, nav):
            h = nav.navigate_to_pose(GOAL)
            await asyncio.sleep(2.5)
            nav.hang("planner_server")
            res = await h  # as in Nav2's PipelineSequence: control goes on with the last path
            assert res.succeeded
    run(main())


def test_cancel_all_and_speed_limit():
    async def main():
        async with rig() as (bus, robot, nav):
            bus.publish("nav_speed_limit", (40.0, True))  # 40 % of 0.25 m/s
            h = nav.navigate_to_pose(GOAL)
            w = nav.wait(100.0)
            await asyncio.sleep(4.0)
            assert max(c.linear for _, c in robot.commands) <= 0.1 + 1e-9
            nav.cancel_all()
            assert (await h).status is ActionStatus.CANCELED
            assert (await w).status is ActionStatus.CANCELED
    run(main())


def test_runs_are_deterministic():
    async def once():
        async with rig(scan_noise=0.01, seed=3) as (_bus, robot, nav):
            res = await nav.navigate_to_pose(GOAL)
            return res.status, [(t, c.linear, c.angular) for t, c in robot.commands], robot.pose

    a, b = run(once()), run(once())
    assert a == b
