"""Contact arcs from bumper segments, marks sized from the arc, and marks that grow."""

from __future__ import annotations

import math

import pytest

from nodes.contact import ContactArc, ObstacleMarks, segments_arc
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
