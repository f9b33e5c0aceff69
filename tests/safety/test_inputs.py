"""Inputs that used to end in tracebacks, hangs or silent misbehaviour get clear errors that
name the file and field: world bounds, robot profiles, runtime and ROS 2 configuration,
--duration, --btlog, a Groot2 port in use, non-regular tree files, map images elsewhere."""

from __future__ import annotations

import argparse
import os
import socket

import pytest
import yaml
from pydantic import ValidationError

from bt_runtime.cli.run import positive_seconds
from bt_runtime.errors import XMLLoadError
from bt_runtime.factory import BehaviorTreeFactory
from bt_runtime.runtime.config import RuntimeConfig
from bt_runtime.xml.reader import read_limited
from groot.cli import Monitoring, MonitoringError, check_btlog_path
from sim.nav.occupancy import OccupancyGrid
from sim.robot import ProfileError, load_profile
from sim.world import WorldError, load_world
from tests.helpers import IDLE_TREE


def world_file(tmp_path, bounds) -> str:
    path = tmp_path / "w.yaml"
    path.write_text(yaml.safe_dump({"name": "w", "bounds": bounds, "spawn": {"x": 0, "y": 0, "yaw": 0},
                                    "obstacles": []}), encoding="utf-8")
    return str(path)


@pytest.mark.parametrize("bounds, expected", [
    ({"xmin": -500, "ymin": -500, "xmax": 500, "ymax": 500}, "GB"),  # 1 km^2
    ({"xmin": -1, "ymin": -1, "xmax": float("inf"), "ymax": 1}, "finite"),
    ({"xmin": -1, "ymin": float("nan"), "xmax": 1, "ymax": 1}, "finite"),
])
def test_world_bounds_that_need_gigabytes_or_are_not_numbers(tmp_path, bounds, expected):
    path = world_file(tmp_path, bounds)
    with pytest.raises(WorldError) as caught:
        load_world(path)
    message = str(caught.value)
    assert path in message and "bounds" in message and expected in message


@pytest.mark.parametrize("field, value", [("max_linear", float("inf")), ("max_angular", float("nan")),
                                          ("cmd_timeout", -1.0), ("battery.capacity_ah", float("inf"))])
def test_robot_profile_values_must_be_finite_and_positive(field, value):
    with pytest.raises(ProfileError) as caught:
        load_profile("burger", **{field: value})
    assert "burger.yaml" in str(caught.value) and field.split(".")[-1] in str(caught.value)


@pytest.mark.parametrize("data, field", [
    ({"gate": {"deadman_timeout": float("inf")}}, "deadman_timeout"),
    ({"tick": {"rate_hz": float("inf")}}, "rate_hz"),
    ({"backup": {"sizes": {"scan": -5}}}, "scan"),
    ({"backup": {"sizes": {"lidar_points": 10}}}, "lidar_points"),
])
def test_runtime_config_refuses_non_finite_negative_and_unknown(data, field):
    with pytest.raises(ValidationError) as caught:
        RuntimeConfig.model_validate(data)
    assert field in str(caught.value)


@pytest.mark.parametrize("text", ["nan", "-5", "inf", "0", "soon"])
def test_duration_must_be_a_positive_number(text):
    with pytest.raises(argparse.ArgumentTypeError, match="positive number of seconds"):
        positive_seconds(text)
    assert positive_seconds("2.5") == 2.5


def test_btlog_folder_and_extension(tmp_path):
    with pytest.raises(MonitoringError, match="does not exist"):
        check_btlog_path(str(tmp_path / "missing" / "run.btlog"))
    with pytest.raises(MonitoringError, match=r"end in \.btlog"):
        check_btlog_path(str(tmp_path / "run.log"))
    check_btlog_path(str(tmp_path / "run.btlog"))


async def test_groot_port_in_use_is_a_clear_error():
    tree = BehaviorTreeFactory().create_tree_from_text(IDLE_TREE)
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        with pytest.raises(MonitoringError, match=f"--groot {port}"):
            await Monitoring(tree, port=port).start()


@pytest.mark.parametrize("uri, message", [("<CycloneDDS><Domain>", "well-formed"),
                                          ("file:///nonexistent/cyclone.xml", "no such file"),
                                          ("udp://10.0.0.1", "file://PATH")])
def test_bad_cyclonedds_uri(uri, message):
    config = pytest.importorskip("bt_runtime.runtime.ros2.config")
    with pytest.raises(ValidationError, match=message) as caught:
        config.Ros2Config(cyclonedds_uri=uri)
    assert "cyclonedds_uri" in str(caught.value)


def test_tree_files_must_be_regular_and_bounded(tmp_path):
    fifo = tmp_path / "tree.xml"
    os.mkfifo(fifo)
    for path in (fifo, "/dev/zero", tmp_path):
        with pytest.raises(XMLLoadError, match="Not a regular file"):
            read_limited(path)
    big = tmp_path / "big.xml"
    big.write_bytes(b" " * 2048)
    with pytest.raises(XMLLoadError, match="too large"):
        read_limited(big, limit=1024)


def test_map_image_outside_the_map_folder_is_refused(tmp_path):
    (tmp_path / "maps").mkdir()
    secret = tmp_path / "secret.pgm"
    secret.write_bytes(b"P5\n1 1\n255\n\x00")
    map_yaml = tmp_path / "maps" / "map.yaml"
    map_yaml.write_text("image: ../secret.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n"
                        "occupied_thresh: 0.65\nfree_thresh: 0.2\nnegate: 0\n", encoding="utf-8")
    with pytest.raises(ValueError, match="outside the map file's folder"):
        OccupancyGrid.load(map_yaml)
