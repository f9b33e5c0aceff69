"""Battery nodes (fn_req9): the energy model, and the goal refusal it drives."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from bt_runtime.runtime.messages import Path, Pose2D, RobotInfo
from bt_runtime.status import NodeStatus
from nodes import register_autonomy_nodes
from nodes.battery import energy_for_path, path_turning
from nodes.robot import POSE_TIMEOUT
from tests.nodes.nav2.support import build, fake_context

BURGER = RobotInfo()  # 1.8 Ah, 6 W idle, 12 W per m/s, 1 W per rad/s
S, F = NodeStatus.SUCCESS, NodeStatus.FAILURE


def test_energy_is_idle_plus_driving_power_over_the_driving_time():
    # 1 m at 0.2 m/s: 5 s at 6 + 12 * 0.2 = 8.4 W -> 42 J; a half turn at 1 rad/s: pi s at 7 W
    assert energy_for_path(1.0, 0.0, 0.2, 1.0, BURGER) == pytest.approx(42.0 / 3600)
    assert energy_for_path(0.0, math.pi, 0.2, 1.0, BURGER) == pytest.approx(7.0 * math.pi / 3600)
    assert energy_for_path(0.0, 0.0, 0.2, 1.0, BURGER) == 0.0


def test_driving_slower_costs_more_because_the_idle_draw_lasts_longer():
    assert energy_for_path(2.0, 0.0, 0.05, 1.0, BURGER) > energy_for_path(2.0, 0.0, 0.2, 1.0, BURGER)


def test_path_turning_sums_heading_changes_the_short_way_round():
    straight = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    assert path_turning(straight, 0.0) == pytest.approx(0.0)
    assert path_turning(straight, math.pi) == pytest.approx(math.pi)  # facing away: turn round first
    corner = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [1.0, 1.0]])  # a repeated pose adds nothing
    assert path_turning(corner, 0.0) == pytest.approx(math.pi / 2)
    west = np.array([[0.0, 0.0], [-1.0, -0.1]])  # heading ~ -3.04 rad, robot at +3.0 rad: 0.24 rad apart
    assert path_turning(west, 3.0) == pytest.approx(abs(math.atan2(-0.1, -1.0) - 3.0 + 2 * math.pi))


def _context():
    """A fake context with what the energy model listens to: the robot's nominal constants and a
    driver to subscribe to (no battery or command messages reach it here: the prior only)."""
    ctx = fake_context()
    ctx.robot = BURGER
    ctx.driver = SimpleNamespace(subscribe=lambda stream, callback: (lambda: None))
    return ctx


def _can_reach(ctx, *, path=None, dock=None, **attrs):
    extra = "".join(f' {k}="{v}"' for k, v in attrs.items())
    bb = {"goal": Pose2D(1.0, 0.0)} | ({"path": path} if path is not None else {}) \
        | ({"dock_pose": dock} if dock is not None else {})
    ports = ' path="{path}"' if path is not None else ""  # no path: the straight line x detour
    tree, _ = build(f'<BatteryCanReach goal="{{goal}}"{ports}{extra}/>', ctx, register=(register_autonomy_nodes,),
                    bb_init=bb)
    return tree


def test_a_short_straight_path_needs_the_reserve_plus_a_little():
    ctx = _context()
    ctx.backup.pose(0.0, 0.0, 0.0)
    ctx.backup.battery(50.0, voltage=11.0)
    tree = _can_reach(ctx, path=Path(0.0, np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])))
    assert tree.tick_once() is S
    bb = tree.root_blackboard
    # nominal: 1 m at 0.22 m/s at 8.64 W = 39.3 J = 0.0109 Wh = 0.055 % of 11 V * 1.8 Ah; times the
    # learned factor (before any measurement: the prior plus its margin, so more than nominal),
    # times the safety factor 1.5, plus the 10 % reserve
    factor = bb.get("battery_energy_factor")
    assert factor > 1.0
    assert bb.get("battery_required") == pytest.approx(10.0 + 1.5 * factor * (8.64 / 0.22 / 3600) / 11.0 / 1.8 * 100)
    assert bb.get("battery_available") == 50.0


def test_a_battery_below_reserve_plus_need_refuses():
    ctx = _context()
    ctx.backup.pose(0.0, 0.0, 0.0)
    ctx.backup.battery(10.05)
    assert _can_reach(ctx).tick_once() is F


def test_a_long_detour_needs_more_than_the_straight_line():
    ctx = _context()
    ctx.backup.pose(0.0, 0.0, 0.0)
    ctx.backup.battery(80.0)
    detour = Path(0.0, np.array([[0, 0, 0], [0, 20, 0], [1, 20, 0], [1, 0, 0]], dtype=float))
    straight = _can_reach(ctx)
    long = _can_reach(ctx, path=detour)
    assert straight.tick_once() is S and long.tick_once() is S
    assert long.root_blackboard.get("battery_required") > straight.root_blackboard.get("battery_required") + 0.5


@pytest.mark.parametrize("case", ["no battery", "unknown charge", "no pose", "stale pose"])
def test_without_charge_or_position_nothing_is_promised(case):
    ctx = _context()
    if case != "no pose":
        ctx.backup.pose(0.0, 0.0, 0.0)
    if case != "no battery":
        ctx.backup.battery(math.nan if case == "unknown charge" else 90.0)
    if case == "stale pose":
        ctx.clock.advance(POSE_TIMEOUT + 0.1)
    assert _can_reach(ctx).tick_once() is F


@pytest.mark.parametrize(("percent", "status"), [(25.0, S), (20.0, F), (5.0, F), (None, F)])
def test_battery_above_is_strictly_above(percent, status):
    ctx = fake_context()
    if percent is not None:
        ctx.backup.battery(percent)
    tree, _ = build('<BatteryAbove percent="20"/>', ctx, register=(register_autonomy_nodes,))
    assert tree.tick_once() is status


def test_refuse_goal_marks_the_goal_refused():
    tree, _ = build('<RefuseGoal goal="{goal}" reason="too far"/>', register=(register_autonomy_nodes,),
                    bb_init={"goal": Pose2D(3.0, 4.0), "goal_status": "ACTIVE"})
    assert tree.tick_once() is S
    assert tree.root_blackboard.get("goal_status") == "REFUSED"


def test_the_way_back_to_the_dock_is_part_of_what_a_goal_needs():
    """A goal 1 m away is in range; with the dock 8 m beyond it, the way back (straight line x
    the detour factor, a half turn) must fit too, with the same factor and margin."""
    ctx = _context()
    ctx.backup.pose(0.0, 0.0, 0.0)
    ctx.backup.battery(11.0, voltage=11.0)
    alone = _can_reach(ctx)
    assert alone.tick_once() is S
    far_dock = _can_reach(ctx, dock=Pose2D(9.0, 0.0, 0.0))
    assert far_dock.tick_once() is F  # 1 m there is fine, 8 m back is not
    bb = far_dock.root_blackboard
    factor = bb.get("battery_energy_factor")
    back = energy_for_path(8.0 * 1.5, math.pi, 0.22, 1.0, BURGER)
    assert bb.get("battery_required") == pytest.approx(
        alone.root_blackboard.get("battery_required") + 1.5 * factor * back / 11.0 / 1.8 * 100)
    near_dock = _can_reach(ctx, dock=Pose2D(1.0, 0.2, 0.0))  # the dock beside the goal costs little
    assert near_dock.tick_once() is S


def test_the_dock_can_be_given_as_text():
    ctx = _context()
    ctx.backup.pose(0.0, 0.0, 0.0)
    ctx.backup.battery(11.0, voltage=11.0)
    assert _can_reach(ctx, dock="9.0;0.0;0.0").tick_once() is F  # e.g. run --set dock_pose=9;0;0


def test_each_new_reading_pose_or_path_is_taken_into_account_at_the_next_tick():
    """The estimate is reused only while its inputs are the same messages (ChargeUntil ticks the
    check at 100 Hz): a new battery reading, pose or path changes the answer at once."""
    ctx = _context()
    ctx.backup.pose(0.0, 0.0, 0.0)
    ctx.backup.battery(50.0, voltage=11.0)
    tree = _can_reach(ctx, path=Path(0.0, np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])))
    bb = tree.root_blackboard
    assert tree.tick_once() is S and tree.tick_once() is S
    short = bb.get("battery_required")
    ctx.backup.battery(10.05, voltage=11.0)
    assert tree.tick_once() is F
    ctx.backup.battery(50.0, voltage=11.0)
    bb.set("path", Path(0.0, np.array([[0, 0, 0], [0, 20, 0], [1, 20, 0], [1, 0, 0]], dtype=float)))
    assert tree.tick_once() is S
    detour = bb.get("battery_required")
    assert detour > short + 0.5
    ctx.backup.pose(0.0, 0.0, -math.pi / 2)  # facing away from the path's first leg: a half turn more
    tree.tick_once()
    assert bb.get("battery_required") > detour
