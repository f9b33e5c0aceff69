"""The ROS 2 driver's config file, the CLI wiring and the message conversions (no DDS traffic)."""

import argparse
import math

import pytest

pytest.importorskip("cyclonedds")

from bt_runtime.runtime.messages import ComponentState, Pose2D  # noqa: E402
from bt_runtime.runtime.ros2 import Ros2Config, Ros2Driver, idl  # noqa: E402
from bt_runtime.runtime.ros2.convert import Converter, Drop, error_code_of, pose2d_of, pose_msg  # noqa: E402
from bt_runtime.runtime.ros2.dds import fq_name  # noqa: E402

CONFIG = """
domain_id: 42
namespace: robot1
topics:
  scan: {name: /lidar/scan, qos: {reliability: best_effort, depth: 2}}
  cmd_vel: {name: cmd_vel, stamped: true}
  nav_cmd_vel: {name: cmd_vel_nav_out}
  bumper: null
navigation:
  navigate_to_pose: /navigate_to_pose
components:
  lidar: {streams: [scan], rate_hz: 10, lifecycle_node: /lidar_driver}
  wheels: {kind: base, streams: [odom], rate_hz: 20}
  amcl: {kind: localization, streams: [pose], depends_on: [wheels]}
robot: {radius: 0.155, max_linear: 0.9, max_angular: 3.0, capacity_ah: 3.5}
"""


def test_config_file_and_cli_driver(tmp_path, monkeypatch):
    from bt_runtime.cli.run import UsageError, make_driver

    path = tmp_path / "robot.yaml"
    path.write_text(CONFIG)
    monkeypatch.setenv("ROS_DOMAIN_ID", "7")
    driver = make_driver(argparse.Namespace(driver="ros2", ros2_config=path, world="apartment", robot="burger"))
    assert isinstance(driver, Ros2Driver)
    cfg = driver.config
    assert cfg.domain_id == 42  # the file wins over ROS_DOMAIN_ID
    assert cfg.topics.scan.name == "/lidar/scan" and cfg.topics.scan.qos.depth == 2
    assert cfg.topics.cmd_vel.stamped and cfg.topics.bumper is None
    infos = {c.name: c for c in driver.components()}
    assert infos["lidar"].restartable and not infos["wheels"].restartable
    assert infos["wheels"].kind == "base" and infos["lidar"].expected_rate_hz == 10
    assert driver.component_state("lidar") is ComponentState.UNKNOWN
    assert infos["amcl"].extra["depends_on"] == ("wheels",)
    info = driver.robot_info()
    assert (info.radius, info.max_linear, info.capacity_ah) == (0.155, 0.9, 3.5)
    default = make_driver(argparse.Namespace(driver="ros2", ros2_config=None))
    assert default.config.domain_id == 7  # ROS_DOMAIN_ID when the file does not say
    (tmp_path / "bad.yaml").write_text("domain_id: -1\n")
    with pytest.raises(UsageError, match="bad.yaml"):  # a bad file is a usage error, not a traceback
        make_driver(argparse.Namespace(driver="ros2", ros2_config=tmp_path / "bad.yaml"))


def test_robot_on_the_command_line_sizes_the_layer_unless_the_file_does(tmp_path):
    """`run --driver ros2 --robot rosbot2` gets the ROSbot's footprint and limits (the gate's
    clamps and the safety zones use them), not the burger defaults; a file's robot: section wins."""
    from bt_runtime.cli.run import make_driver
    from sim.robot import load_profile

    rosbot = load_profile("rosbot2")
    info = make_driver(argparse.Namespace(driver="ros2", ros2_config=None, robot="rosbot2")).robot_info()
    assert (info.radius, info.max_linear, info.max_angular) == (rosbot.radius, rosbot.max_linear, rosbot.max_angular)
    assert info.capacity_ah == rosbot.battery.capacity_ah and info.lidar_x == rosbot.lidar.x
    path = tmp_path / "robot.yaml"
    path.write_text(CONFIG)
    waffle = load_profile("waffle")
    assert (waffle.radius, waffle.max_linear) != (0.155, 0.9)
    info = make_driver(argparse.Namespace(driver="ros2", ros2_config=path, robot="waffle")).robot_info()
    assert (info.radius, info.max_linear) == (0.155, 0.9)  # the file's section


