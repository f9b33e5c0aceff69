"""The one pose reader of the node library: a fresh pose is the robot's pose, a stale one is none,
and the nodes that need a pose refuse to decide from a stale one."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from bt_runtime.runtime.messages import RobotInfo
from bt_runtime.status import NodeStatus
from nodes import register_autonomy_nodes
from nodes.robot import POSE_TIMEOUT, robot_pose
from tests.nodes.nav2.support import build, fake_context


def _node(ctx):
    return SimpleNamespace(context=ctx)


def test_fresh_pose_is_read_and_a_stale_one_counts_as_missing():
    ctx = fake_context()
    assert robot_pose(_node(ctx)) is None  # no localization yet
    ctx.backup.pose(1.0, 2.0, 0.5)
    pose = robot_pose(_node(ctx))
    assert (pose.x, pose.y, pose.yaw) == (1.0, 2.0, 0.5)
    ctx.clock.advance(POSE_TIMEOUT)
    assert robot_pose(_node(ctx)) is not None  # exactly at the limit: still usable
    ctx.clock.advance(0.01)
    assert robot_pose(_node(ctx)) is None
    assert robot_pose(_node(ctx), max_age=5.0) is not None  # a caller may accept older poses


@pytest.mark.parametrize("bad", [(float("nan"), 0.0, 0.0), (1.0, float("inf"), 0.0), (1.0, 2.0, float("nan"))])
def test_a_non_finite_pose_is_no_pose(bad):
    """Localization publishing NaN (a NaN fault, a diverged filter) gives no position to decide from."""
    ctx = fake_context()
    ctx.backup.pose(*bad)
    assert robot_pose(_node(ctx)) is None


def test_no_context_or_no_backup_is_no_pose():
    assert robot_pose(_node(None)) is None
    assert robot_pose(_node(SimpleNamespace())) is None


@pytest.mark.parametrize("stale", [False, True])
def test_contact_point_is_not_estimated_from_a_stale_pose(stale):
    ctx = fake_context()
    ctx.robot = RobotInfo()
    ctx.backup.pose(2.0, 0.0, 0.0)
    if stale:
        ctx.clock.advance(POSE_TIMEOUT + 0.5)
    tree, _ = build('<EstimateContactPoint direction="0" offset="0.1"/>', ctx, register=(register_autonomy_nodes,))
    status = tree.tick_once()
    if stale:
        assert status is NodeStatus.FAILURE
    else:
        assert status is NodeStatus.SUCCESS
        point = tree.root_blackboard.get("contact_point")
        assert point.x == pytest.approx(2.0 + ctx.robot.radius + 0.1) and point.y == pytest.approx(0.0)
