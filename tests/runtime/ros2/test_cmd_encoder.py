"""The velocity command's CDR bytes (ros2/cmd_encoder.py) equal what Cyclone's writer
serialises from the IDL objects the driver built before (Twist; TwistStamped with its frame and
a stamp taken by ``idl.Time.from_sec`` at the same instant)."""

import math
import random

import pytest

pytest.importorskip("cyclonedds")

from bt_runtime.runtime.ros2 import cmd_encoder, idl  # noqa: E402

VALUES = [0.0, -0.0, 0.25, -1.5, 1e-300, 123.456, math.pi]


def cyclone_twist(linear: float, angular: float) -> idl.Twist:
    return idl.Twist(linear=idl.Vector3(float(linear), 0.0, 0.0), angular=idl.Vector3(0.0, 0.0, float(angular)))


def test_twist_bytes_equal_cyclones():
    encode = cmd_encoder.twist_encoder()
    rng = random.Random(1)
    pairs = [(a, b) for a in VALUES for b in VALUES] + [(rng.uniform(-2, 2), rng.uniform(-3, 3)) for _ in range(50)]
    for linear, angular in pairs:
        assert encode(linear, angular) == cyclone_twist(linear, angular).serialize(use_version_2=None)


@pytest.mark.parametrize("frame_id", ["", "b", "base_link", "base_footprint", "odom_12", "базa"])
def test_twist_stamped_bytes_equal_cyclones(monkeypatch, frame_id):
    rng = random.Random(2)
    for _ in range(40):
        t = rng.choice([0.0, 1.0 - 1e-10, 1_700_000_000.123456789]) + rng.random() * 1e3
        monkeypatch.setattr(cmd_encoder.time, "time", lambda t=t: t)
        encode = cmd_encoder.twist_encoder(True, frame_id)
        linear, angular = rng.uniform(-2, 2), rng.choice(VALUES)
        expected = idl.TwistStamped(header=idl.Header(stamp=idl.Time.from_sec(t), frame_id=frame_id),
                                    twist=cyclone_twist(linear, angular)).serialize(use_version_2=None)
        expected = expected.ljust((len(expected) + 3) & ~3, b"\0")  # as DataWriter.write pads
        assert encode(linear, angular) == expected
