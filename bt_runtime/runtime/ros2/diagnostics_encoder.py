"""The CDR bytes of a diagnostic_msgs/DiagnosticArray, without Cyclone's serialiser.

The runtime publishes its components' health once a second (and on every change): ten
statuses with key/value lists, which Cyclone's Python serialiser took ~320 us to encode warm
(most of the diagnostics task's cost on the loop). The message is strings, a byte and counts,
so it is packed here into the same bytes (``tests/runtime/ros2/test_diagnostics_encoder.py``
compares them with Cyclone's).
"""

from __future__ import annotations

import struct
from collections.abc import Iterable

from .cmd_encoder import ENCAPSULATION, stamp_of

_U32 = struct.Struct("<I")
_STAMP = struct.Struct("<iI")


def _string(out: bytearray, text: str) -> None:
    data = text.encode("utf-8") + b"\x00"
    out += b"\x00" * (-len(out) % 4)  # (the encapsulation is 4 bytes: alignment is the same)
    out += _U32.pack(len(data))
    out += data


def encode_diagnostic_array(t: float, frame_id: str,
                            statuses: Iterable[tuple[int, str, str, str, Iterable[tuple[str, str]]]]) -> bytes:
    """A DiagnosticArray stamped with ROS time ``t`` (as ``idl.Time.from_sec``): each status is
    (level, name, message, hardware_id, [(key, value), ...])."""
    out = bytearray(ENCAPSULATION)
    out += _STAMP.pack(*stamp_of(t))
    _string(out, frame_id)
    statuses = list(statuses)
    out += b"\x00" * (-len(out) % 4)
    out += _U32.pack(len(statuses))
    for level, name, message, hardware_id, values in statuses:
        out += struct.pack("<b", level)
        _string(out, name)
        _string(out, message)
        _string(out, hardware_id)
        values = list(values)
        out += b"\x00" * (-len(out) % 4)
        out += _U32.pack(len(values))
        for key, value in values:
            _string(out, key)
            _string(out, value)
    out += b"\x00" * (-len(out) % 4)  # as DataWriter.write pads the sample
    return bytes(out)
