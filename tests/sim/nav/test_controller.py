"""sim.nav.controller and sim.nav.behaviors as plain synchronous units."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_runtime.runtime.messages import NavErrorCode, Pose2D, Twist
from sim.nav.behaviors import BackUp, DriveOnHeading, Spin
from sim.nav.controller import GoalChecker, NoValidControl, ProgressChecker, RegulatedPurePursuit
from sim.nav.costmap import GlobalCostmap, LocalCostmap
from sim.nav.occupancy import OccupancyGrid
from sim.nav.params import BehaviorParams, ControllerParams, RobotParams

HOME = Pose2D(2.0, 3.0, 0.0)


def setup(pose=HOME):
    grid = OccupancyGrid(np.zeros((120, 200), np.int8), 0.05, (0.0, 0.0, 0.0))
    lc = LocalCostmap(GlobalCostmap(grid, 0.1), 0.1)
    lc.update(pose)
    rpp = RegulatedPurePursuit(ControllerParams(), RobotParams(), lc)
    return rpp, lc


def straight(x0=2.0, x1=5.0, y=3.0, yaw=0.0):
    xs = np.arange(x0, x1 + 1e-9, 0.05)
    return np.column_stack([xs, np.full_like(xs, y), np.full_like(xs, yaw)])


def test_tracks_a_straight_path_at_the_desired_speed():
    rpp, _ = setup()
    rpp.set_plan(straight())
    cmd = rpp.compute(Pose2D(2.0, 3.0, 0.0), Twist(0.25, 0.0), GoalChecker())
    assert cmd.linear == pytest.approx(0.25) and abs(cmd.angular) < 1e-9
    # off to the right of the path: steer left
    cmd = rpp.compute(Pose2D(2.2, 2.9, 0.0), Twist(0.25, 0.0), GoalChecker())
    assert cmd.angular > 0.05 and cmd.linear > 0.2


def test_rotates_in_place_towards_a_path_behind():
    rpp, _ = setup()
    rpp.set_plan(straight())
    cmd = rpp.compute(Pose2D(2.0, 3.0, math.pi - 0.3), Twist(0.0, 0.0), GoalChecker())
    assert cmd.linear == 0.0 and cmd.angular < 0  # shortest way round is clockwise
    assert abs(cmd.angular) <= 3.2 / 20 + 1e-9  # accel-limited from standstill


def test_rotates_to_the_goal_heading_at_the_goal():
    rpp, _ = setup(Pose2D(4.9, 3.0, 0.0))
    rpp.set_plan(np.column_stack([straight(x0=4.5)[:, :2], np.full(11, 1.5)]))
    cmd = rpp.compute(Pose2D(4.9, 3.0, 0.0), Twist(0.0, 0.9), GoalChecker())
    assert cmd.linear == 0.0 and cmd.angular > 0.5
    assert rpp.is_rotating_to_heading


def test_slows_down_on_approach_and_obeys_speed_limits():
    rpp, _ = setup(Pose2D(4.7, 3.0, 0.0))
    rpp.set_plan(straight(x0=4.0))
    cmd = rpp.compute(Pose2D(4.6, 3.0, 0.0), Twist(0.25, 0.0), GoalChecker(xy_tolerance=0.05))
    assert cmd.linear == pytest.approx(0.25 * 0.4 / 0.6)  # approach_velocity_scaling_dist
    rpp2, _ = setup()
    rpp2.set_plan(straight())
    rpp2.set_speed_limit(0.1)
    assert rpp2.compute(Pose2D(2.0, 3.0), Twist(), GoalChecker()).linear == pytest.approx(0.1)
    rpp2.set_speed_limit(50.0, percentage=True)
    assert rpp2.compute(Pose2D(2.0, 3.0), Twist(), GoalChecker()).linear == pytest.approx(0.125)
    rpp2.set_speed_limit(None)
    rpp2.set_desired_speed(0.2)
    assert rpp2.compute(Pose2D(2.0, 3.0), Twist(), GoalChecker()).linear == pytest.approx(0.2)
    rpp2.set_desired_speed(5.0)  # capped by the robot's max (0.3)
    assert rpp2.compute(Pose2D(2.0, 3.0), Twist(), GoalChecker()).linear == pytest.approx(0.3)


def test_collision_ahead_raises_no_valid_control():
    rpp, lc = setup()
    rpp.set_plan(straight())
    lc.add_phantom(2.3, 3.0, 0.05)
    with pytest.raises(NoValidControl):
        rpp.compute(Pose2D(2.0, 3.0, 0.0), Twist(0.25, 0.0), GoalChecker())


def test_a_robot_inside_an_inflated_zone_may_drive_out_but_not_deeper():
    """Beside its own collision mark the robot's cell is inscribed; Nav2's RPP would refuse every
    command there. Ours lets it follow a path that does not take it deeper, and still refuses
    one that runs into the mark."""
    rpp, lc = setup()
    lc.map.add_obstacle(2.0, 3.12, 0.02)  # a lethal cell 0.1 m from the centre: inscribed
    lc.recompose()
    assert lc.in_collision(2.0, 3.0)
    rpp.set_plan(straight())  # along the mark and away from it
    cmd = rpp.compute(Pose2D(2.0, 3.0, 0.0), Twist(0.0, 0.0), GoalChecker())
    assert cmd.linear > 0.0
    lc.map.add_obstacle(2.3, 3.0, 0.05)  # and now one straight ahead as well
    lc.recompose()
    rpp.set_plan(straight())
    with pytest.raises(NoValidControl):
        rpp.compute(Pose2D(2.0, 3.0, 0.0), Twist(0.25, 0.0), GoalChecker())


def test_goal_checker_is_stateful():
    gc = GoalChecker(0.25, 0.25, stateful=True)
    goal = Pose2D(0.0, 0.0, 0.0)
    assert not gc.is_goal_reached(Pose2D(0.3, 0.0, 0.0), goal, 0.3)
    assert not gc.is_goal_reached(Pose2D(0.2, 0.0, 1.0), goal, 0.2)  # xy latched, yaw off
    assert gc.is_goal_reached(Pose2D(0.3, 0.0, 0.1), goal, 0.3)  # drifted out but latched
    gc.reset()
    assert not gc.is_goal_reached(Pose2D(0.3, 0.0, 0.1), goal, 0.3)
    assert not GoalChecker().is_goal_reached(Pose2D(0.0, 0.0), goal, 1.5)  # path too long left


def test_progress_checker():
    pc = ProgressChecker(0.5, 10.0)
    assert pc.check(Pose2D(0, 0), 0.0)
    assert pc.check(Pose2D(0.3, 0), 9.9)
    assert not pc.check(Pose2D(0.4, 0), 10.1)
    assert pc.check(Pose2D(0.6, 0), 10.2)  # moved: new baseline
    assert pc.check(Pose2D(0.6, 0), 20.1)
    assert not pc.check(Pose2D(0.6, 0), 20.3)


def test_spin_profile():
    _, lc = setup()
    spin = Spin(1.57, BehaviorParams(), lc)
    assert spin.start(0.0, Pose2D(0, 0, 0.0)) is None
    st = spin.cycle(0.1, Pose2D(0, 0, 0.0), Pose2D(0, 0, 0.0))
    assert not st.done and st.cmd.angular == pytest.approx(1.0)  # max_rotational_vel
    st = spin.cycle(0.2, Pose2D(0, 0, 1.5), Pose2D(0, 0, 1.5))
    assert st.cmd.angular == pytest.approx(max(math.sqrt(2 * 3.2 * 0.07), 0.4))
    assert spin.cycle(0.3, Pose2D(0, 0, 1.6), Pose2D(0, 0, 1.6)).done
    neg = Spin(-3.0, BehaviorParams(), lc, time_allowance=1.0)
    neg.start(0.0, Pose2D(0, 0, 3.0))
    assert neg.cycle(0.1, Pose2D(0, 0, -3.1), Pose2D(0, 0, 0)).cmd.angular < 0  # wraps at pi
    assert neg.cycle(1.2, Pose2D(0, 0, -3.0), Pose2D(0, 0, 0)).error_code is NavErrorCode.BEHAVIOR_TIMEOUT


def test_drive_on_heading_validation_and_profile():
    _, lc = setup()
    bad = DriveOnHeading(0.5, -0.1, BehaviorParams(), lc)
    assert bad.start(0.0, Pose2D(2, 3)).error_code is NavErrorCode.INVALID_INPUT
    d = DriveOnHeading(0.5, 0.2, BehaviorParams(), lc)
    assert d.start(0.0, Pose2D(2, 3)) is None
    st = d.cycle(0.1, Pose2D(2, 3), Pose2D(2, 3))
    assert st.cmd.linear == pytest.approx(0.2)
    st = d.cycle(0.2, Pose2D(2.496, 3), Pose2D(2.496, 3))
    assert st.cmd.linear == pytest.approx(math.sqrt(2 * 2.5 * 0.004))  # decelerating to stop
    st = d.cycle(0.3, Pose2D(2.499, 3), Pose2D(2.499, 3))
    assert st.cmd.linear == pytest.approx(0.10)  # minimum_speed near the end
    assert d.cycle(0.4, Pose2D(2.5, 3), Pose2D(2.5, 3)).done


def test_backup_collision_check():
    _, lc = setup()
    lc.add_phantom(1.7, 3.0, 0.05)  # an obstacle 0.3 m behind
    b = BackUp(0.5, 0.15, BehaviorParams(), lc)
    b.start(0.0, Pose2D(2.0, 3.0, 0.0))
    st = b.cycle(0.1, Pose2D(2.0, 3.0, 0.0), Pose2D(2.0, 3.0, 0.0))
    assert st.done and st.error_code is NavErrorCode.COLLISION_AHEAD
    # touching something in front: backing away is allowed (not getting deeper)
    _, lc2 = setup()
    lc2.add_phantom(2.1, 3.0, 0.05)
    assert lc2.in_collision(2.0, 3.0)
    b2 = BackUp(0.3, 0.15, BehaviorParams(), lc2)
    b2.start(0.0, Pose2D(2.0, 3.0, 0.0))
    st = b2.cycle(0.1, Pose2D(2.0, 3.0, 0.0), Pose2D(2.0, 3.0, 0.0))
    assert not st.done and st.cmd.linear == pytest.approx(-0.15)
    fwd = DriveOnHeading(0.3, 0.15, BehaviorParams(), lc2)
    fwd.start(0.0, Pose2D(2.0, 3.0, 0.0))
    assert fwd.cycle(0.1, Pose2D(2.0, 3.0, 0.0), Pose2D(2.0, 3.0, 0.0)).error_code is NavErrorCode.COLLISION_AHEAD
