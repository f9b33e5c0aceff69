"""Nav2 action, service, selector and path nodes against a fake navigation client
(BtActionNode mechanics), plus the port types' string forms."""

from __future__ import annotations

import asyncio
import math

import numpy as np
import pytest

from bt_runtime.errors import XMLLoadError
from bt_runtime.runtime.clock import run
from bt_runtime.runtime.messages import ActionStatus, NavResult, Path, Pose2D
from bt_runtime.status import FAILURE, IDLE, RUNNING, SUCCESS
from nodes.nav2 import publish
from nodes.types import parse_goals, parse_path, parse_pose
from tests.nodes.nav2.support import FakeHandle, build, fake_context

A, C = ActionStatus.ABORTED, ActionStatus.CANCELED


def line(x0: float, x1: float, n: int = 11, stamp: float = 0.0) -> Path:
    xs = np.linspace(x0, x1, n)
    return Path(stamp, np.column_stack([xs, np.zeros(n), np.zeros(n)]))


def bb(tree, key):
    return tree.root_blackboard.get(key, default=None)


# -- FollowPath: the BtActionNode mechanics -------------------------------------------------------

FOLLOW = '<FollowPath path="{path}" controller_id="{ctrl}" error_code_id="{code}" error_msg="{msg}"/>'


def test_follow_path_sends_once_and_maps_results():
    tree, ctx = build(FOLLOW, bb_init={"path": line(0, 1), "ctrl": "FollowPath"})
    nav = ctx.navigation
    assert tree.tick_exactly_once() is RUNNING
    assert [c[0] for c in nav.calls] == ["follow_path"] and nav.calls[0][2]["controller_id"] == "FollowPath"
    assert tree.tick_exactly_once() is RUNNING and len(nav.calls) == 1
    nav.handles[-1].finish(A, 105, "Failed to make progress")
    assert tree.tick_exactly_once() is FAILURE
    assert bb(tree, "code") == 105 and bb(tree, "msg") == "Failed to make progress"
    assert tree.tick_exactly_once() is RUNNING  # a new activation sends a new goal
    nav.handles[-1].finish(ActionStatus.SUCCEEDED)
    assert tree.tick_exactly_once() is SUCCESS and bb(tree, "code") == 0
    tree.tick_exactly_once()
    nav.handles[-1].finish(C)
    assert tree.tick_exactly_once() is SUCCESS  # CANCELED -> SUCCESS, as Nav2
    assert len(nav.handles) == 3


def test_follow_path_passes_new_paths_to_the_running_goal():
    tree, ctx = build(FOLLOW, bb_init={"path": line(0, 1), "ctrl": "FollowPath"})
    nav = ctx.navigation
    tree.tick_exactly_once()
    h = nav.handles[0]
    tree.tick_exactly_once()
    assert h.updates == []  # the same path object: nothing to send
    tree.root_blackboard.set("path", line(0, 1, stamp=1.0))  # same poses, new stamp: a new message
    tree.tick_exactly_once()
    new = line(0, 2, stamp=2.0)
    tree.root_blackboard.set("path", new)
    tree.tick_exactly_once()
    assert len(h.updates) == 2 and h.updates[-1] is new and len(nav.handles) == 1
    tree.root_blackboard.set("path", line(0, 0, 0))  # an empty path is ignored
    tree.tick_exactly_once()
    assert len(h.updates) == 2
    tree.root_blackboard.set("ctrl", "Other")  # a new controller id: a new goal
    tree.tick_exactly_once()
    assert len(nav.handles) == 2 and nav.handles[1].kwargs["controller_id"] == "Other"
    assert nav.handles[1].args[0] is new


def test_follow_path_resends_when_the_client_cannot_update():
    class NoUpdate(FakeHandle):
        update_path = None

    tree, ctx = build(FOLLOW, bb_init={"path": line(0, 1), "ctrl": "c"})
    nav = ctx.navigation
    nav._action = lambda kind, *a, **k: (nav.handles.append(NoUpdate(kind, a, k)), nav.handles[-1])[1]
    tree.tick_exactly_once()
    tree.root_blackboard.set("path", line(0, 3, stamp=1.0))
    assert tree.tick_exactly_once() is RUNNING
    assert len(nav.handles) == 2
    nav.handles[0].finish(A, 0, "preempted")  # the old goal's result is not ours any more
    assert tree.tick_exactly_once() is RUNNING


