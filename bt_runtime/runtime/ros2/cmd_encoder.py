"""The CDR bytes of the velocity command (geometry_msgs/Twist or TwistStamped), without
Cyclone's serialiser.

The driver writes ``cmd_vel`` ten times a second while the base stands (the zero keep-alive)
and up to 100 times while it drives. Building the IDL objects and serialising them field by
field through Cyclone's machinery took ~12 us warm and several times that on a busy loop; the
command is two numbers (and a stamp), so it is packed with one precompiled ``struct`` into
the same bytes (``tests/runtime/ros2/test_cmd_encoder.py`` compares them with Cyclone's).
"""

from __future__ import annotations

import struct
import time
from collections.abc import Callable

ENCAPSULATION = b"\x00\x01\x00\x00"  # XCDR1, little-endian, no options (what Cyclone writes for these types)
_TWIST = struct.Struct("<d16x16xd")  # linear (x, y=0, z=0), angular (x=0, y=0, z)


def stamp_of(t: float) -> tuple[int, int]:
    """(sec, nanosec) of a ROS time in seconds, as ``idl.Time.from_sec`` makes them."""
    sec = int(t // 1)
    return sec, min(int(round((t - sec) * 1e9)), 999_999_999)


def twist_encoder(stamped: bool = False, frame_id: str = "") -> Callable[[float, float], bytes]:
    """``encode(linear, angular) -> bytes``: a Twist, or a TwistStamped stamped with the wall
    clock at the call (as ``idl.Time.now()``) in ``frame_id``."""
    if not stamped:
        pack = _TWIST.pack

        def encode_twist(linear: float, angular: float) -> bytes:
            return ENCAPSULATION + pack(linear, angular)

        return encode_twist
    name = frame_id.encode("utf-8") + b"\x00"
    pad = (-(12 + len(name))) % 8  # the doubles align to 8 (from the end of the encapsulation)
    pack_stamped, n = struct.Struct(f"<iII{len(name)}s{pad}xd16x16xd").pack, len(name)
    wall = time.time

    def encode_stamped(linear: float, angular: float) -> bytes:
        sec, nanosec = stamp_of(wall())
        return ENCAPSULATION + pack_stamped(sec, nanosec, n, name, linear, angular)

    return encode_stamped
