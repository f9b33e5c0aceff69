"""Path nodes (fn_req7, fn_req8): rating a planned path, and searching a reachable goal nearby."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_runtime.runtime.messages import ActionStatus, NavErrorCode, NavResult, Path, Pose2D, RobotInfo
from bt_runtime.status import NodeStatus
from nodes import register_autonomy_nodes
from nodes.path import ring_candidates
from nodes.robot import POSE_TIMEOUT
from tests.nodes.nav2.support import build, fake_context

S, F = NodeStatus.SUCCESS, NodeStatus.FAILURE
GOAL = Pose2D(2.0, 0.0)


def _line(*xy: tuple[float, float]) -> Path:
    return Path(0.0, np.array([[x, y, 0.0] for x, y in xy]))


def _rate(path, *, valid=True, clearance=1.0, pose=(0.0, 0.0), pose_age=0.0, **attrs):
    ctx = fake_context()
    if pose is not None:
        ctx.backup.pose(*pose)
    ctx.clock.advance(pose_age)
    ctx.navigation.valid = valid
    ctx.navigation.path_clearance = lambda _path: clearance
    extra = "".join(f' {k}="{v}"' for k, v in attrs.items())
    tree, _ = build(f'<RatePathQuality path="{{path}}" goal="{{goal}}"{extra}/>', ctx,
                    register=(register_autonomy_nodes,), bb_init={"path": path, "goal": GOAL})
    status = tree.tick_once()
    return status, tree.root_blackboard.get("path_quality")


def test_a_straight_clear_path_is_perfect():
    assert _rate(_line((0, 0), (1, 0), (2, 0))) == (S, pytest.approx(1.0))


def test_quality_falls_with_detour_and_closeness_to_obstacles():
    status, detour = _rate(_line((0, 0), (0, 1), (2, 1), (2, 0)))  # 4 m for 2 m
    assert status is S and detour == pytest.approx(0.5)
    status, tight = _rate(_line((0, 0), (2, 0)), clearance=0.1)  # 0.1 m of 0.5 m wanted
    assert status is S and tight == pytest.approx(0.2)


def test_limits_fail_the_path():
    assert _rate(_line((0, 0), (0, 3), (2, 3), (2, 0)), max_length_ratio=3.0)[0] is F  # 8 m for 2 m
    assert _rate(_line((0, 0), (2, 0)), clearance=0.1, min_clearance=0.2)[0] is F
    assert _rate(_line((0, 0), (2, 0)), valid=False) == (F, 0.0)  # blocked on the costmap


@pytest.mark.parametrize("case", ["one pose", "no pose", "stale pose"])
def test_nothing_to_rate_is_unusable(case):
    path = _line((0, 0)) if case == "one pose" else _line((0, 0), (2, 0))
    pose = None if case == "no pose" else (0.0, 0.0)
    age = POSE_TIMEOUT + 0.1 if case == "stale pose" else 0.0
    assert _rate(path, pose=pose, pose_age=age) == (F, 0.0)


def test_ring_candidates_cover_every_direction_on_each_ring():
    cands = ring_candidates(GOAL, None, max_radius=0.2, step=0.1, directions=4)
    assert len(cands) == 8
    first_ring = {(round(c.x - GOAL.x, 6), round(c.y - GOAL.y, 6)) for c in cands[:4]}
    assert first_ring == {(0.1, 0.0), (0.0, 0.1), (-0.1, 0.0), (0.0, -0.1)}  # no robot: starts at +x


def _plans(*lengths: float | NavErrorCode) -> list[NavResult | float]:
    """Planner answers in order: a number is a straight path of that length ending at the pose
    asked for, a code an abort (a NavResult is answered as it is)."""
    return [NavResult(ActionStatus.ABORTED, x, "no") if isinstance(x, NavErrorCode) else x for x in lengths]


def _search_context(plans: list[NavResult | float], clearance=lambda pose: 1.0):
    ctx = fake_context()
    ctx.robot = RobotInfo()
    ctx.backup.pose(-2.0, 0.0)
    nav = ctx.navigation
    nav.plan_results = plans
    nav.path_clearance = lambda path: clearance(Pose2D(*path.points[0]))
    answer = nav.compute_path_to_pose

    async def compute_path_to_pose(goal, **kw):
        result = await answer(goal, **kw)
        if isinstance(result, NavResult):
            return result
        return NavResult(ActionStatus.SUCCEEDED, NavErrorCode.NONE, "", _line((goal.x - result, goal.y), (goal.x, goal.y)))

    nav.compute_path_to_pose = compute_path_to_pose
    return ctx


async def _search(ctx, **attrs):
    extra = "".join(f' {k}="{v}"' for k, v in attrs.items())
    tree, _ = build(f'<FindAlternativeGoal goal="{{goal}}" step="0.5" max_radius="1.0" directions="4"{extra}/>',
                    ctx, register=(register_autonomy_nodes,), bb_init={"goal": GOAL})
    before = len(ctx.navigation.calls)
    status = await tree.tick_while_running_async()
    asked = [call[1][0] for call in ctx.navigation.calls[before:] if call[0] == "compute_path_to_pose"]
    return status, tree.root_blackboard, asked


async def test_the_cheapest_reachable_candidate_of_the_nearest_ring_wins_and_is_kept():
    no = NavErrorCode.NO_VALID_PATH
    ctx = _search_context(_plans(no, no, 5.0, 2.0))  # ring 1 (0.5 m): two unreachable, a long and a short path
    status, bb, asked = await _search(ctx, extra_rings="0")
    assert status is S and len(asked) == 4 and bb.get("alternatives_tried") == 4
    assert all(p.distance_to(GOAL) == pytest.approx(0.5) for p in asked)  # the nearest ring only
    assert asked[0].x < GOAL.x  # the candidate on the robot's side is tried first
    assert bb.get("nav_goal") == asked[3] and bb.get("path").length == pytest.approx(2.0)
    assert "0.50 m from the requested goal" in bb.get("goal_detail")
    ctx.navigation.plan_results = _plans(2.0)
    status, bb, asked_again = await _search(ctx, extra_rings="0")  # the same goal again
    assert status is S and asked_again == [asked[3]] and bb.get("alternatives_tried") == 1


async def test_candidates_too_close_to_obstacles_are_not_planned_to_while_clearer_ones_exist():
    ctx = _search_context(_plans(1.0, 1.0), clearance=lambda pose: 0.1 if abs(pose.y) > 0.01 else 1.0)
    status, bb, asked = await _search(ctx, extra_rings="0")
    assert status is S and all(abs(p.y) <= 0.01 for p in asked) and len(asked) == 2


async def test_no_reachable_candidate_fails_after_trying_them_all():
    ctx = _search_context(_plans(*[NavErrorCode.NO_VALID_PATH] * 16))
    status, bb, asked = await _search(ctx)
    assert status is F and bb.get("alternatives_tried") == 8
    assert {(round(p.x, 6), round(p.y, 6)) for p in asked} == \
        {(round(GOAL.x + r * math.cos(a), 6), round(r * math.sin(a), 6))
         for r in (0.5, 1.0) for a in (0, math.pi / 2, math.pi, -math.pi / 2)}  # every candidate was asked


async def test_a_planner_that_is_down_stops_the_search():
    ctx = _search_context(_plans(*[NavErrorCode.PLANNER_UNKNOWN] * 16))
    status, bb, asked = await _search(ctx)
    assert status is F and 1 <= len(asked) <= 2  # at most one try per clearance level, not all 8 candidates


def _ends(path_end: tuple[float, float] | None, goal: Pose2D = GOAL):
    ctx = _search_context([])
    bb = {"goal": goal, "plan_error": 0}
    if path_end is not None:
        bb["path"] = _line((0, 0), path_end)
    tree, _ = build('<PathReachesGoal path="{path}" goal="{goal}" error_code_id="{plan_error}"/>', ctx,
                    register=(register_autonomy_nodes,), bb_init=bb)
    return tree.tick_once(), tree.root_blackboard.get("plan_error")


def test_a_plan_that_ends_short_of_the_goal_reads_as_goal_occupied():
    assert _ends((GOAL.x, GOAL.y)) == (S, 0)
    assert _ends((GOAL.x - 0.05, GOAL.y)) == (S, 0)  # within one cell
    # Nav2's planner tolerance moved the end out of the obstacle the goal lies in
    assert _ends((GOAL.x - 0.35, GOAL.y)) == (F, int(NavErrorCode.GOAL_OCCUPIED))
    assert _ends(None) == (F, int(NavErrorCode.GOAL_OCCUPIED))


async def test_a_candidate_whose_plan_ends_elsewhere_is_not_an_alternative():
    no = NavErrorCode.NO_VALID_PATH
    elsewhere = NavResult(ActionStatus.SUCCEEDED, NavErrorCode.NONE, "", _line((0, 0), (1.0, 0)))
    # the first candidate is occupied: the planner's tolerance answers with a plan to elsewhere
    ctx = _search_context(_plans(elsewhere, *[no] * 7, elsewhere, *[no] * 7))
    status, bb, asked = await _search(ctx, extra_rings="0")
    assert status is F and len(asked) == 16 and not bb.get("goal_detail", default="")


async def test_planner_answers_tells_a_broken_planner_from_a_cut_off_goal():
    for plans, expected in (([NavResult(ActionStatus.SUCCEEDED, NavErrorCode.NONE, "", _line((-2, 0), (-2, 0)))], S),
                            (_plans(NavErrorCode.NO_VALID_PATH), F)):
        ctx = _search_context(plans)
        tree, _ = build("<PlannerAnswers/>", ctx, register=(register_autonomy_nodes,))
        assert await tree.tick_while_running_async() is expected
        assert ctx.navigation.calls[-1][1][0].distance_to(Pose2D(-2.0, 0.0)) < 1e-9  # asked for its own pose
