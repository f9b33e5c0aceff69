"""DockRobot / UndockRobot (opennav_docking_bt) against a fake navigation client: the goal
they send from their ports and the outputs they write for each result."""

from __future__ import annotations

import asyncio

from bt_runtime.runtime.clock import run
from bt_runtime.runtime.messages import ActionStatus, Pose2D
from bt_runtime.status import FAILURE, RUNNING, SUCCESS
from tests.nodes.nav2.support import build

DOCK = ('<DockRobot dock_id="home_dock" max_staging_time="60" success="{ok}" num_retries="{retries}" '
        'error_code_id="{code}" error_msg="{msg}"/>')


def bb(tree, key):
    return tree.root_blackboard.get(key, default=None)


def test_dock_robot_sends_the_dock_id_and_reports_success_with_retries():
    async def main():
        tree, ctx = build(DOCK)
        nav = ctx.navigation
        assert tree.tick_exactly_once() is RUNNING
        kind, _, goal = nav.calls[0]
        assert kind == "dock_robot"
        assert goal == {"use_dock_id": True, "dock_id": "home_dock", "max_staging_time": 60.0,
                        "navigate_to_staging_pose": True}
        nav.handles[0].finish()
        nav.handles[0]._result.num_retries = 2
        await asyncio.sleep(0.001)
        assert tree.tick_exactly_once() is SUCCESS
        assert (bb(tree, "ok"), bb(tree, "retries"), bb(tree, "code")) == (True, 2, 0)
    run(main(), virtual=True)


def test_dock_robot_failure_writes_the_server_code():
    async def main():
        tree, ctx = build(DOCK)
        assert tree.tick_exactly_once() is RUNNING
        ctx.navigation.handles[0].finish(ActionStatus.ABORTED, 906, "timed out waiting for charge to start")
        await asyncio.sleep(0.001)
        assert tree.tick_exactly_once() is FAILURE
        assert (bb(tree, "ok"), bb(tree, "code")) == (False, 906)
        assert "charge" in bb(tree, "msg")
    run(main(), virtual=True)


def test_dock_robot_by_pose_needs_a_pose():
    tree, ctx = build('<DockRobot use_dock_id="false" error_code_id="{code}" success="{ok}"/>')
    assert tree.tick_exactly_once() is FAILURE
    assert (bb(tree, "code"), bb(tree, "ok")) == (902, False) and not ctx.navigation.calls

    async def main():
        tree, ctx = build('<DockRobot use_dock_id="false" dock_pose="1;2" dock_type="simple_charging_dock"/>')
        assert tree.tick_exactly_once() is RUNNING
        goal = ctx.navigation.calls[0][2]
        assert goal["dock_pose"] == Pose2D(1, 2) and goal["dock_type"] == "simple_charging_dock"
        assert "dock_id" not in goal
    run(main(), virtual=True)


def test_halting_dock_robot_cancels_its_goal_and_undock_reports():
    async def main():
        tree, ctx = build(DOCK)
        assert tree.tick_exactly_once() is RUNNING
        tree.halt_tree()
        assert ctx.navigation.handles[0].cancelled
        tree, ctx = build('<UndockRobot max_undocking_time="12" success="{ok}" error_code_id="{code}"/>')
        assert tree.tick_exactly_once() is RUNNING
        assert ctx.navigation.calls[0][2] == {"dock_type": "", "max_undocking_time": 12.0}
        ctx.navigation.handles[0].finish(ActionStatus.ABORTED, 0, "lost")
        await asyncio.sleep(0.001)
        assert tree.tick_exactly_once() is FAILURE and (bb(tree, "ok"), bb(tree, "code")) == (False, 999)
    run(main(), virtual=True)