def test_config_errors_name_the_file_and_field(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("topics:\n  scan: {name: scan, qos: {reliability: maybe}}\n")
    with pytest.raises(ValueError, match=r"(?s)bad.yaml.*reliability"):
        Ros2Config.load(path)
    with pytest.raises(ValueError, match="not found"):
        Ros2Config.load(tmp_path / "missing.yaml")


def test_run_command_accepts_ros2_config():
    from bt_runtime.cli import run

    parser = argparse.ArgumentParser()
    run.add_parser(parser.add_subparsers())
    args = parser.parse_args(["run", "t.xml", "--driver", "ros2", "--ros2-config", "x.yaml"])
    assert str(args.ros2_config) == "x.yaml"


def test_sim_robot_command_line():
    from bt_runtime.cli import sim_robot

    parser = argparse.ArgumentParser()
    sim_robot.add_parser(parser.add_subparsers())
    args = parser.parse_args(["sim-robot", "--world", "apartment", "--robot", "rosbot2", "--domain", "5",
                              "--crash", "lidar@3", "--seed", "2"])
    assert args.domain == 5 and args.crash == ["lidar@3"]
    from sim.ros2_robot import parse_crash

    assert parse_crash("lidar@3.5") == ("lidar", 3.5)
    with pytest.raises(ValueError):
        parse_crash("lidar")
    assert sim_robot.run(parser.parse_args(["sim-robot", "--crash", "nonsense"])) == 2


def test_names():
    assert fq_name("scan") == "/scan"
    assert fq_name("scan", "robot1") == "/robot1/scan"
    assert fq_name("/abs/x", "robot1") == "/abs/x"


def test_pose_round_trip_and_error_codes():
    p = Pose2D(1.5, -2.0, 2.5)
    q = pose2d_of(pose_msg(p))
    assert (q.x, q.y) == (1.5, -2.0) and q.yaw == pytest.approx(2.5)
    assert error_code_of("backup", 714).value == 703  # BackUp COLLISION_AHEAD -> ours
    assert error_code_of("navigate_to_pose", 12345).value == 9000


def test_converter_limits():
    conv = Converter(Ros2Config())
    scan = idl.LaserScan(angle_min=-1.0, angle_max=1.0, angle_increment=0.5, range_min=0.1, range_max=4.0,
                         ranges=[1.0, math.inf, -math.inf, 2.0, 3.0])
    out = conv.scan(scan, 3.0)
    assert out.stamp == 3.0 and len(out.ranges) == 5
    with pytest.raises(Drop):
        conv.scan(idl.LaserScan(angle_min=0, angle_max=1, angle_increment=0.5, range_min=0.1, range_max=4,
                                ranges=[1.0, 1.0, 1.0], intensities=[1.0]), 0)
    bat = conv.battery(idl.BatteryState(voltage=11.1, percentage=0.42, current=-1.5), 1.0)
    assert bat.percentage == pytest.approx(42.0) and bat.current == pytest.approx(1.5)
    imu = conv.imu(idl.Imu(orientation=idl.Quaternion(0, 0, 0, 1), angular_velocity=idl.Vector3(0, 0, 0.3)), 0)
    assert imu.yaw_rate == pytest.approx(0.3)
    contact = conv.bumper_vector(idl.Vector3Stamped(vector=idl.Vector3(0.0, 1.0, 0.2)), 0)
    assert contact.in_contact and contact.direction == pytest.approx(math.pi / 2)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_converter_names_non_finite_values_and_only_those(bad):
    conv = Converter(Ros2Config())
    with pytest.raises(Drop, match="non-finite imu"):
        conv.imu(idl.Imu(orientation=idl.Quaternion(0, 0, 0, 1), angular_velocity=idl.Vector3(0, bad, 0.3)), 0)
    # huge but finite values whose sum overflows are absurd, not non-finite
    with pytest.raises(Drop, match="absurd imu"):
        conv.imu(idl.Imu(orientation=idl.Quaternion(0, 0, 0, 1), angular_velocity=idl.Vector3(1e308, 1e308, 1e308)), 0)
    with pytest.raises(Drop, match="non-finite odometry"):
        conv.odom(idl.Odometry(pose=idl.PoseWithCovariance(pose=idl.Pose(
            position=idl.Point(bad, 0.0, 0.0), orientation=idl.Quaternion(0, 0, 0, 1)))), 0)
