"""The goal hand-off: a sender writes PENDING, the tree works while PENDING/ACTIVE and ends it."""

from __future__ import annotations

import pytest

from bt_runtime.status import NodeStatus
from nodes import register_autonomy_nodes
from tests.nodes.nav2.support import build

S, F = NodeStatus.SUCCESS, NodeStatus.FAILURE


@pytest.mark.parametrize(("status", "expected"), [("PENDING", S), ("ACTIVE", S), ("SUCCEEDED", F),
                                                  ("ABORTED", F), ("REFUSED", F), ("", F)])
def test_goal_pending_while_open(status, expected):
    tree, _ = build("<GoalPending/>", register=(register_autonomy_nodes,), bb_init={"goal_status": status})
    assert tree.tick_once() is expected


def test_goal_pending_without_any_status_is_no_goal():
    tree, _ = build("<GoalPending/>", register=(register_autonomy_nodes,))
    assert tree.tick_once() is F


@pytest.mark.parametrize(("before", "after"), [("PENDING", "ABORTED"), ("ACTIVE", "ABORTED"),
                                               ("REFUSED", "REFUSED"), ("SUCCEEDED", "SUCCEEDED")])
def test_abort_only_if_open_keeps_a_final_status(before, after):
    tree, _ = build('<SetGoalStatus status="ABORTED" only_if_open="true"/>', register=(register_autonomy_nodes,),
                    bb_init={"goal_status": before})
    assert tree.tick_once() is S
    assert tree.root_blackboard.get("goal_status") == after


def test_set_goal_status_overwrites_by_default():
    tree, _ = build('<SetGoalStatus status="ACTIVE"/>', register=(register_autonomy_nodes,),
                    bb_init={"goal_status": "SUCCEEDED"})
    assert tree.tick_once() is S
    assert tree.root_blackboard.get("goal_status") == "ACTIVE"


def test_a_goal_runs_pending_to_active_to_succeeded_through_one_tree():
    xml = ('<Sequence><GoalPending/><SetGoalStatus status="ACTIVE" only_if_open="true"/>'
           '<SetGoalStatus status="SUCCEEDED" only_if_open="true"/></Sequence>')
    tree, _ = build(xml, register=(register_autonomy_nodes,), bb_init={"goal_status": "PENDING"})
    assert tree.tick_once() is S
    assert tree.root_blackboard.get("goal_status") == "SUCCEEDED"
    assert tree.tick_once() is F  # nothing left to do: the goal is closed
