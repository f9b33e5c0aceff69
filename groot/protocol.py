"""The Groot2 wire protocol (BT.CPP ``groot2_protocol.h``), shared by the server and the tests.

Request: frame 1 = 6 bytes ``<BBI`` (protocol 2, ASCII request type, u32 request id), optional
frame 2 = payload. Reply: 22-byte header (the request header with protocol 2, then the 16-byte
tree UUID) plus 0 or 1 payload frames. Errors: ``[b"error", message]`` without a header.
"""

from __future__ import annotations

import math
import random
import struct
import uuid
from collections.abc import Iterable
from typing import Any

PROTOCOL_ID = 2
HEADER = struct.Struct("<BBI")
HEADER_SIZE = HEADER.size  # 6
REPLY_HEADER_SIZE = HEADER_SIZE + 16

FULLTREE = ord("T")
STATUS = ord("S")
BLACKBOARD = ord("B")
HOOK_INSERT = ord("I")
HOOK_REMOVE = ord("R")
BREAKPOINT_REACHED = ord("N")
BREAKPOINT_UNLOCK = ord("U")
HOOKS_DUMP = ord("D")
REMOVE_ALL_HOOKS = ord("A")
DISABLE_ALL_HOOKS = ord("X")
TOGGLE_RECORDING = ord("r")
GET_TRANSITIONS = ord("t")

TRANSITION = struct.Struct("<QHB")  # packed as 6 + 2 + 1 bytes, see pack_transitions


def request_header(rtype: int, request_id: int | None = None) -> bytes:
    rid = random.getrandbits(32) if request_id is None else request_id
    return HEADER.pack(PROTOCOL_ID, rtype, rid)


def new_tree_uuid() -> bytes:
    """16 random bytes with the RFC 4122 version-4 / variant-10 bits (BT.CPP 4.8.3+)."""
    return uuid.uuid4().bytes


def pack_transitions(records: Iterable[tuple[int, int, int]]) -> bytes:
    """9-byte records: u48 LE microseconds, u16 LE uid, u8 status (``.btlog`` and GET_TRANSITIONS)."""
    out = bytearray()
    for usec, uid, status in records:
        out += (usec & 0xFFFFFFFFFFFF).to_bytes(6, "little")
        out += uid.to_bytes(2, "little")
        out.append(status)
    return bytes(out)


def unpack_transitions(buf: bytes) -> list[tuple[int, int, int]]:
    return [(int.from_bytes(buf[i:i + 6], "little"), int.from_bytes(buf[i + 6:i + 8], "little"), buf[i + 8])
            for i in range(0, len(buf) - len(buf) % 9, 9)]


def unpack_status(buf: bytes) -> list[tuple[int, int]]:
    return [(buf[i] | (buf[i + 1] << 8), buf[i + 2]) for i in range(0, len(buf) - len(buf) % 3, 3)]


# ---------------------------------------------------------------------------------------------
# msgpack, the way nlohmann::json::to_msgpack writes it
# ---------------------------------------------------------------------------------------------

_FLT_MAX = 3.4028234663852886e38


def msgpack_encode(value: Any) -> bytes:
    """Encode JSON-like data (None, bool, int, float, str, list, dict with str keys) exactly as
    nlohmann's ``to_msgpack``: smallest integer forms, a float as float32 when that is exact,
    map keys in sorted (byte) order."""
    out = bytearray()
    _pack(value, out)
    return bytes(out)


