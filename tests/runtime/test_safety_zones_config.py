"""collision_monitor YAML files: Nav2's own load as they are, bad ones name the file and field."""

from __future__ import annotations

import textwrap

import pytest

from bt_runtime.runtime.messages import RobotInfo
from bt_runtime.runtime.safety_zones import SafetyZones
from bt_runtime.runtime.safety_zones_config import (
    SafetyZonesConfigError,
    default_config,
    load_collision_monitor,
    parse_points,
    to_yaml,
)
from tests.paths import REFERENCE, ROOT

EXAMPLE = ROOT / "docs" / "collision_monitor.example.yaml"


def write(tmp_path, text: str):
    path = tmp_path / "cm.yaml"
    path.write_text(textwrap.dedent(text))
    return path


GOOD = """\
collision_monitor:
  ros__parameters:
    base_frame_id: "base_footprint"
    source_timeout: 0.5
    polygons: ["PolygonStop", "PolygonSlow"]
    PolygonStop:
      type: "circle"
      radius: 0.2
      action_type: "stop"
      visualize: true
    PolygonSlow:
      type: "polygon"
      points: "[[0.5, 0.25], [0.5, -0.25], [0.0, -0.25], [0.0, 0.25]]"
      action_type: "slowdown"
      slowdown_ratio: 0.3
      max_points: 2
    NotListed: {type: "velocity_polygon"}
    observation_sources: ["scan"]
    scan: {type: "scan", topic: "/scan", source_timeout: 0.2}
"""


def test_a_collision_monitor_file_loads_with_its_defaults(tmp_path):
    cfg = load_collision_monitor(write(tmp_path, GOOD))
    assert cfg.polygons == ["PolygonStop", "PolygonSlow"]
    stop, slow = cfg.zones["PolygonStop"], cfg.zones["PolygonSlow"]
    assert (stop.type, stop.radius, stop.effective_min_points) == ("circle", 0.2, 4)
    assert slow.points == ((0.5, 0.25), (0.5, -0.25), (0.0, -0.25), (0.0, 0.25))
    assert slow.effective_min_points == 3  # the deprecated max_points N means min_points N + 1
    assert cfg.scan_timeout == 0.2  # the source's own timeout overrides the node's


@pytest.mark.parametrize("name", ["collision_monitor_params_main.yaml", "tb3_nav2_params_burger_jazzy+.yaml"])
def test_nav2s_shipped_parameter_files_load(name):
    path = REFERENCE / "nav2" / "params" / name
    if not path.exists():
        pytest.skip("the shared reference folder is absent")
    cfg = load_collision_monitor(path)
    assert cfg.polygons
    zones = SafetyZones.for_robot(RobotInfo(), cfg, clock=lambda: 0.0)
    # TB3's FootprintApproach follows the costmap's footprint topic: here the robot's radius
    approach = [z for z in zones.zones if z.action == "approach"]
    assert all(z.shape.radius == RobotInfo().radius for z in approach if z.cfg.points is None)


def test_the_documented_example_and_the_defaults_round_trip(tmp_path):
    example = load_collision_monitor(EXAMPLE)
    assert {z.action_type for z in example.zones.values()} >= {"stop", "slowdown", "approach"}
    defaults = default_config(RobotInfo(radius=0.155, max_linear=0.9))
    path = tmp_path / "defaults.yaml"
    path.write_text(to_yaml(defaults))
    again = load_collision_monitor(path)
    assert again.zones == defaults.zones and again.polygons == defaults.polygons
    assert {n: example.zones[n] for n in example.polygons} == defaults.zones  # the example: ROSbot's defaults