def test_halting_follow_path_cancels_its_goal():
    tree, ctx = build(FOLLOW, bb_init={"path": line(0, 1), "ctrl": "c", "code": 105})
    tree.tick_exactly_once()
    h = ctx.navigation.handles[0]
    tree.halt_tree()
    assert h.cancelled and bb(tree, "code") == 0  # on_cancelled ran
    assert tree.root_node.status is IDLE


def test_follow_path_tracking_feedback():
    ctx = fake_context()
    ctx.backup.pose(0.5, 0.1, 0.2)
    tree, ctx = build('<FollowPath path="{path}" tracking_feedback="{fb}"/>', ctx, bb_init={"path": line(0, 1)})
    tree.tick_exactly_once()
    tree.tick_exactly_once()
    fb = bb(tree, "fb")
    assert fb.position_tracking_error == pytest.approx(0.1)  # left of the path
    assert fb.heading_tracking_error == pytest.approx(0.2)
    assert fb.remaining_path_length == pytest.approx(0.5)
    assert fb.current_path_index == 5


def test_cancel_control_cancels_follow_path_which_then_succeeds():
    tree, ctx = build('<ReactiveSequence><FollowPath path="{path}" name="fp"/></ReactiveSequence>',
                      bb_init={"path": line(0, 1)})
    tree.tick_exactly_once()
    other, _ = build('<CancelControl/>', ctx)
    assert other.tick_exactly_once() is SUCCESS
    assert ctx.navigation.handles[0].cancelled
    assert tree.tick_exactly_once() is SUCCESS


# -- planner ---------------------------------------------------------------------------------

PLAN = ('<ComputePathToPose goal="{goal}" path="{path}" planner_id="GridBased" '
        'error_code_id="{code}"/>')


def test_compute_path_to_pose_outputs_the_path_or_an_empty_one():
    async def main():
        tree, ctx = build(PLAN, bb_init={"goal": Pose2D(3, 0)})
        nav = ctx.navigation
        planned = line(0, 3, stamp=5.0)
        nav.plan_results.append(NavResult(ActionStatus.SUCCEEDED, path=planned))
        assert tree.tick_exactly_once() is RUNNING
        await asyncio.sleep(0.001)
        assert tree.tick_exactly_once() is SUCCESS
        assert bb(tree, "path") is planned and bb(tree, "code") == 0
        assert nav.calls[0][2] == {"start": None, "planner_id": "GridBased", "use_start": False}
        nav.plan_results.append(NavResult(A, 208, "no path"))
        tree.tick_exactly_once()
        await asyncio.sleep(0.001)
        assert tree.tick_exactly_once() is FAILURE
        assert len(bb(tree, "path")) == 0 and bb(tree, "code") == 208
        # halting writes an empty path (Nav2 ComputePathToPose::halt), even when not running
        tree.root_blackboard.set("path", planned)
        tree.halt_tree()
        assert len(bb(tree, "path")) == 0
    run(main(), virtual=True)


def test_compute_path_to_pose_start_and_viapoints():
    async def main():
        tree, ctx = build('<ComputePathToPose goal="3;0" start="1;1" path="{path}"/>')
        nav = ctx.navigation
        nav.plan_results.append(NavResult(ActionStatus.SUCCEEDED, path=line(1, 3)))
        tree.tick_exactly_once()
        await asyncio.sleep(0.001)
        assert tree.tick_exactly_once() is SUCCESS
        assert nav.calls[0][2]["start"] == Pose2D(1, 1) and nav.calls[0][2]["use_start"]
        tree, ctx = build('<ComputePathToPose goal="3;0" start="1;1" use_start="false" path="{path}"/>')
        ctx.navigation.plan_results.append(NavResult(ActionStatus.SUCCEEDED, path=line(0, 3)))
        tree.tick_exactly_once()
        await asyncio.sleep(0.001)
        tree.tick_exactly_once()
        assert ctx.navigation.calls[0][2]["start"] is None
        tree, ctx = build('<ComputePathToPose goal="3;0" viapoints="1,0|2,0" path="{path}"/>')
        nav = ctx.navigation
        nav.plan_results += [NavResult(ActionStatus.SUCCEEDED, path=line(0, 1, 3)),
                             NavResult(ActionStatus.SUCCEEDED, path=line(1, 2, 3)),
                             NavResult(ActionStatus.SUCCEEDED, path=line(2, 3, 3))]
        tree.tick_exactly_once()
        await asyncio.sleep(0.01)
        assert tree.tick_exactly_once() is SUCCESS
        assert [c[1][0] for c in nav.calls] == [Pose2D(1, 0), Pose2D(2, 0), Pose2D(3, 0)]
        assert [c[2]["start"] for c in nav.calls] == [None, Pose2D(1, 0), Pose2D(2, 0)]
        assert np.allclose(bb(tree, "path").points[:, 0], [0, 0.5, 1, 1.5, 2, 2.5, 3])
    run(main(), virtual=True)