def _pack(v: Any, out: bytearray) -> None:
    if v is None:
        out.append(0xC0)
    elif v is True:
        out.append(0xC3)
    elif v is False:
        out.append(0xC2)
    elif isinstance(v, int):
        _pack_int(v, out)
    elif isinstance(v, float):
        if -_FLT_MAX <= v <= _FLT_MAX and struct.unpack("<f", struct.pack("<f", v))[0] == v:
            out.append(0xCA)
            out += struct.pack(">f", v)
        else:
            out.append(0xCB)
            out += struct.pack(">d", v)
    elif isinstance(v, str):
        data = v.encode("utf-8", "surrogatepass")
        n = len(data)
        if n < 32:
            out.append(0xA0 | n)
        elif n < 0x100:
            out += bytes((0xD9, n))
        elif n < 0x10000:
            out.append(0xDA)
            out += struct.pack(">H", n)
        else:
            out.append(0xDB)
            out += struct.pack(">I", n)
        out += data
    elif isinstance(v, (bytes, bytearray)):
        n = len(v)
        if n < 0x100:
            out += bytes((0xC4, n))
        elif n < 0x10000:
            out.append(0xC5)
            out += struct.pack(">H", n)
        else:
            out.append(0xC6)
            out += struct.pack(">I", n)
        out += v
    elif isinstance(v, (list, tuple)):
        n = len(v)
        if n < 16:
            out.append(0x90 | n)
        elif n < 0x10000:
            out.append(0xDC)
            out += struct.pack(">H", n)
        else:
            out.append(0xDD)
            out += struct.pack(">I", n)
        for item in v:
            _pack(item, out)
    elif isinstance(v, dict):
        n = len(v)
        if n < 16:
            out.append(0x80 | n)
        elif n < 0x10000:
            out.append(0xDE)
            out += struct.pack(">H", n)
        else:
            out.append(0xDF)
            out += struct.pack(">I", n)
        for key in sorted(v, key=lambda k: str(k).encode("utf-8", "surrogatepass")):
            _pack(str(key), out)
            _pack(v[key], out)
    else:
        raise TypeError(f"cannot msgpack {type(v).__name__}")


def _pack_int(v: int, out: bytearray) -> None:
    if v >= 0:
        if v < 0x80:
            out.append(v)
        elif v < 0x100:
            out += bytes((0xCC, v))
        elif v < 0x10000:
            out.append(0xCD)
            out += struct.pack(">H", v)
        elif v < 0x100000000:
            out.append(0xCE)
            out += struct.pack(">I", v)
        elif v < 0x10000000000000000:
            out.append(0xCF)
            out += struct.pack(">Q", v)
        else:
            _pack(float(v), out)
    else:
        if v >= -32:
            out.append(v & 0xFF)
        elif v >= -0x80:
            out.append(0xD0)
            out += struct.pack(">b", v)
        elif v >= -0x8000:
            out.append(0xD1)
            out += struct.pack(">h", v)
        elif v >= -0x80000000:
            out.append(0xD2)
            out += struct.pack(">i", v)
        elif v >= -0x8000000000000000:
            out.append(0xD3)
            out += struct.pack(">q", v)
        else:
            _pack(float(v), out)


# ---------------------------------------------------------------------------------------------
# Blackboard values -> JSON (BT.CPP ExportBlackboardToJSON)
# ---------------------------------------------------------------------------------------------

MAX_ITEMS = 10_000  # per container: a request's work stays bounded
MAX_DEPTH = 8


def to_json_value(value: Any, depth: int = 0) -> Any:
    """A blackboard value as BT.CPP's JSON exporter shows it.

    str/int/float as is; **bool as 0/1** (BT::Any stores bools as integers); enums (NodeStatus
    included) as their integer; lists/tuples as arrays; dicts as maps; an object with a
    ``to_json()`` method as its result; anything else (no converter in BT.CPP) as null.
    """
    from bt_runtime.ports import EMPTY

    if value is None or value is EMPTY:
        return None
    if isinstance(value, bool):
        return int(value)
    if isinstance(value, int):  # IntEnum / NodeStatus included
        return int(value)
    if isinstance(value, float):
        return value
    if isinstance(value, str):
        return value
    if depth >= MAX_DEPTH:
        return None
    if isinstance(value, (list, tuple)):
        return [to_json_value(v, depth + 1) for v in value[:MAX_ITEMS]]
    if isinstance(value, dict):
        items = list(value.items())[:MAX_ITEMS]
        return {str(k): to_json_value(v, depth + 1) for k, v in items}
    import enum

    if isinstance(value, enum.Enum):
        return to_json_value(value.value, depth + 1)
    to_json = getattr(value, "to_json", None)
    if callable(to_json):
        try:
            return to_json_value(to_json(), depth + 1)
        except Exception:  # noqa: BLE001 - a broken converter shows as null, like BT.CPP
            return None
    if hasattr(value, "tolist"):  # numpy scalars and small arrays
        try:
            size = getattr(value, "size", 1)
            return to_json_value(value.tolist(), depth + 1) if size <= MAX_ITEMS else None
        except Exception:  # noqa: BLE001
            return None
    return None


def export_blackboard(bb: Any) -> Any:
    """A blackboard's *local* entries as a JSON object (sorted when packed); None if empty."""
    entries = bb.local_entries()
    if not entries:
        return None
    return {key: to_json_value(entry.value) for key, entry in entries.items()}


def is_finite_number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