@pytest.mark.parametrize(("change", "message"), [
    (("radius: 0.2", "radiuss: 0.2"), "PolygonStop.radiuss: unknown parameter"),
    (("radius: 0.2", "radius: -1"), "PolygonStop.radius: Input should be greater than 0"),
    (('action_type: "stop"', 'action_type: "halt"'), "PolygonStop.action_type"),
    (("[0.0, 0.25]]", "[0.0]]"), "PolygonSlow.points: point 3 must be [x, y]"),
    (('points: "[[0.5, 0.25], [0.5, -0.25], [0.0, -0.25], [0.0, 0.25]]"', 'points: "[[0.5, 0.25]]"'),
     "PolygonSlow.points: a polygon needs at least 3 points"),
    (("slowdown_ratio: 0.3", "slowdown_ratio: 1.5"), "PolygonSlow.slowdown_ratio"),
    (('type: "scan", topic', 'type: "pointcloud", topic'), "scan.type: 'pointcloud' sources are not supported"),
    (('polygons: ["PolygonStop", "PolygonSlow"]', 'polygons: ["PolygonStop", "Missing"]'),
     "polygon 'Missing' is listed in 'polygons' but not defined"),
    (("source_timeout: 0.5", "source_timout: 0.5"), "source_timout: unknown parameter"),
    (('observation_sources: ["scan"]', "observation_sources: scan"), "observation_sources: must be a list"),
    (('type: "circle"', 'type: "velocity_polygon"'), "PolygonStop: a velocity_polygon needs 'velocity_polygons'"),
])
def test_bad_files_get_errors_naming_the_file_and_the_field(tmp_path, change, message):
    path = write(tmp_path, GOOD.replace(*change))
    with pytest.raises(SafetyZonesConfigError) as err:
        load_collision_monitor(path)
    assert str(path) in str(err.value) and message in str(err.value)


def test_unreadable_files_are_named(tmp_path):
    with pytest.raises(SafetyZonesConfigError, match="cannot read"):
        load_collision_monitor(tmp_path / "missing.yaml")
    with pytest.raises(SafetyZonesConfigError, match="ros__parameters"):
        load_collision_monitor(write(tmp_path, "collision_monitor: {polygons: []}\n"))
    with pytest.raises(SafetyZonesConfigError, match="not valid YAML"):
        load_collision_monitor(write(tmp_path, "collision_monitor: [\n"))


def test_points_accept_the_string_the_pairs_and_the_old_flat_list():
    square = ((0.1, 0.1), (0.1, -0.1), (-0.1, -0.1))
    assert parse_points("[[0.1, 0.1], [0.1, -0.1], [-0.1, -0.1]]") == square
    assert parse_points([[0.1, 0.1], [0.1, -0.1], [-0.1, -0.1]]) == square
    assert parse_points([0.1, 0.1, 0.1, -0.1, -0.1, -0.1]) == square
    with pytest.raises(ValueError, match="not finite"):
        parse_points("[[0.1, .nan], [0.1, -0.1], [-0.1, -0.1]]")


VELOCITY = """\
collision_monitor:
  ros__parameters:
    polygons: ["VelocityPolygonStop"]
    VelocityPolygonStop:
      type: "velocity_polygon"
      action_type: "stop"
      min_points: 6
      velocity_polygons: ["rotation", "translation_forward"]
      holonomic: false
      rotation:
        points: "[[0.3, 0.3], [0.3, -0.3], [-0.3, -0.3], [-0.3, 0.3]]"
        linear_min: 0.0
        linear_max: 0.05
        theta_min: -1.0
        theta_max: 1.0
      translation_forward:
        points: "[[0.35, 0.3], [0.35, -0.3], [-0.2, -0.3], [-0.2, 0.3]]"
        linear_min: 0.0
        linear_max: 1.0
        theta_min: -1.0
        theta_max: 1.0
    observation_sources: ["scan"]
    scan: {type: "scan", topic: "scan"}
"""


def test_velocity_polygons_load_and_round_trip(tmp_path):
    cfg = load_collision_monitor(write(tmp_path, VELOCITY))
    zone = cfg.zones["VelocityPolygonStop"]
    assert zone.velocity_polygons == ["rotation", "translation_forward"]
    assert zone.sub_polygons["translation_forward"].points[0] == (0.35, 0.3)
    path = tmp_path / "again.yaml"
    path.write_text(to_yaml(cfg))
    assert load_collision_monitor(path).zones == cfg.zones


@pytest.mark.parametrize(("change", "message"), [
    (("        linear_min: 0.0\n        linear_max: 0.05\n", "        linear_max: 0.05\n"),
     "VelocityPolygonStop.rotation.linear_min: Field required"),
    (('["rotation", "translation_forward"]', '["rotation", "backward"]'),
     "velocity polygon(s) backward listed but not defined"),
    (('action_type: "stop"', 'action_type: "approach"'), "a velocity_polygon cannot be one here"),
])
def test_bad_velocity_polygons_name_the_field(tmp_path, change, message):
    path = write(tmp_path, VELOCITY.replace(*change))
    with pytest.raises(SafetyZonesConfigError) as err:
        load_collision_monitor(path)
    assert str(path) in str(err.value) and message in str(err.value)
