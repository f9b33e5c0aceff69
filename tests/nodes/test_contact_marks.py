"""Contact arcs from bumper segments, marks sized from the arc, and marks that grow."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_runtime.runtime.messages import Pose2D
from nodes.contact import ContactArc, ObstacleMarks, segments_arc
from sim.nav.costmap import GlobalCostmap
from sim.nav.occupancy import OccupancyGrid
from sim.nav.params import PlannerParams
from sim.nav.planner import GridPlanner
from sim.robot import load_profile

BURGER = load_profile("burger").bumper.spans()  # front, left, rear, right (90 deg each)


def test_one_pressed_segment_gives_its_span():
    middle, half = segments_arc(BURGER, (0,))
    assert middle == pytest.approx(0.0) and half == pytest.approx(math.pi / 4)
    middle, half = segments_arc(BURGER, (3,))
    assert middle == pytest.approx(-math.pi / 2) and half == pytest.approx(math.pi / 4)


def test_two_neighbouring_segments_give_the_corner_arc_across_both():
    middle, half = segments_arc(BURGER, (0, 1))  # front and left: a front-left corner hit
    assert middle == pytest.approx(math.pi / 4) and half == pytest.approx(math.pi / 2)
    middle, half = segments_arc(BURGER, (2, 3))  # rear and right: the arc wraps through -pi
    assert middle == pytest.approx(-3 * math.pi / 4) and half == pytest.approx(math.pi / 2)


def test_unknown_or_no_segments_give_no_arc():
    assert segments_arc(BURGER, ()) is None
    assert segments_arc(BURGER, (7,)) is None
    assert segments_arc((), (0,)) is None


def test_the_mark_covers_the_chord_plus_the_margin():
    arc = ContactArc(0.0, 0.0, 0.0, math.pi / 4, 0.1)
    pts = arc.chord(0.3, 0.1)
    ys = [y for _, y in pts]
    half_chord = 0.3 * math.sin(math.pi / 4)
    assert min(ys) < -half_chord - 0.05 and max(ys) > half_chord + 0.05  # past both ends
    assert all(math.hypot(x, y) == pytest.approx(0.3) for x, y in pts)
    gaps = [math.dist(a, b) for a, b in zip(pts, pts[1:])]
    assert max(gaps) <= 0.1 + 1e-9  # no hole a robot could think is free


def test_a_second_hit_near_a_mark_grows_it_and_a_far_one_starts_another():
    marks = ObstacleMarks()
    first, discs = marks.place([(1.0, 0.0), (1.0, 0.1)], 0.1, 0.3)
    assert first == 0 and len(discs) == 2
    grown, discs = marks.place([(1.0, 0.3), (1.0, 0.4)], 0.1, 0.3)
    assert grown == 0 and len(discs) == 2 and len(marks.marks[0].discs) == 4
    again, discs = marks.place([(1.0, 0.0)], 0.1, 0.3)  # the same spot: nothing new to send
    assert again == 0 and discs == []
    other, _ = marks.place([(3.0, 3.0)], 0.1, 0.3)
    assert other == 1 and len(marks.marks) == 2


def _corridor() -> OccupancyGrid:
    """A 4 m corridor, free for y in [0.1, 1.2] (walls below and above)."""
    data = np.zeros((26, 80), np.int8)
    data[:2, :] = 100
    data[24:, :] = 100
    return OccupancyGrid(data, 0.05, (0.0, 0.0, 0.0))


def _marked_corridor(disc: float, margin: float) -> GridPlanner:
    """A burger drove along y = 0.5 into the top-left corner (1.9, 0.45) of a 0.3 m box that
    stands against the lower wall; its front segment closed. Marks as MarkObstacle makes them."""
    radius = 0.105
    x = 1.9 - math.sqrt(radius**2 - 0.05**2)
    arc = ContactArc(x, 0.5, *segments_arc(BURGER, (0,)), radius)
    costmap = GlobalCostmap(_corridor(), radius)
    _, discs = ObstacleMarks().place(arc.chord(radius + disc, margin), disc, 0.3)
    for dx, dy, r in discs:
        costmap.add_obstacle(dx, dy, r)
    assert min(math.hypot(dx - 1.9, dy - 0.45) - r for dx, dy, r in discs) < 0.05  # covers the contact
    return GridPlanner(costmap, PlannerParams())


def test_marks_leave_open_the_corridor_the_box_leaves_open():
    """The box leaves 0.75 m of the corridor free; the mark of the corner hit (the tree's 0.1 m
    discs, 0.05 m margin) must not close it, as the earlier 0.2 m discs with 0.1 m did."""
    start, goal = Pose2D(0.5, 0.7), Pose2D(3.5, 0.7)
    assert _marked_corridor(0.1, 0.05).plan(start, goal).ok
    assert not _marked_corridor(0.2, 0.1).plan(start, goal).ok


def test_a_touch_off_to_one_side_is_marked_further_on_that_side():
    """A waffle's front-left segment closed while heading east: the obstacle lies to the
    left (had it reached across the path the front segment would have closed), so the mark
    reaches `outward` further left, not to the right; a head-on touch stays symmetric."""
    spans = load_profile("waffle").bumper.spans()
    middle, half = segments_arc(spans, (1,))  # front_left
    arc = ContactArc(0.0, 0.0, middle, half, 0.22, heading=0.0)
    plain = arc.chord(0.32, 0.05)
    wide = arc.chord(0.32, 0.05, outward=0.15)
    assert min(y for _, y in wide) == pytest.approx(min(y for _, y in plain))  # the path side unchanged
    assert max(math.atan2(y, x) for x, y in wide) > max(math.atan2(y, x) for x, y in plain) + 0.4
    ahead = ContactArc(0.0, 0.0, *segments_arc(spans, (0,)), 0.22, heading=0.0)
    assert ahead.chord(0.32, 0.05, outward=0.15) == ahead.chord(0.32, 0.05)
    assert ContactArc(0.0, 0.0, middle, half, 0.22).chord(0.32, 0.05, 0.15) == plain  # heading unknown


def test_rows_behind_the_arc_make_the_mark_deeper_not_wider():
    """A 0.3 m box touched at its near face extends 0.3 m behind it: the mark gets parallel
    rows up to `depth` behind the arc, along the contact bearing, and no wider across it."""
    arc = ContactArc(0.0, 0.0, 0.0, 0.35, 0.155)  # touched straight ahead (+x)
    row = arc.chord(0.255, 0.05)
    deep = arc.behind(row, 0.2, 0.1)
    assert len(deep) == 3 * len(row) and deep[:len(row)] == row
    assert max(x for x, _ in deep) == pytest.approx(max(x for x, _ in row) + 0.2)
    assert min(y for _, y in deep) == pytest.approx(min(y for _, y in row))
    assert max(y for _, y in deep) == pytest.approx(max(y for _, y in row))
    assert arc.behind(row, 0.0, 0.1) == row


def test_a_box_touched_at_its_corner_is_covered_behind_the_corner():
    """A rosbot drove north into the bottom corner of a 0.3 m box turned 45 degrees (a
    diamond): the arc alone leaves the box's side corners and middle unmarked (a re-plan around
    the mark's end touched them again); with 0.2 m of rows behind it every part of the box lies
    within the robot's radius of a disc, so a path that keeps the robot's radius from the discs
    cannot touch the box."""
    radius, disc = 0.155, 0.1
    corner = (0.0, 0.0)
    box = [corner, (0.212, 0.212), (0.0, 0.424), (-0.212, 0.212)]
    arc = ContactArc(0.0, -radius, math.pi / 2, 0.35, radius, heading=math.pi / 2)
    row = arc.chord(radius + disc, 0.05)

    def uncovered(points):
        samples = [(a[0] + (b[0] - a[0]) * k / 10, a[1] + (b[1] - a[1]) * k / 10)
                   for a, b in zip(box, box[1:] + box[:1]) for k in range(10)]
        return [p for p in samples
                if min(math.hypot(p[0] - x, p[1] - y) for x, y in points) > disc + radius]

    assert uncovered(row)  # the arc alone
    assert not uncovered(arc.behind(row, 0.2, disc))
