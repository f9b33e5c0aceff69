"""``runtime.send_goal``: goals handed to trees/autonomy.xml on the simulator (virtual time).

A goal reaches its pose with feedback on the way; a cancelled goal ends CANCELED and the robot
stops; a new goal preempts the running one; a goal the battery cannot make is refused with
the reason when the robot has no dock (tests/runtime/test_goal_docking.py: with one); a tree without the goal hand-off rejects goals with a message that says why.
"""

from __future__ import annotations

import asyncio
import math

import pytest

from bt_runtime.runtime.goal_intake import GoalState, remaining_distance
from bt_runtime.runtime.messages import Path, Pose2D
from tests.paths import ROOT

AUTONOMY = str(ROOT / "trees" / "autonomy.xml")
SPAWN = Pose2D(-2.0, -2.0, 0.0)


async def until_driving(rt, timeout: float = 20.0) -> None:
    """Wait (robot time) until the robot drives faster than 0.1 m/s."""
    async def driving():
        while speed_of(rt) < 0.1:
            await asyncio.sleep(0.1)
    await asyncio.wait_for(driving(), timeout)


def speed_of(rt) -> float:
    odom = rt.backup.latest("odom")
    return abs(odom.twist.linear) if odom is not None else 0.0


async def test_a_goal_succeeds_with_feedback(runtime):
    rt = await runtime(AUTONOMY, seed=1)
    try:
        await asyncio.sleep(1.0)  # components report
        handle = rt.send_goal(Pose2D(-1.0, -2.0, 0.0))
        seen = []
        handle.on_feedback.append(seen.append)
        result = await asyncio.wait_for(handle, 60)
    finally:
        await rt.stop()
    assert result.succeeded and result.status == GoalState.SUCCEEDED, result
    assert result.error_code == 0
    assert len(seen) >= 3
    assert seen[0].distance_remaining == pytest.approx(1.0, abs=0.3)
    assert seen[-1].distance_remaining < seen[0].distance_remaining - 0.5
    assert seen[-1].navigation_time > seen[0].navigation_time
    assert seen[-1].current_pose.x > SPAWN.x + 0.5
    assert all(f.number_of_recoveries == 0 for f in seen)


async def test_cancel_ends_canceled_and_the_robot_stops(runtime):
    rt = await runtime(AUTONOMY, seed=1)
    try:
        await asyncio.sleep(1.0)
        handle = rt.send_goal(Pose2D(3.5, -2.5, 0.0))
        await until_driving(rt)
        assert handle.cancel()
        result = await asyncio.wait_for(handle, 5)
        await asyncio.sleep(1.5)
        stopped = speed_of(rt)
        status = rt.tree.root_blackboard.get("goal_status")
    finally:
        await rt.stop()
    assert result.status == GoalState.CANCELED and result.outcome == "CANCELED", result
    assert stopped < 0.01
    assert status == "CANCELED"
    assert not handle.cancel()  # already ended


async def test_a_new_goal_preempts_the_running_one(runtime):
    rt = await runtime(AUTONOMY, seed=1)
    try:
        await asyncio.sleep(1.0)
        first = rt.send_goal(Pose2D(3.5, -2.5, 0.0))
        await until_driving(rt)
        second = rt.send_goal(Pose2D(-1.0, -2.0, 0.0))
        first_result = await asyncio.wait_for(first, 5)
        assert not second.done
        second_result = await asyncio.wait_for(second, 60)
        pose = rt.backup.latest("pose").pose
    finally:
        await rt.stop()
    assert first_result.status == GoalState.ABORTED and first_result.outcome == "PREEMPTED"
    assert "preempted" in first_result.error_msg
    assert second_result.succeeded, second_result
    assert math.hypot(pose.x + 1.0, pose.y + 2.0) < 0.35


async def test_queued_goals_run_one_after_the_other(runtime):
    rt = await runtime(AUTONOMY, seed=1)
    try:
        await asyncio.sleep(1.0)
        first = rt.send_goal(Pose2D(-1.4, -2.0, 0.0))
        second = rt.send_goal(Pose2D(-2.0, -2.0, 0.0), preempt=False)
        results = await asyncio.wait_for(asyncio.gather(first, second), 90)
    finally:
        await rt.stop()
    assert [r.status for r in results] == [GoalState.SUCCEEDED] * 2
    assert first.started_at < second.started_at


async def test_a_goal_the_battery_cannot_make_is_refused_without_a_dock(runtime):
    from sim.robot import load_profile
    from sim.world import World, load_world

    no_dock = World.model_validate({**load_world("apartment").model_dump(), "dock": None})
    rt = await runtime(AUTONOMY, world=no_dock,
                       robot=load_profile("burger", **{"battery.capacity_ah": 0.1, "battery.initial_soc": 12.0}), seed=1)
    try:
        await asyncio.sleep(1.5)
        result = await asyncio.wait_for(rt.send_goal(Pose2D(3.5, -2.5, 0.0)), 30)
    finally:
        await rt.stop()
    assert result.status == GoalState.ABORTED and result.outcome == "REFUSED"
    assert result.error_msg.startswith("refused: battery")


async def test_a_tree_without_the_goal_handoff_rejects_goals(runtime):
    rt = await runtime('<root BTCPP_format="4"><BehaviorTree ID="Main"><KeepRunningUntilFailure>'
                       '<AlwaysSuccess/></KeepRunningUntilFailure></BehaviorTree></root>')
    try:
        result = await asyncio.wait_for(rt.send_goal(Pose2D(0, 0)), 1)
        nan = await asyncio.wait_for(rt.send_goal(Pose2D(math.nan, 0)), 1)
    finally:
        await rt.stop()
    assert result.status == GoalState.REJECTED and "{goal_status}" in result.error_msg
    assert nan.status == GoalState.REJECTED and "not finite" in nan.error_msg


async def test_stopping_the_runtime_ends_open_goals(runtime):
    rt = await runtime(AUTONOMY, seed=1)
    await asyncio.sleep(1.0)
    handle = rt.send_goal(Pose2D(3.5, -2.5, 0.0))
    await asyncio.sleep(1.0)
    assert handle.state == GoalState.EXECUTING
    await rt.stop()
    result = await asyncio.wait_for(handle, 1)
    assert result.status == GoalState.ABORTED and "stopped" in result.error_msg


def test_remaining_distance_follows_the_path():
    import numpy as np

    path = Path(0.0, np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0]]))
    assert remaining_distance(Pose2D(1.0, 0.1), Pose2D(2.0, 2.0), path) == pytest.approx(0.1 + 1.0 + 2.0)
    assert remaining_distance(Pose2D(2.5, 1.5), Pose2D(2.0, 2.0), path) == pytest.approx(0.5 + 0.5)
    assert remaining_distance(Pose2D(0.0, 0.0), Pose2D(5.0, 0.0), path) == pytest.approx(5.0)  # path elsewhere
    assert math.isnan(remaining_distance(None, Pose2D(1, 1), path))
