"""Safety zones (collision_monitor semantics): each action type and shape on synthetic scans."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_runtime.runtime.messages import LaserScan, RobotInfo, Twist
from bt_runtime.runtime.safety_zones import INVALID_SOURCE, STREAM, SafetyZones
from bt_runtime.runtime.safety_zones_config import default_config, from_parameters

N = 720
INC = 2 * math.pi / N


def scan(points=(), *, stamp=0.0, extra=None, range_min=0.05, range_max=10.0) -> LaserScan:
    """A scan whose beams hit the given (x, y) points of the sensor frame (nearest beam each)."""
    ranges = np.full(N, np.inf)
    for x, y in points:
        k = round(math.atan2(y, x) / INC) % N
        ranges[k] = min(ranges[k], math.hypot(x, y))
    if extra:
        for k, value in extra.items():
            ranges[k] = value
    return LaserScan(stamp, 0.0, INC, range_min, range_max, ranges)


def wall(x, half_width, step=0.01):
    """Points on the line x = const within |y| <= half_width."""
    return [(x, y) for y in np.arange(-half_width, half_width + 1e-9, step)]


def monitor(polygons: dict, *, order=None, source_timeout=1.0, mount=(0.0, 0.0, 0.0), **node):
    params = {"source_timeout": source_timeout, "polygons": order or list(polygons), **polygons,
              "observation_sources": ["scan"], "scan": {"type": "scan", "topic": "scan"}, **node}
    clock = [0.0]
    zones = SafetyZones(from_parameters(params, "test"), clock=lambda: clock[0], lidar_mount=mount)
    return zones


STOP_BOX = {"type": "polygon", "points": "[[0.4, 0.2], [0.4, -0.2], [0.0, -0.2], [0.0, 0.2]]",
            "action_type": "stop", "min_points": 4}


def test_stop_polygon_zeroes_the_command_only_with_min_points_inside():
    zones = monitor({"Stop": STOP_BOX})
    zones.on_scan(scan([(0.3, y) for y in (-0.03, -0.01, 0.01)]))  # 3 points: below min_points
    assert zones.filter(Twist(0.2, 0.3), 0.1) == Twist(0.2, 0.3)
    assert not zones.state.triggered
    zones.on_scan(scan(wall(0.3, 0.05)))
    assert zones.filter(Twist(0.2, 0.3), 0.1, "nav") == Twist(0.0, 0.0)
    assert (zones.state.action, zones.state.zone, zones.state.source) == ("stop", "Stop", "nav")
    assert zones.state.points >= 4
    zones.on_scan(scan(wall(0.5, 0.05)))  # beyond the box
    assert zones.filter(Twist(0.2, 0.3), 0.2) == Twist(0.2, 0.3)
    assert zones.state.action == "none"


def test_polygon_inside_test_follows_the_outline_of_a_concave_shape():
    # an L: the notch at x > 0.2, y > 0.1 is outside
    ell = {"type": "polygon", "action_type": "stop", "min_points": 1,
           "points": "[[0, -0.3], [0.5, -0.3], [0.5, 0.1], [0.2, 0.1], [0.2, 0.3], [0, 0.3]]"}
    zones = monitor({"L": ell})
    shape = zones.zones[0].shape
    xs = np.array([0.1, 0.35, 0.35, 0.1, 0.6, -0.05, 0.45])
    ys = np.array([0.2, 0.2, -0.2, -0.25, 0.0, 0.0, 0.05])
    assert shape.inside(xs, ys).tolist() == [True, False, True, True, False, False, True]


def test_circle_counts_points_strictly_inside_its_radius():
    zones = monitor({"Ring": {"type": "circle", "radius": 0.3, "action_type": "stop", "min_points": 4}})
    ring = [(r * math.cos(a), r * math.sin(a)) for a in np.linspace(0, 2 * math.pi, 40, endpoint=False)
            for r in (0.31,)]
    zones.on_scan(scan(ring))
    assert zones.filter(Twist(0.1, 0.0), 0.1) == Twist(0.1, 0.0)
    zones.on_scan(scan([(-0.2, y) for y in (-0.04, -0.02, 0.0, 0.02)]))  # behind: circles see all round
    assert zones.filter(Twist(0.1, 0.0), 0.1) == Twist(0.0, 0.0)


def test_slowdown_scales_both_speeds_by_the_ratio():
    zones = monitor({"Slow": {**STOP_BOX, "action_type": "slowdown", "slowdown_ratio": 0.3}})
    zones.on_scan(scan(wall(0.3, 0.1)))
    out = zones.filter(Twist(0.2, -0.5), 0.1)
    assert out.linear == pytest.approx(0.06) and out.angular == pytest.approx(-0.15)
    assert zones.state.action == "slowdown"
    assert zones.filter(Twist(0.0, 0.0), 0.2) == Twist(0.0, 0.0)
    assert not zones.state.triggered  # a zero command is not slowed: nothing acted


def test_limit_caps_speeds_keeping_the_curvature():
    zones = monitor({"Lim": {**STOP_BOX, "action_type": "limit", "linear_limit": 0.1, "angular_limit": 0.4}})
    zones.on_scan(scan(wall(0.3, 0.1)))
    out = zones.filter(Twist(0.4, 0.2), 0.1)  # linear ratio 0.25 is the tighter one
    assert out.linear == pytest.approx(0.1) and out.angular == pytest.approx(0.05)
    out = zones.filter(Twist(0.05, 1.6), 0.1)  # angular ratio 0.25
    assert out.linear == pytest.approx(0.0125) and out.angular == pytest.approx(0.4)
    assert zones.filter(Twist(0.05, 0.1), 0.1) == Twist(0.05, 0.1)  # within the limits
    assert zones.state.action == "none"


APPROACH = {"type": "circle", "radius": 0.1, "action_type": "approach", "min_points": 4,
            "time_before_collision": 2.0, "simulation_time_step": 0.1}


def test_approach_scales_the_command_by_the_time_left_before_a_collision():
    zones = monitor({"Foot": APPROACH})
    zones.on_scan(scan(wall(0.4, 0.3)))
    # at 0.2 m/s the footprint (r 0.1) reaches the wall at x = 0.4 in step 16 (0.32 m): t = 1.5 s
    out = zones.filter(Twist(0.2, 0.0), 0.1)
    assert out.linear == pytest.approx(0.2 * 1.5 / 2.0)
    assert zones.state.action == "approach" and zones.state.zone == "Foot"
    assert zones.filter(Twist(0.05, 0.0), 0.1) == Twist(0.05, 0.0)  # 2 s at 0.05 m/s: 0.1 m, free
    assert zones.filter(Twist(-0.2, 0.0), 0.1) == Twist(-0.2, 0.0)  # away from the wall: free
    assert zones.filter(Twist(0.0, 1.0), 0.1) == Twist(0.0, 1.0)  # turning a circle on the spot: free


def test_approach_simulates_the_arc_of_a_turning_command():
    zones = monitor({"Foot": {**APPROACH, "time_before_collision": 3.0}})
    zones.on_scan(scan([(0.25 + 0.01 * i, 0.35) for i in range(10)]))  # a bar ahead on the left
    assert zones.filter(Twist(0.2, 0.0), 0.1) == Twist(0.2, 0.0)  # straight on passes it
    left = zones.filter(Twist(0.2, 0.6), 0.1)
    assert 0.0 < left.linear < 0.2 and zones.state.action == "approach"
    assert zones.filter(Twist(0.2, -0.6), 0.1) == Twist(0.2, -0.6)  # turning away passes


def test_approach_stops_when_points_are_inside_the_footprint_already():
    zones = monitor({"Foot": APPROACH})
    zones.on_scan(scan(wall(0.08, 0.03)))
    assert zones.filter(Twist(-0.2, 0.0), 0.1) == Twist(0.0, 0.0)  # as collision_monitor: t = 0


def test_a_stop_ends_the_evaluation_and_otherwise_the_most_restrictive_wins():
    slow = {**STOP_BOX, "action_type": "slowdown", "slowdown_ratio": 0.5}
    lim = {**STOP_BOX, "action_type": "limit", "linear_limit": 0.05, "angular_limit": 1.0}
    zones = monitor({"Slow": slow, "Lim": lim})
    zones.on_scan(scan(wall(0.3, 0.1)))
    assert zones.filter(Twist(0.2, 0.0), 0.1) == Twist(0.05, 0.0)
    assert zones.state.zone == "Lim"
    assert zones.filter(Twist(0.06, 0.0), 0.1) == Twist(0.03, 0.0)
    assert zones.state.zone == "Slow"
    zones = monitor({"Slow": slow, "Stop": STOP_BOX}, order=["Slow", "Stop"])
    zones.on_scan(scan(wall(0.3, 0.1)))
    assert zones.filter(Twist(0.2, 0.0), 0.1) == Twist(0.0, 0.0)
    assert zones.state.zone == "Stop"


def test_a_stale_or_missing_scan_stops_the_robot_as_an_invalid_source():
    zones = monitor({"Stop": STOP_BOX}, source_timeout=0.5)
    assert zones.filter(Twist(0.1, 0.0), 0.0) == Twist(0.0, 0.0)  # no scan yet
    assert zones.state.zone == INVALID_SOURCE
    zones.on_scan(scan(stamp=1.0))
    assert zones.filter(Twist(0.1, 0.0), 1.4) == Twist(0.1, 0.0)
    assert zones.filter(Twist(0.1, 0.0), 1.6) == Twist(0.0, 0.0)
    assert (zones.state.action, zones.state.zone) == ("stop", INVALID_SOURCE)
    never = monitor({"Stop": STOP_BOX}, source_timeout=0.0)
    assert never.filter(Twist(0.1, 0.0), 0.0) == Twist(0.1, 0.0)  # timeout 0: not even before a scan
    never.on_scan(scan(stamp=1.0))
    assert never.filter(Twist(0.1, 0.0), 100.0) == Twist(0.1, 0.0)


def test_nan_inf_and_out_of_range_readings_are_ignored():
    zones = monitor({"Stop": STOP_BOX})
    bad = {k: v for k, v in zip(range(-5, 5), [math.nan, -math.inf, 0.01, 0.02, 0.03, 11.0, math.nan,
                                               0.04, -0.3, math.inf], strict=True)}
    zones.on_scan(scan(extra=bad, range_min=0.05, range_max=10.0))
    assert zones.filter(Twist(0.1, 0.0), 0.1) == Twist(0.1, 0.0)


def test_points_are_moved_into_the_base_frame_with_the_lidar_mount():
    ring = {"Ring": {"type": "circle", "radius": 0.2, "action_type": "stop", "min_points": 4}}
    points = wall(0.25, 0.02)  # 0.25 m ahead of the lidar
    at_centre = monitor(ring)
    at_centre.on_scan(scan(points))
    assert at_centre.filter(Twist(0.1, 0.0), 0.1) == Twist(0.1, 0.0)
    behind = monitor(ring, mount=(-0.1, 0.0, 0.0))  # the lidar 0.1 m behind the centre: 0.15 m ahead
    behind.on_scan(scan(points))
    assert behind.filter(Twist(0.1, 0.0), 0.1) == Twist(0.0, 0.0)
    turned = monitor(ring, mount=(0.0, 0.0, math.pi))  # a lidar mounted backwards: base x = -0.25
    turned.on_scan(scan([(-0.15, y) for y in np.arange(-0.02, 0.021, 0.01)]))  # base x = +0.15
    assert turned.filter(Twist(0.1, 0.0), 0.1) == Twist(0.0, 0.0)


def test_disabled_zones_sources_and_monitor_do_not_act():
    zones = monitor({"Stop": {**STOP_BOX, "enabled": False}})
    zones.on_scan(scan(wall(0.3, 0.1)))
    assert zones.filter(Twist(0.1, 0.0), 0.1) == Twist(0.1, 0.0)
    off = monitor({"Stop": STOP_BOX}, enabled=False)
    assert off.filter(Twist(0.1, 0.0), 5.0) == Twist(0.1, 0.0)  # not even a missing scan stops it
    blind = monitor({"Stop": {**STOP_BOX, "sources_names": []}})
    blind.on_scan(scan(wall(0.3, 0.1)))
    assert blind.filter(Twist(0.1, 0.0), 0.1) == Twist(0.1, 0.0)


def test_state_changes_go_to_the_backup_for_the_tree():
    recorded = []

    class Backup:
        def record(self, stream, message, stamp):
            recorded.append((stream, message.action, message.zone, stamp))

    zones = monitor({"Stop": STOP_BOX})
    zones.backup = Backup()
    zones.on_scan(scan(wall(0.3, 0.1)))
    for t in (0.1, 0.2, 0.3):
        zones.filter(Twist(0.1, 0.0), t)
    zones.on_scan(scan())
    zones.filter(Twist(0.1, 0.0), 0.4)
    assert recorded == [(STREAM, "stop", "Stop", 0.1), (STREAM, "none", "", 0.4)]


def test_default_zones_are_sized_from_the_robot_and_keep_it_off_a_wall():
    robot = RobotInfo(radius=0.155, max_linear=0.9, max_linear_accel=1.0, lidar_x=0.02)
    zones = SafetyZones.for_robot(robot, default_config(robot), clock=lambda: 0.0)
    assert [(z.name, z.action) for z in zones.zones] == [
        ("PolygonStop", "stop"), ("PolygonSlow", "slowdown"), ("FootprintApproach", "approach")]
    zones.on_scan(scan(wall(0.6, 0.4)))  # 0.58 m ahead of the centre
    fast = zones.filter(Twist(0.9, 0.0), 0.1)
    assert 0.0 < fast.linear < 0.9 and zones.state.zone == "FootprintApproach"
    zones.on_scan(scan(wall(0.17, 0.3)))  # 1.5 cm from the front of a 0.155 m robot
    assert zones.filter(Twist(0.2, 0.0), 0.1) == Twist(0.0, 0.0)
    assert zones.filter(Twist(-0.2, 0.0), 0.1).linear < 0.0  # backing away stays allowed
    assert zones.filter(Twist(0.0, 1.0), 0.1).angular > 0.0  # and so does turning on the spot


def test_a_scan_that_cannot_be_read_is_dropped_and_goes_stale():
    zones = monitor({"Stop": STOP_BOX}, source_timeout=0.5)
    zones.on_scan(scan(stamp=0.0))
    zones.on_scan(LaserScan(0.3, 0.0, INC, 0.05, 10.0, np.array(["not", "ranges"])))  # logged, not raised
    assert zones.filter(Twist(0.1, 0.0), 0.4) == Twist(0.1, 0.0)  # the last good scan still counts
    assert zones.filter(Twist(0.1, 0.0), 0.6) == Twist(0.0, 0.0)  # until it is stale


def test_a_velocity_polygon_uses_the_sub_polygon_of_the_command():
    forward = {"points": "[[0.35, 0.3], [0.35, -0.3], [-0.2, -0.3], [-0.2, 0.3]]",
               "linear_min": 0.0, "linear_max": 1.0, "theta_min": -1.0, "theta_max": 1.0}
    backward = {"points": "[[0.2, 0.3], [0.2, -0.3], [-0.35, -0.3], [-0.35, 0.3]]",
                "linear_min": -1.0, "linear_max": 0.0, "theta_min": -1.0, "theta_max": 1.0}
    zones = monitor({"Vel": {"type": "velocity_polygon", "action_type": "stop", "min_points": 4,
                             "velocity_polygons": ["forward", "backward"], "forward": forward,
                             "backward": backward}})
    zones.on_scan(scan(wall(0.3, 0.1)))  # inside the forward shape only
    assert zones.filter(Twist(-0.2, 0.0), 0.1) == Twist(-0.2, 0.0)  # backing away: the backward shape
    assert zones.filter(Twist(0.2, 0.0), 0.1) == Twist(0.0, 0.0)
    assert zones.state.zone == "Vel"
    assert zones.filter(Twist(0.2, 3.0), 0.1) == Twist(0.0, 0.0)  # covered by none: the last shape stays
    fresh = monitor({"Vel": {"type": "velocity_polygon", "action_type": "stop", "min_points": 4,
                             "velocity_polygons": ["forward"], "forward": forward}})
    fresh.on_scan(scan(wall(0.3, 0.1)))
    assert fresh.filter(Twist(0.2, 3.0), 0.1) == Twist(0.2, 3.0)  # no shape chosen yet: not evaluated


def test_a_holonomic_velocity_polygon_reads_speed_and_direction():
    ahead = {"points": "[[0.4, 0.3], [0.4, -0.3], [0.0, -0.3], [0.0, 0.3]]", "linear_min": 0.0, "linear_max": 1.0,
             "theta_min": -1.0, "theta_max": 1.0, "direction_start_angle": -0.5, "direction_end_angle": 0.5}
    behind = {"points": "[[0.0, 0.3], [0.0, -0.3], [-0.4, -0.3], [-0.4, 0.3]]", "linear_min": 0.0,
              "linear_max": 1.0, "theta_min": -1.0, "theta_max": 1.0, "direction_start_angle": 2.5,
              "direction_end_angle": -2.5}  # wraps through pi
    zones = monitor({"Vel": {"type": "velocity_polygon", "action_type": "stop", "holonomic": True,
                             "velocity_polygons": ["ahead", "behind"], "ahead": ahead, "behind": behind}})
    zones.on_scan(scan(wall(-0.3, 0.1)))
    assert zones.filter(Twist(0.2, 0.0), 0.1) == Twist(0.2, 0.0)
    assert zones.filter(Twist(-0.2, 0.0), 0.1) == Twist(0.0, 0.0)
