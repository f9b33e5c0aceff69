"""Collision nodes: detection from bumper and IMU, contact point, backing out, map marks."""

from __future__ import annotations

import asyncio
import math

import pytest

from bt_runtime.runtime.messages import Imu, Pose2D
from nodes.collision import ImpactDetector
from nodes.contact import marks_of
from nodes.path import ring_candidates
from tests.helpers import tree_xml

RECOVER = ('<KeepRunningUntilFailure><ForceSuccess><Fallback><Inverter><CollisionDetected source="{src}"/>'
           '</Inverter><Sequence><StopRobot/><EstimateContactPoint offset="0.2"/>'
           '<ReverseOut speed="0.1" max_distance="0.6" clearance="0.25"/>'
           '<ReleaseRobot/></Sequence></Fallback></ForceSuccess></KeepRunningUntilFailure>')


async def test_bumper_collision_backs_out_away_from_the_contact(runtime):
    rt = await runtime(tree_xml(RECOVER.replace("{src}", "bumper")))
    sim, gate = rt.driver.sim, rt.gate
    sim.faults.invisible_obstacle(ahead=0.3, width=0.4, depth=0.2, name="box")
    for _ in range(300):  # drive into the invisible box with a tree command, like a controller would
        if rt.backup.latest("bumper") is not None and rt.backup.latest("bumper").in_contact:
            break
        gate.set_tree_command(0.15, 0.0)
        await asyncio.sleep(0.01)
    gate.clear_tree_command()
    contact_x = sim.pose.x
    await asyncio.sleep(6.0)
    bb = rt.tree.root_blackboard
    point = bb.get("contact_point")
    assert abs(bb.get("collision_direction")) < 0.3  # straight ahead
    assert point.x > contact_x  # in front of where the robot touched it
    assert sim.pose.x < contact_x - 0.2  # it backed away
    assert not rt.backup.latest("bumper").in_contact
    await rt.stop()


async def test_imu_spike_detects_a_push_from_behind(runtime):
    rt = await runtime(tree_xml(RECOVER.replace("{src}", "imu")))
    sim = rt.driver.sim
    await asyncio.sleep(1.0)
    x0 = sim.pose.x
    sim.faults.push(1.0, 0.0)  # hit from behind: pushed forward
    await asyncio.sleep(0.1)
    direction = rt.tree.root_blackboard.get("collision_direction")
    assert abs(abs(direction) - math.pi) < 0.5  # the contact was behind
    await asyncio.sleep(4.0)
    assert sim.pose.x > x0  # moved away from the contact, forwards
    await rt.stop()


def test_impact_detector_only_reads_new_samples_and_forgets_old_spikes():
    class Ctx:
        def __init__(self):
            from bt_runtime.runtime.backup import DataBackup

            self.t = 0.0
            self.backup = DataBackup(None, clock=lambda: self.t)

        def clock(self):
            return self.t

    ctx = Ctx()
    detect = ImpactDetector()
    for i in range(10):
        ctx.t = i * 0.02
        ctx.backup.record("imu", Imu(ctx.t, 0.0, 0.3, 0.0))
    assert detect(ctx, 0.25, 6.0) is None
    ctx.t = 0.3
    ctx.backup.record("imu", Imu(ctx.t, 0.0, -9.0, 1.0))  # decelerating hard: hit from the front
    magnitude, bearing = detect(ctx, 0.25, 6.0)
    assert magnitude > 9 and abs(bearing - math.atan2(-1.0, 9.0)) < 1e-9
    ctx.t = 0.6
    assert detect(ctx, 0.25, 6.0) is None


def test_ring_candidates_nearest_ring_first_facing_the_robot_first():
    goal = Pose2D(0.0, 0.0)
    cands = ring_candidates(goal, Pose2D(-2.0, 0.0), max_radius=0.3, step=0.1, directions=8)
    radii = [round(math.hypot(c.x, c.y), 6) for c in cands]
    assert radii == sorted(radii) and radii[0] == 0.1 and len(cands) == 24
    assert cands[0].x < 0 and abs(cands[0].y) < 1e-9  # first candidate faces the robot
    assert all(abs(math.atan2(-c.y, -c.x) - c.yaw) < 1e-9 for c in cands)  # each faces the goal


MARK = RECOVER.replace("<ReleaseRobot/>", '<MarkObstacle radius="0.15"/><ReleaseRobot/>')


@pytest.mark.parametrize("robot", ["rosbot2", "burger"])
async def test_an_oblique_corner_hit_is_marked_across_the_sensed_arc(runtime, robot):
    """The ROSbot senses the hit with its IMU alone, the burger with its bumper; either way the
    mark is placed from the robot's own pose estimate and covers where the body really hit."""
    rt = await runtime(tree_xml(MARK.replace("{src}", "any")), robot=robot)
    sim, gate = rt.driver.sim, rt.gate
    assert (sim.bumper is None) == (robot == "rosbot2")
    pose = sim.pose
    # a box turned 40 degrees, its corner 0.12 m left of the robot's path
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    ahead, left = sim.profile.radius + 0.35, 0.12
    sim.faults.invisible_obstacle(x=pose.x + c * ahead - s * left, y=pose.y + s * ahead + c * left,
                                  yaw=pose.yaw + math.radians(40), width=0.4, depth=0.4, name="box")
    for _ in range(500):
        if sim.events_of("collision"):
            break
        gate.set_tree_command(0.2, 0.0)
        await asyncio.sleep(0.01)
    gate.clear_tree_command()
    await asyncio.sleep(6.0)
    hit = sim.events_of("collision")[0].data["point"]
    discs = [d for mark in marks_of(rt.context).marks for d in mark.discs]
    assert discs, "nothing was marked"
    assert min(math.hypot(hit[0] - x, hit[1] - y) - r for x, y, r in discs) < 0.05
    assert len(sim.events_of("collision")) == 1
    await rt.stop()


