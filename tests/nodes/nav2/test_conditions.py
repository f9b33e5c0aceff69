"""Nav2 conditions with fake robot data on a scripted clock."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_runtime.runtime.messages import POWER_SUPPLY_CHARGING, POWER_SUPPLY_FULL, BatteryState, Path, Pose2D
from bt_runtime.status import FAILURE, RUNNING, SUCCESS
from nodes.types import TrackingFeedback
from tests.nodes.nav2.support import Counter, build, fake_context


def tick(xml: str, ctx=None, bb=None):
    tree, ctx = build(xml, ctx, bb_init=bb)
    return tree.tick_exactly_once()


def line(x0: float, x1: float, n: int, stamp: float = 0.0) -> Path:
    xs = np.linspace(x0, x1, n)
    return Path(stamp, np.column_stack([xs, np.zeros(n), np.zeros(n)]))


# -- error codes -----------------------------------------------------------------------------

@pytest.mark.parametrize(("node", "helps", "does_not_help"), [
    ("WouldAControllerRecoveryHelp", [100, 104, 105, 106], [0, 101, 102, 103, 107, 208]),
    ("WouldAPlannerRecoveryHelp", [200, 207, 208, 300, 307, 308], [0, 201, 202, 203, 204, 205, 206, 105]),
    ("WouldARouteRecoveryHelp", [400, 404, 405], [0, 401, 402]),
    ("WouldASmootherRecoveryHelp", [500, 502, 503, 504], [0, 501, 505]),
])
def test_would_a_recovery_help(node, helps, does_not_help):
    for code in helps:
        assert tick(f'<{node} error_code="{{code}}"/>', bb={"code": code}) is SUCCESS, code
    for code in does_not_help:
        assert tick(f'<{node} error_code="{{code}}"/>', bb={"code": code}) is FAILURE, code


def test_an_unset_error_code_reads_as_none():
    assert tick('<WouldAControllerRecoveryHelp error_code="{never_written}"/>') is FAILURE


def test_are_error_codes_present_uses_its_list():
    xml = '<AreErrorCodesPresent error_code="{code}" error_codes_to_check="703;714"/>'
    assert tick(xml, bb={"code": 714}) is SUCCESS
    assert tick(xml, bb={"code": 105}) is FAILURE


# -- goals ---------------------------------------------------------------------------------------

def test_goal_updated_fails_on_activation_then_detects_changes():
    tree, _ = build('<GoalUpdated/>', bb_init={"goal": Pose2D(1, 0)})
    node = tree.root_node
    assert node.execute_tick() is FAILURE  # IDLE: stores the goal
    assert node.execute_tick() is FAILURE
    tree.root_blackboard.set("goal", Pose2D(2, 0))
    assert node.execute_tick() is SUCCESS
    assert node.execute_tick() is FAILURE
    tree.root_blackboard.set("goal", Pose2D(3, 0))
    node.halt_node()  # a reactive parent resets it: the change is swallowed (Nav2 issue #6082)
    assert node.execute_tick() is FAILURE


def test_goal_updated_under_a_reactive_fallback_cannot_preempt_a_running_sibling():
    """Upstream behaviour kept on purpose (honest baseline): ReactiveFallback resets
    GoalUpdated while the recovery runs, so a new goal does not end the recovery."""
    c = Counter()
    c.status["recovery"] = RUNNING
    tree, _ = build('<ReactiveFallback><GoalUpdated/><Busy name="recovery"/></ReactiveFallback>',
                    register=(c.register_running,), bb_init={"goal": Pose2D(1, 0)})
    assert tree.tick_exactly_once() is RUNNING
    tree.root_blackboard.set("goal", Pose2D(9, 9))
    for _ in range(3):
        assert tree.tick_exactly_once() is RUNNING
    assert c.ticks["recovery"] == 4


def test_global_updated_goal_first_tick_succeeds_and_survives_halts():
    tree, _ = build('<GlobalUpdatedGoal goal="{goal}"/>', bb_init={"goal": Pose2D(1, 0)})
    node = tree.root_node
    assert node.execute_tick() is SUCCESS
    assert node.execute_tick() is FAILURE
    node.halt_node()
    assert node.execute_tick() is FAILURE  # memory kept across halts
    tree.root_blackboard.set("goal", Pose2D(1, 1))
    node.halt_node()
    assert node.execute_tick() is SUCCESS


def test_goal_reached_and_are_poses_near():
    ctx = fake_context()
    ctx.backup.pose(1.0, 1.2)
    assert tick('<GoalReached goal="1;1"/>', ctx) is SUCCESS
    ctx.backup.pose(1.0, 1.3)
    assert tick('<GoalReached goal="1;1"/>', ctx) is FAILURE
    assert tick('<ArePosesNear ref_pose="0;0" target_pose="0.3;0.4"/>') is SUCCESS  # 0.5 m
    assert tick('<ArePosesNear ref_pose="0;0" target_pose="0.3;0.41"/>') is FAILURE
    assert tick('<ArePosesNear ref_pose="0;map;0;0;0;0;0;0;1" target_pose="1,0" tolerance="1.0"/>') is SUCCESS


# -- paths ---------------------------------------------------------------------------------------

def test_is_goal_nearby_measures_the_remaining_path_from_the_robot():
    ctx = fake_context()
    path = line(0.0, 10.0, 101)
    ctx.backup.pose(5.0, 0.2)
    xml = '<IsGoalNearby path="{path}" proximity_threshold="4.0"/>'
    assert tick(xml, ctx, {"path": path}) is FAILURE  # 5 m left
    ctx.backup.pose(6.5, -0.1)
    assert tick(xml, ctx, {"path": path}) is SUCCESS  # 3.5 m left
    assert tick(xml, ctx, {"path": line(0, 0, 0)}) is FAILURE  # empty path
    assert tick(xml, fake_context(), {"path": path}) is FAILURE  # no pose


def test_is_goal_nearby_bounded_search_moves_forward_along_the_path():
    ctx = fake_context()
    # a path that comes back near its start: without the bounded search the robot at the start
    # would match the end of the path
    pts = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [0.1, 1, 0], [0.1, 0.12, 0]], dtype=float)
    path = Path(0.0, pts)
    ctx.backup.pose(0.1, 0.1)
    tree, ctx = build('<IsGoalNearby path="{path}" proximity_threshold="1.0" max_robot_pose_search_dist="1.0"/>',
                      ctx, bb_init={"path": path})
    assert tree.tick_exactly_once() is FAILURE  # closest within 1 m of the start: pose 0, 5.6 m left
    tree2, _ = build('<IsGoalNearby path="{path}" proximity_threshold="1.0"/>', ctx, bb_init={"path": path})
    assert tree2.tick_exactly_once() is SUCCESS  # whole path searched: the last pose is closest


def test_is_path_valid_asks_the_planner_server():
    ctx = fake_context()
    path = line(0, 1, 11)
    assert tick('<IsPathValid path="{path}"/>', ctx, {"path": path}) is SUCCESS
    ctx.navigation.valid = False
    assert tick('<IsPathValid path="{path}"/>', ctx, {"path": path}) is FAILURE
    ctx.navigation.valid = True
    assert tick('<IsPathValid path="{path}"/>', ctx, {"path": line(0, 0, 0)}) is FAILURE


def test_path_expiring_timer():
    tree, ctx = build('<PathExpiringTimer seconds="2.0" path="{path}"/>', bb_init={"path": line(0, 1, 5)})
    node = tree.root_node
    results = []
    for i in range(12):  # 0 .. 5.5 s
        if i == 6:  # t = 3.0: a new path restarts the timer
            tree.root_blackboard.set("path", line(0, 2, 5, stamp=3.0))
        results.append(node.execute_tick())
        ctx.clock.advance(0.5)
    ok = [round(i * 0.5, 1) for i, r in enumerate(results) if r is SUCCESS]
    assert ok == [2.0, 5.0]


def test_is_within_path_tracking_bounds():
    def fb(err, heading=0.0):
        return TrackingFeedback(0.0, err, heading, 0, Pose2D(0, 0), 1.0, 0.2, 1.0)
    xml = '<IsWithinPathTrackingBounds tracking_feedback="{fb}" max_error_left="0.2" max_error_right="0.3"/>'
    assert tick(xml) is SUCCESS  # no feedback yet
    assert tick(xml, bb={"fb": fb(0.19)}) is SUCCESS
    assert tick(xml, bb={"fb": fb(0.21)}) is FAILURE
    assert tick(xml, bb={"fb": fb(-0.29)}) is SUCCESS
    assert tick(xml, bb={"fb": fb(-0.31)}) is FAILURE
    assert tick(xml, bb={"fb": fb(0.0, 3.2)}) is FAILURE


# -- robot state -----------------------------------------------------------------------------------

def test_is_battery_low_uses_ros_fractions_or_volts():
    ctx = fake_context()
    assert tick('<IsBatteryLow min_battery="0.2"/>', ctx) is FAILURE  # no message yet
    ctx.backup.battery(25.0, voltage=11.1)
    assert tick('<IsBatteryLow min_battery="0.2"/>', ctx) is FAILURE
    ctx.backup.battery(20.0, voltage=10.4)
    assert tick('<IsBatteryLow min_battery="0.2"/>', ctx) is SUCCESS
    assert tick('<IsBatteryLow min_battery="10.5" is_voltage="true"/>', ctx) is SUCCESS
    assert tick('<IsBatteryLow min_battery="10.0" is_voltage="true"/>', ctx) is FAILURE


def test_is_battery_charging():
    ctx = fake_context()
    assert tick('<IsBatteryCharging/>', ctx) is FAILURE
    ctx.backup.battery(50.0, current=1.2)
    assert tick('<IsBatteryCharging/>', ctx) is FAILURE
    ctx.backup.battery(50.0, current=-0.8)
    assert tick('<IsBatteryCharging/>', ctx) is SUCCESS
    # a monitor that reports power_supply_status is believed: FULL on the charger is not charging
    ctx.backup.record("battery", BatteryState(0.0, 12.6, 100.0, -0.1, 0.0, 0.1, POWER_SUPPLY_FULL))
    assert tick('<IsBatteryCharging/>', ctx) is FAILURE
    ctx.backup.record("battery", BatteryState(0.0, 12.0, 80.0, math.nan, 0.0, 0.1, POWER_SUPPLY_CHARGING))
    assert tick('<IsBatteryCharging/>', ctx) is SUCCESS


def test_is_stuck_detects_a_hard_deceleration_only():
    ctx = fake_context()
    assert tick('<IsStuck/>', ctx) is FAILURE
    ctx.backup.odom(0.2, stamp=0.00)
    ctx.backup.odom(0.2, stamp=0.02)
    assert tick('<IsStuck/>', ctx) is FAILURE  # standing or cruising is not "stuck"
    ctx.backup.odom(0.0, stamp=0.04)  # -10 m/s^2 is the limit: 0.2 m/s lost in 20 ms
    ctx.backup.streams["odom"][-1] = (0.04, ctx.backup.streams["odom"][-1][1])
    assert tick('<IsStuck/>', ctx) is FAILURE
    ctx.backup.odom(0.2, stamp=0.06)
    ctx.backup.odom(0.0, stamp=0.07)  # -20 m/s^2: a bump
    assert tick('<IsStuck/>', ctx) is SUCCESS


def test_time_expired_and_distance_traveled():
    tree, ctx = build('<TimeExpired seconds="1.0"/>')
    node = tree.root_node
    out = []
    for _ in range(9):  # every 0.25 s
        out.append(node.execute_tick())
        ctx.clock.advance(0.25)
    assert [i * 0.25 for i, r in enumerate(out) if r is SUCCESS] == [1.0, 2.0]
    ctx = fake_context()
    ctx.backup.pose(0, 0)
    tree, ctx = build('<DistanceTraveled distance="1.0"/>', ctx)
    node = tree.root_node
    out = []
    for x in (0.0, 0.5, 1.0, 1.5, 2.0, 2.1):
        ctx.backup.pose(x, 0)
        out.append(node.execute_tick())
    assert out == [FAILURE, FAILURE, SUCCESS, FAILURE, SUCCESS, FAILURE]


def test_transform_available_and_initial_pose_received():
    ctx = fake_context()
    tree, ctx = build('<TransformAvailable child="base_link" parent="map"/>', ctx)
    assert tree.tick_exactly_once() is FAILURE
    ctx.backup.pose(0, 0)
    assert tree.tick_exactly_once() is SUCCESS
    ctx.clock.advance(10.0)  # found once: stays found
    assert tree.tick_exactly_once() is SUCCESS
    assert tick('<TransformAvailable child="base_link" parent="base_scan"/>') is SUCCESS
    with pytest.raises(Exception, match="Child or parent frames not provided"):
        tick('<TransformAvailable child="base_link"/>')
    assert tick('<InitialPoseReceived/>') is FAILURE
    assert tick('<InitialPoseReceived/>', bb={"initial_pose_received": True}) is SUCCESS
    assert tick('<InitialPoseReceived initial_pose_received="{flag}"/>', bb={"flag": False}) is FAILURE


def test_a_stale_pose_is_no_pose():
    ctx = fake_context()
    ctx.backup.pose(1.0, 1.0)
    ctx.clock.advance(2.0)
    assert tick('<GoalReached goal="1;1"/>', ctx) is FAILURE