def test_compute_path_through_poses_chains_legs_with_through_poses_codes():
    async def main():
        tree, ctx = build('<ComputePathThroughPoses goals="{goals}" path="{path}" error_code_id="{code}"/>',
                          bb_init={"goals": [Pose2D(1, 0), Pose2D(2, 0)]})
        nav = ctx.navigation
        nav.plan_results += [NavResult(ActionStatus.SUCCEEDED, path=line(0, 1, 3)),
                             NavResult(A, 208, "blocked")]
        tree.tick_exactly_once()
        await asyncio.sleep(0.01)
        assert tree.tick_exactly_once() is FAILURE and bb(tree, "code") == 308
        tree.root_blackboard.set("goals", [])
        tree.tick_exactly_once()
        await asyncio.sleep(0.01)
        assert tree.tick_exactly_once() is FAILURE and bb(tree, "code") == 309
    run(main(), virtual=True)


# -- behaviours ------------------------------------------------------------------------------

@pytest.mark.parametrize(("xml", "kind", "args", "kwargs", "stack_code", "nav2_code", "recovery"), [
    ('<Spin spin_dist="1.57" error_code_id="{code}"/>', "spin", (1.57,), {"time_allowance": 10.0}, 703, 703, 1),
    ('<Spin spin_dist="-3" is_recovery="false" disable_collision_checks="true" error_code_id="{code}"/>',
     "spin", (-3.0,), {"time_allowance": 10.0, "disable_collision_checks": True}, 701, 701, 0),
    ('<BackUp backup_dist="0.30" backup_speed="0.15" error_code_id="{code}"/>', "backup", (0.3, 0.15),
     {"time_allowance": 10.0}, 703, 714, 1),
    ('<DriveOnHeading dist_to_travel="2.0" speed="0.2" time_allowance="12" error_code_id="{code}"/>',
     "drive_on_heading", (2.0, 0.2), {"time_allowance": 12.0}, 704, 724, 0),
    ('<Wait wait_duration="-5.0" error_code_id="{code}"/>', "wait", (5.0,), {}, 700, 740, 1),
])
def test_behaviour_goals_codes_and_recovery_count(xml, kind, args, kwargs, stack_code, nav2_code, recovery):
    tree, ctx = build(xml, bb_init={"number_recoveries": 0})
    assert tree.tick_exactly_once() is RUNNING
    h = ctx.navigation.handles[0]
    assert (h.kind, h.args, h.kwargs) == (kind, args, kwargs)
    h.finish(A, stack_code)
    assert tree.tick_exactly_once() is FAILURE
    assert bb(tree, "code") == nav2_code and bb(tree, "number_recoveries") == recovery


# -- services --------------------------------------------------------------------------------

def test_clear_entire_costmap_picks_the_costmap_and_counts_a_recovery():
    async def main():
        for service, which in (("local_costmap/clear_entirely_local_costmap", "local"),
                               ("global_costmap/clear_entirely_global_costmap", "global"), ("", "both")):
            tree, ctx = build(f'<ClearEntireCostmap service_name="{service}"/>')
            assert tree.tick_exactly_once() is RUNNING
            await asyncio.sleep(0.001)
            assert tree.tick_exactly_once() is SUCCESS
            assert ctx.navigation.clears == [which] and bb(tree, "number_recoveries") == 1
    run(main(), virtual=True)


def test_a_service_without_an_answer_in_server_timeout_fails():
    async def main():
        ctx = fake_context()
        ctx.clock = asyncio.get_running_loop().time
        ctx.navigation.service_delay = 1.0
        tree, ctx = build('<ClearEntireCostmap service_name="local_costmap/x" server_timeout="100"/>', ctx)
        statuses = []
        for _ in range(20):
            statuses.append(tree.tick_exactly_once())
            if statuses[-1] is not RUNNING:
                break
            await asyncio.sleep(0.01)
        assert statuses[-1] is FAILURE and 10 <= len(statuses) <= 12  # ~100 ms at 100 Hz
    run(main(), virtual=True)


def test_validate_path_and_the_main_tree_ports():
    async def main():
        tree, ctx = build('<ValidatePath path="{path}"/>', bb_init={"path": line(0, 1)})
        assert tree.tick_exactly_once() is SUCCESS
        assert ctx.navigation.calls[-1][2]["max_cost"] == 253
        ctx.navigation.valid = False
        assert tree.tick_exactly_once() is FAILURE
    run(main(), virtual=True)