async def test_a_robot_standing_beside_its_own_mark_drives_away_to_its_goal(runtime):
    """The robot's own cell is inscribed (its collision mark lies right beside it): planning and
    the controller must still let it leave, not refuse every command until the time limit."""
    xml = tree_xml('<Sequence><Delay delay_msec="500"><AlwaysSuccess/></Delay>'
                   '<NavigateToPose goal="-1.0;-2.3;0.0" error_code_id="{code}"/></Sequence>')
    rt = await runtime(xml, robot="waffle")
    sim = rt.driver.sim
    nav = rt.driver.navigation
    await nav.add_obstacle(sim.pose.x, sim.pose.y + 0.17, 0.04)
    assert nav.global_costmap.distance_field().min() == 0.0
    assert nav.global_costmap.cost_at(sim.pose.x, sim.pose.y) >= 253  # inscribed: "in collision"
    done = rt.restart_tree()
    status = await asyncio.wait_for(done, 40.0)
    assert status.name == "SUCCESS", rt.tree.root_blackboard.get("code", default=None)
    assert math.hypot(sim.pose.x + 1.0, sim.pose.y + 2.3) < 0.3
    await rt.stop()


@pytest.mark.parametrize("source, sensed", [("imu", False), ("motion", True)])
async def test_a_slow_rosbot_touch_is_sensed_from_imu_and_wheels_not_from_the_spike(runtime, source, sensed):
    """A ROSbot (no bumper) creeping into a box at 0.06 m/s makes no 6 m/s^2 IMU spike; the
    IMU against the wheels (nodes/stall.py) still senses the contact, ahead."""
    rt = await runtime(tree_xml(RECOVER.replace("{src}", source)), robot="rosbot2")
    sim, gate = rt.driver.sim, rt.gate
    assert sim.bumper is None
    await asyncio.sleep(1.0)
    sim.faults.invisible_obstacle(ahead=0.1, width=0.4, depth=0.2, name="box")
    for _ in range(400):
        if sim.events_of("collision"):
            break
        gate.set_tree_command(0.06, 0.0)
        await asyncio.sleep(0.01)
    for _ in range(100):  # keep pushing a little: a real controller would not stop at once
        gate.set_tree_command(0.06, 0.0)
        await asyncio.sleep(0.01)
    gate.clear_tree_command()
    await asyncio.sleep(0.5)
    assert sim.events_of("collision"), "the robot never reached the box"
    direction = rt.tree.root_blackboard.get("collision_direction", default=None)
    if sensed:
        assert direction is not None and abs(direction) < 0.7  # ahead
    else:
        assert direction is None
    await rt.stop()


async def test_marks_that_close_the_only_door_are_relaxed_to_what_was_sensed(runtime):
    """A mark is wider than the touch that made it (margins, the far-side extension); beside a
    doorway that can close the only way the obstacle itself leaves. RelaxCollisionMarks shrinks
    every mark to its core and marks the map again: the plan through the door exists again."""
    from bt_runtime.runtime.messages import NavErrorCode

    rt = await runtime(tree_xml('<Sequence><Delay delay_msec="500"><RelaxCollisionMarks/></Delay>'
                                '<Script code="relaxed := true"/></Sequence>'))
    nav = rt.driver.navigation
    marks = marks_of(rt.context)
    # the apartment's door at x -6.76..-5.86 in the wall at y 0.85..1.0
    wide = [(x / 100, 0.6) for x in range(-680, -579, 10)]
    core = [(-6.3, 0.6, 0.05), (-6.3, 0.65, 0.05)]
    marks.place(wide, 0.1, 0.3, core=core, touch=core[:1])
    for x, y in wide:
        await nav.add_obstacle(x, y, 0.1)
    start, goal = Pose2D(-6.3, -1.0, 1.57), Pose2D(-6.3, 2.0, 1.57)
    before = await nav.compute_path_to_pose(goal, start=start, use_start=True)
    assert before.error_code == NavErrorCode.NO_VALID_PATH
    await asyncio.sleep(1.5)
    assert rt.tree.root_blackboard.get("relaxed")
    assert marks.marks[0].discs == core
    after = await nav.compute_path_to_pose(goal, start=start, use_start=True)
    assert after.error_code == NavErrorCode.NONE
    await rt.stop()


def test_a_mark_relaxes_to_its_core_then_to_its_touches_and_grows_back_on_a_new_touch():
    from nodes.contact import ObstacleMarks

    marks = ObstacleMarks()
    core, touch = [(0.0, 0.0, 0.05), (0.05, 0.0, 0.05)], [(0.0, 0.0, 0.05)]
    marks.place([(0.0, 0.0), (0.1, 0.0), (0.2, 0.0)], 0.1, 0.3, core=core, touch=touch)
    assert marks.relax() and marks.marks[0].discs == core
    assert marks.relax() and marks.marks[0].discs == touch
    assert not marks.relax()  # nothing smaller left
    _, new = marks.place([(0.0, 0.2)], 0.1, 0.3, core=[(0.0, 0.15, 0.05)], touch=[(0.0, 0.15, 0.05)])
    assert new and marks.marks[0].stage == 0 and len(marks.marks) == 1
    assert marks.relax() and marks.marks[0].discs == core + [(0.0, 0.15, 0.05)]
