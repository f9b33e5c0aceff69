"""The high-rate messages (odometry, imu, tf, twist, scan) as rosbags' own CDR bytes with only
their changing fields rewritten in place: no per-message serializer run.

Why: rosbags' generated serializer costs ~20 us a message in Python, and ~190 messages per
robot second made it the larger half of a recording's CPU. These messages have a fixed layout
once their frame names (and a scan's length) are fixed, so the bytes of one message differ
from the next only in a few numeric slots.

How, without a second encoder: ``Layout`` serializes a template message once with rosbags
(``types.serialize``), then finds where each changing field lies by serializing the template
again with two sentinel values in that field and diffing the bytes (exactly the field's width
must differ). Encoding a message is then one ``struct.pack`` call over the whole message, with
the template's bytes between the slots as constant arguments. Every byte outside the slots is
rosbags' own; the slots hold the
values packed with the field's own CDR width (little endian, as the template's encapsulation
header says). ``tests/runtime/recording/test_layout_cdr.py`` compares the result with rosbags'
serialization of the same values, field by field and byte by byte.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from typing import Any

from .types import serialize

Path = tuple[str | int, ...]  # attribute names and sequence indices, e.g. ("transforms", 0, "header")


def _get(msg: Any, path: Path) -> Any:
    for step in path:
        msg = msg[step] if isinstance(step, int) else getattr(msg, step)
    return msg


def _set(msg: Any, path: Path, value: Any) -> None:
    parent = _get(msg, path[:-1])
    last = path[-1]
    if isinstance(last, int):
        parent[last] = value
    else:
        setattr(parent, last, value)


def _sentinel(code: str, fill: int) -> Any:
    """A value of type ``code`` whose every encoded byte is ``fill``."""
    return struct.unpack("<" + code, bytes([fill]) * struct.calcsize(code))[0]


def slot_offset(msg: Any, typename: str, path: Path, code: str) -> int:
    """Byte offset (encapsulation header included) of field ``path`` in rosbags' CDR of ``msg``."""
    original = _get(msg, path)
    name = ".".join(map(str, path))
    blobs = []
    try:
        for fill in (0x11, 0x22):
            _set(msg, path, _sentinel(code, fill))
            blobs.append(serialize(msg, typename))
    except (TypeError, ValueError, AttributeError, struct.error) as exc:
        raise ValueError(f"{typename}: field {name} does not take a {code!r} value: {exc}") from None
    finally:
        _set(msg, path, original)
    a, b = blobs
    diff = [i for i in range(len(a)) if a[i] != b[i]]
    size = struct.calcsize(code)
    if len(a) != len(b) or len(diff) != size or diff[-1] - diff[0] + 1 != size:
        raise ValueError(f"{typename}: field {name} is not a fixed {code!r} slot")
    return diff[0]


class Layout:
    """One message type with fixed strings and sequence lengths: rosbags' bytes of ``template``
    with the fields of ``slots`` rewritten by ``encode``.

    ``slots``: ``(path, code)`` in wire order; ``code`` is a struct code (``d``, ``f``, ``i``,
    ``I``...), or ``<count><code>`` for a run of ``count`` sequence elements starting at
    ``path`` (a scan's ranges), which ``encode`` takes as bytes. ``encode(*values)`` is one
    generated call of one ``struct.Struct.pack`` over the whole message: the template's bytes
    between the slots are constant arguments."""

    __slots__ = ("typename", "template", "size", "encode", "offsets")

    def __init__(self, typename: str, template: Any, slots: Sequence[tuple[Path, str]]):
        self.typename = typename
        self.template = serialize(template, typename)
        self.size = len(self.template)
        self.offsets: dict[Path, int] = {}
        fmt, args, constants = ["<"], [], {}
        end = 0
        for k, (path, code) in enumerate(slots):
            block = code[:-1] != ""  # "<count><code>": sequence elements, passed as bytes
            count = int(code[:-1]) if block else 1
            offset = slot_offset(template, typename, path, code[-1])
            if offset < end:
                raise ValueError(f"{typename}: slot {'.'.join(map(str, path))} is not in wire order")
            if offset > end:  # the template's own bytes up to this slot
                constants[f"c{k}"] = self.template[end:offset]
                fmt.append(f"{offset - end}s")
                args.append(f"c{k}")
            width = struct.calcsize(code[-1]) * count
            fmt.append(f"{width}s" if block else code)
            args.append(f"v{k}")
            self.offsets[path] = offset
            end = offset + width
        if end < self.size:
            constants["tail"] = self.template[end:]
            fmt.append(f"{self.size - end}s")
            args.append("tail")
        constants["pack"] = struct.Struct("".join(fmt)).pack
        params = ", ".join(f"v{k}" for k in range(len(slots)))
        source = f"def encode({params}):\n    return pack({', '.join(args)})\n"
        exec(compile(source, f"<layout {typename}>", "exec"), constants)  # noqa: S102 - our own format
        self.encode = constants["encode"]