# -- selectors -------------------------------------------------------------------------------

def test_selectors_use_the_topic_else_the_default():
    tree, ctx = build('<PlannerSelector selected_planner="{p}" default_planner="GridBased"/>')
    assert tree.tick_exactly_once() is SUCCESS and bb(tree, "p") == "GridBased"
    publish(ctx, "planner_selector", "SmacHybrid")
    assert tree.tick_exactly_once() is SUCCESS and bb(tree, "p") == "SmacHybrid"
    tree, ctx = build('<ControllerSelector selected_controller="{c}" topic_name="my_topic"/>')
    assert tree.tick_exactly_once() is FAILURE  # no default, nothing published
    publish(ctx, "my_topic", "RPP")
    assert tree.tick_exactly_once() is SUCCESS and bb(tree, "c") == "RPP"


# -- path and goal utilities -----------------------------------------------------------------

def test_truncate_path_drops_the_end_and_faces_the_goal():
    pts = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [2.5, 0.5, 0], [3, 1, 0]], dtype=float)
    tree, _ = build('<TruncatePath input_path="{p}" output_path="{out}" distance="1.0"/>',
                    bb_init={"p": Path(0.0, pts)})
    assert tree.tick_exactly_once() is SUCCESS
    out = bb(tree, "out").points
    assert len(out) == 3 and out[-1, 0] == 2.0
    assert out[-1, 2] == pytest.approx(math.atan2(1, 1))


def test_truncate_path_local_windows_the_path_around_the_robot():
    ctx = fake_context()
    ctx.backup.pose(5.0, 0.1)
    path = line(0, 10, 101)
    tree, ctx = build('<TruncatePathLocal input_path="{p}" output_path="{out}" distance_forward="2.0" '
                      'distance_backward="1.0"/>', ctx, bb_init={"p": path})
    assert tree.tick_exactly_once() is SUCCESS
    xs = bb(tree, "out").points[:, 0]
    assert xs[0] == pytest.approx(4.0) and xs[-1] == pytest.approx(7.0)
    tree, _ = build('<TruncatePathLocal input_path="{p}" output_path="{out}" distance_forward="-1" '
                    'distance_backward="0"/>', ctx, bb_init={"p": path})
    tree.tick_exactly_once()  # Nav2 main: -1 = the whole rest of the path
    xs = bb(tree, "out").points[:, 0]
    assert xs[0] == pytest.approx(5.0) and xs[-1] == pytest.approx(10.0)
    tree, _ = build('<TruncatePathLocal input_path="{p}" output_path="{out}" pose="9;0"/>',
                    fake_context(), bb_init={"p": path})
    tree.tick_exactly_once()  # the given pose instead of the robot's
    assert bb(tree, "out").points[0, 0] == pytest.approx(5.0)
    tree, _ = build('<TruncatePathLocal input_path="{p}" output_path="{out}"/>', fake_context(),
                    bb_init={"p": path})
    assert tree.tick_exactly_once() is FAILURE  # no robot pose


def test_remove_passed_goals_keeps_the_last_goal():
    ctx = fake_context()
    ctx.backup.pose(1.0, 0.0)
    goals = [Pose2D(0.8, 0), Pose2D(1.2, 0.1), Pose2D(3, 0)]
    tree, ctx = build('<RemovePassedGoals input_goals="{goals}" output_goals="{goals}" radius="0.7"/>', ctx,
                      bb_init={"goals": goals})
    assert tree.tick_exactly_once() is SUCCESS and bb(tree, "goals") == [Pose2D(3, 0)]
    ctx.backup.pose(3.0, 0.0)
    assert tree.tick_exactly_once() is SUCCESS and bb(tree, "goals") == [Pose2D(3, 0)]


