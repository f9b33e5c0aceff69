"""Imu and Odometry read straight from their CDR bytes: the values the converter checks, without
building the messages.

At the tick the driver reads ~100 imu and odom samples a second. Decoding each into its IDL
objects (a header, quaternions, vectors, three or two covariance arrays: 10-15 objects) only for
the converter to read ten numbers of them was half of a sample's cost on the loop. Here one
``struct`` unpack per message reads those numbers (the rest is skipped, but must be there: a
truncated sample raises as ``cdr.decoder``'s does, and so does a bad frame id). The result,
``(sec, nanosec, values)``, goes to ``Converter.imu_values`` / ``odom_values``, the same checks
``Converter.imu`` / ``odom`` run on the objects (``tests/runtime/ros2/test_sensor_wire.py``
compares the two paths). Anything but little-endian XCDR1 is decoded the ordinary way.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import Any

import numpy as np

from . import cdr, idl
from .convert import imu_values_of, odom_values_of, scan_values_of

Values = tuple[int, int, tuple]  # header stamp (sec, nanosec), the converter's arguments
_HEAD = struct.Struct("<iII")  # stamp, frame_id's length (after the 4-byte encapsulation)
_U32 = struct.Struct("<I")
# orientation, covariance[0] (8 more), angular velocity, (covariance), linear acceleration, (covariance)
_IMU = struct.Struct("<4dd64x3d72x3d72x")
# position x, y (z), orientation, (covariance), linear x (y, z, angular x, y), angular z, (covariance)
_ODOM = struct.Struct("<2d8x4d288xd32xd288x")
# angle_min, angle_max, angle_increment, time_increment, scan_time, range_min, range_max, len(ranges)
_SCAN = struct.Struct("<7fI")
_HEADER = cdr.HEADER


def _string_end(data: bytes, at: int) -> int:
    """Check the string at ``at`` (from the end of the encapsulation, aligned to 4) as
    ``cdr.decoder`` reads it; return where it ends."""
    at += (-at) % 4
    (n,) = _U32.unpack_from(data, _HEADER + at)
    start = _HEADER + at + 4
    if n == 0 or start + n > len(data):
        raise ValueError(f"bad string length {n}")
    data[start:start + n - 1].decode("utf-8")
    return at + 4 + n


def imu_decoder() -> Callable[[bytes], Values]:
    fallback = cdr.decoder(idl.Imu)
    unpack = _IMU.unpack_from

    def decode_imu(data: bytes) -> Values:
        if data[:2] != cdr.CDR_LE:
            return _of(fallback(data), imu_values_of)
        sec, nanosec, _ = _HEAD.unpack_from(data, _HEADER)
        at = _string_end(data, 8)
        qx, qy, qz, qw, cov0, wx, wy, wz, ax, ay, az = unpack(data, _HEADER + at + (-at) % 8)
        return sec, nanosec, (wx, wy, wz, ax, ay, az, qx, qy, qz, qw, cov0)

    return decode_imu


def odom_decoder() -> Callable[[bytes], Values]:
    fallback = cdr.decoder(idl.Odometry)
    unpack = _ODOM.unpack_from

    def decode_odom(data: bytes) -> Values:
        if data[:2] != cdr.CDR_LE:
            return _of(fallback(data), odom_values_of)
        sec, nanosec, _ = _HEAD.unpack_from(data, _HEADER)
        at = _string_end(data, _string_end(data, 8))  # frame_id, child_frame_id
        return sec, nanosec, unpack(data, _HEADER + at + (-at) % 8)

    return decode_odom


def scan_decoder() -> Callable[[bytes], Values]:
    """A LaserScan's geometry and its ranges as one float32 array straight from the bytes (no
    Python float per beam; a signalling NaN keeps its bits instead of becoming a quiet one)."""
    fallback = cdr.decoder(idl.LaserScan)
    unpack = _SCAN.unpack_from

    def decode_scan(data: bytes) -> Values:
        if data[:2] != cdr.CDR_LE:
            return _of(fallback(data), scan_values_of)
        sec, nanosec, _ = _HEAD.unpack_from(data, _HEADER)
        at = _string_end(data, 8)
        at += (-at) % 4
        angle_min, angle_max, increment, _, _, range_min, range_max, n = unpack(data, _HEADER + at)
        at += _SCAN.size
        if n > len(data):
            raise ValueError(f"bad sequence length {n}")
        ranges = np.frombuffer(data, "<f4", n, _HEADER + at).copy()
        at += 4 * n
        (m,) = _U32.unpack_from(data, _HEADER + at)
        if m:
            np.frombuffer(data, "<f4", m, _HEADER + at + 4)  # (there, as the decoder requires; unused)
        return sec, nanosec, (angle_min, angle_max, increment, range_min, range_max, ranges, m)

    return decode_scan


def _of(m: Any, values: Callable[[Any], tuple]) -> Values:
    return m.header.stamp.sec, m.header.stamp.nanosec, values(m)


DECODERS = {"imu": imu_decoder, "odom": odom_decoder, "scan": scan_decoder}  # stream -> decoder factory
