"""Imu, Odometry and LaserScan read from their bytes (ros2/sensor_wire.py) give what the
ordinary path gives: ``cdr.decoder`` then ``Converter.imu`` / ``odom`` / ``scan`` (the same
message, or the same drop with the same reason), the same header stamp, and a truncated or
garbled sample fails in both."""

import math
import random

import pytest

pytest.importorskip("cyclonedds")

import numpy as np  # noqa: E402

from bt_runtime.runtime.ros2 import Ros2Config, cdr, idl, sensor_wire  # noqa: E402
from bt_runtime.runtime.ros2.convert import Converter, Drop  # noqa: E402

SPECIAL = [0.0, -0.0, 1.0, -1.0, 0.5, 1e308, -1e308, math.nan, math.inf, -math.inf, 5e-324, 40.0, 2.0]
FRAMES = ["", "imu", "imu_link", "odom", "base_footprint", "ünï", "a" * 37]


def value(rng: random.Random) -> float:
    return rng.choice(SPECIAL) if rng.random() < 0.15 else rng.uniform(-3.0, 3.0)


def quaternion(rng: random.Random) -> idl.Quaternion:
    if rng.random() < 0.2:
        return idl.Quaternion(value(rng), value(rng), value(rng), value(rng))
    yaw = rng.uniform(-math.pi, math.pi)
    return idl.Quaternion(0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


def header(rng: random.Random) -> idl.Header:
    return idl.Header(stamp=idl.Time(rng.randrange(-2**31, 2**31), rng.randrange(0, 2**32)),
                      frame_id=rng.choice(FRAMES))


def random_imu(rng: random.Random) -> idl.Imu:
    return idl.Imu(header=header(rng), orientation=quaternion(rng),
                   orientation_covariance=[rng.choice([-1.0, 0.0, value(rng)])] + [value(rng) for _ in range(8)],
                   angular_velocity=idl.Vector3(value(rng), value(rng), value(rng)),
                   angular_velocity_covariance=[value(rng) for _ in range(9)],
                   linear_acceleration=idl.Vector3(value(rng), value(rng), value(rng) * 4),
                   linear_acceleration_covariance=[value(rng) for _ in range(9)])


def random_odom(rng: random.Random) -> idl.Odometry:
    return idl.Odometry(
        header=header(rng), child_frame_id=rng.choice(FRAMES),
        pose=idl.PoseWithCovariance(pose=idl.Pose(position=idl.Point(value(rng) * 10, value(rng), value(rng)),
                                                  orientation=quaternion(rng)),
                                    covariance=[value(rng) for _ in range(36)]),
        twist=idl.TwistWithCovariance(twist=idl.Twist(linear=idl.Vector3(value(rng), value(rng), value(rng)),
                                                      angular=idl.Vector3(value(rng), value(rng), value(rng))),
                                      covariance=[value(rng) for _ in range(36)]))


def random_scan(rng: random.Random) -> idl.LaserScan:
    n = rng.choice([0, 1, 5, 360, 361, 720, 2000])
    increment = rng.choice([2 * math.pi / max(n, 1), 0.0, math.nan, 0.01])
    angle_min = rng.choice([-math.pi, 0.0, -1.0, math.inf])
    angle_max = angle_min + increment * (n - 1 + rng.choice([0, 0, 0, 3]))
    pool = [1.0, 2.5, 0.3, 7.9] * 3 + [math.nan, math.inf, -math.inf, -0.5, 1e6]
    ranges = [rng.choice(pool) if rng.random() < 0.3 else rng.uniform(0.1, 8.0) for _ in range(n)]
    if rng.random() < 0.1:
        ranges = [math.nan] * n
    intensities = rng.choice([[], [1.0] * n, [1.0] * max(0, n - 1)])
    return idl.LaserScan(header=header(rng), angle_min=angle_min, angle_max=angle_max, angle_increment=increment,
                         time_increment=rng.uniform(0, 1e-3), scan_time=0.2, range_min=rng.choice([0.12, 0.0, 9.0]),
                         range_max=rng.choice([8.0, 12.0, math.nan]), ranges=ranges, intensities=intensities)


def outcome(fn, *args):
    try:
        return fn(*args)
    except Drop as why:
        return ("drop", str(why))


def same(a, b) -> bool:
    if hasattr(a, "ranges"):  # a LaserScan: the arrays to the value (NaN where NaN) and the type
        return (type(a) is type(b) and a.ranges.dtype == b.ranges.dtype and a.ranges.flags.writeable
                and np.array_equal(a.ranges, b.ranges, equal_nan=True)
                and (a.stamp, a.angle_min, a.angle_increment, a.range_min, a.range_max)
                == (b.stamp, b.angle_min, b.angle_increment, b.range_min, b.range_max))
    return a == b or repr(a) == repr(b)  # (NaN fields compare by their repr)


KINDS = {"imu": (random_imu, idl.Imu), "odom": (random_odom, idl.Odometry), "scan": (random_scan, idl.LaserScan)}


@pytest.mark.parametrize("kind", list(KINDS))
def test_values_from_the_bytes_convert_as_the_decoded_message_does(kind):
    rng = random.Random(7)
    conv = Converter(Ros2Config())
    make, data_type = KINDS[kind]
    convert, convert_values = getattr(conv, kind), getattr(conv, kind + "_values")
    decode, wire = cdr.decoder(data_type), sensor_wire.DECODERS[kind]()
    outcomes = set()
    for _ in range(3000 if kind != "scan" else 600):
        data = make(rng).serialize(use_version_2=None)
        m = decode(data)
        sec, nanosec, values = wire(data)
        assert (sec, nanosec) == (m.header.stamp.sec, m.header.stamp.nanosec)
        expected, got = outcome(convert, m, 12.5), outcome(convert_values, values, 12.5)
        assert same(expected, got), (expected, got)
        outcomes.add(expected[1] if isinstance(expected, tuple) else "ok")
    assert "ok" in outcomes and len(outcomes) >= 3, outcomes  # converted, and drops of several kinds


@pytest.mark.parametrize("kind", list(KINDS))
def test_truncated_or_garbled_samples_fail_in_both_paths(kind):
    rng = random.Random(3)
    make, data_type = KINDS[kind]
    decode, wire = cdr.decoder(data_type), sensor_wire.DECODERS[kind]()
    for _ in range(300):
        data = bytearray(make(rng).serialize(use_version_2=None))
        if rng.random() < 0.5:
            data = data[:rng.randrange(4, len(data))]
        else:  # a string length or a frame id byte
            at = rng.choice([8, 12, 13, 16, 20, 24])
            data[4 + at] = rng.randrange(256) if at >= 12 else 0xFF
        data = bytes(data)
        try:
            decode(data)
            ordinary = True
        except Exception:
            ordinary = False
        try:
            wire(data)
            fast = True
        except Exception:
            fast = False
        assert ordinary == fast, data.hex()


def test_big_endian_samples_take_the_ordinary_decoder():
    m = idl.Imu(header=idl.Header(stamp=idl.Time(5, 6), frame_id="imu"), orientation=idl.Quaternion(0, 0, 0, 1),
                angular_velocity=idl.Vector3(0.0, 0.0, 0.25))
    data = m.serialize(use_version_2=None, endianness=idl.Endianness.Big) if hasattr(idl, "Endianness") else None
    if data is None:
        from cyclonedds.idl._support import Endianness
        data = m.serialize(use_version_2=None, endianness=Endianness.Big)
    assert data[:2] != cdr.CDR_LE
    sec, nanosec, values = sensor_wire.DECODERS["imu"]()(data)
    assert (sec, nanosec) == (5, 6) and values[2] == 0.25