def test_small_path_and_goal_utilities():
    ctx = fake_context()
    ctx.backup.pose(1.0, 2.0, 0.5)
    xml = ('<Sequence>'
           '<GetPoseFromPath path="{p}" index="-1" pose="{last}"/>'
           '<ConcatenatePaths input_path1="{p}" input_path2="{q}" output_path="{pq}"/>'
           '<GetCurrentPose current_pose="{here}"/>'
           '<AppendGoalPoseToGoals goal_pose="{last}" input_goals="{goals}" output_goals="{goals2}"/>'
           '<GetNextFewGoals num_goals="2" input_goals="{goals2}" output_goals="{few}"/>'
           '<SmoothPath unsmoothed_path="{p}" smoothed_path="{smooth}" was_completed="{done}"/>'
           '</Sequence>')
    p, q = line(0, 1, 3), line(1, 2, 3)
    tree, _ = build(xml, ctx, bb_init={"p": p, "q": q, "goals": [Pose2D(5, 5), Pose2D(6, 6)]})
    assert tree.tick_exactly_once() is SUCCESS
    assert bb(tree, "last") == Pose2D(1, 0, 0) and len(bb(tree, "pq")) == 6
    assert bb(tree, "here") == Pose2D(1.0, 2.0, 0.5)
    assert bb(tree, "few") == [Pose2D(5, 5), Pose2D(6, 6)] and len(bb(tree, "goals2")) == 3
    assert bb(tree, "smooth") is p and bb(tree, "done") is True
    tree, _ = build('<GetPoseFromPath path="{p}" index="7" pose="{x}"/>', bb_init={"p": p})
    assert tree.tick_exactly_once() is FAILURE


# -- navigator and unavailable servers ---------------------------------------------------------

def test_navigate_to_pose_and_through_poses():
    async def main():
        tree, ctx = build('<NavigateToPose goal="2;3" error_code_id="{code}"/>')
        assert tree.tick_exactly_once() is RUNNING
        ctx.navigation.handles[0].finish(A, 208)
        assert tree.tick_exactly_once() is FAILURE and bb(tree, "code") == 208
        tree, ctx = build('<NavigateThroughPoses goals="1,0|2,0"/>')
        nav = ctx.navigation
        assert tree.tick_exactly_once() is RUNNING
        await asyncio.sleep(0.001)
        nav.handles[0].finish()
        await asyncio.sleep(0.001)
        assert [h.args[0] for h in nav.handles] == [Pose2D(1, 0), Pose2D(2, 0)]
        nav.handles[1].finish()
        await asyncio.sleep(0.001)
        assert tree.tick_exactly_once() is SUCCESS
    run(main(), virtual=True)


def test_nodes_without_a_server_fail_with_their_unknown_code():
    tree, _ = build('<AssistedTeleop error_code_id="{code}"/>')
    assert tree.tick_exactly_once() is FAILURE and bb(tree, "code") == 730
    tree, _ = build('<ComputeRoute goal="1;1" error_code_id="{code}"/>')
    assert tree.tick_exactly_once() is FAILURE and bb(tree, "code") == 400


def test_actions_need_a_navigation_client():
    tree, _ = build('<Wait wait_duration="1"/>', ctx=type("Ctx", (), {"clock": staticmethod(lambda: 0.0),
                                                                      "extras": {}})())
    with pytest.raises(Exception, match="needs a runtime context with a navigation client"):
        tree.tick_exactly_once()


# -- string forms ----------------------------------------------------------------------------

def test_pose_goal_and_path_literals():
    assert parse_pose("1;2") == Pose2D(1, 2) and parse_pose("1,2,0.5") == Pose2D(1, 2, 0.5)
    p = parse_pose("0;map;1.0;2.0;0.0;0.0;0.0;0.7071068;0.7071068")  # Nav2's PoseStamped form
    assert (p.x, p.y) == (1.0, 2.0) and p.yaw == pytest.approx(math.pi / 2)
    assert parse_pose('json:{"x": 1, "y": 2, "yaw": 3}') == Pose2D(1, 2, 3)
    assert parse_pose('json:{"pose": {"position": {"x": 1, "y": 2, "z": 0}, '
                      '"orientation": {"x": 0, "y": 0, "z": 0, "w": 1}}}') == Pose2D(1, 2, 0)
    assert parse_goals("1,2|3,4,1") == [Pose2D(1, 2), Pose2D(3, 4, 1)]
    assert parse_goals("0;map;1;2;0;0;0;0;1;0;map;3;4;0;0;0;0;1") == [Pose2D(1, 2), Pose2D(3, 4)]
    assert parse_goals("") == [] and parse_goals("json:[[1, 2], [3, 4, 0.5]]") == [Pose2D(1, 2),
                                                                                   Pose2D(3, 4, 0.5)]
    path = parse_path("0;map;0;map;1;2;0;0;0;0;1;0;map;3;4;0;0;0;0;1")
    assert path.points[:, :2].tolist() == [[1, 2], [3, 4]]
    assert parse_path("json:[[0, 0], [1, 0]]").length == 1.0
    with pytest.raises(XMLLoadError, match="can not be converted"):
        build('<ComputePathToPose goal="one;two"/>')
