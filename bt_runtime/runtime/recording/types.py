"""The ROS 2 message types a recording uses: a ``rosbags`` typestore holding only them (Jazzy's
definitions, ``msgdefs``) plus nav2_msgs' tree log.

One typestore per process, built in a few milliseconds. ``schema(typename)`` is the ``ros2msg``
text MCAP and Foxglove need (the type followed by every type it uses), ``serialize`` the CDR
bytes ROS 2 puts on the wire.
"""

from __future__ import annotations

from functools import cache
from typing import Any

# nav2_msgs as shipped with Jazzy (navigation2/nav2_msgs/msg)
NAV2_MSGS = {
    "nav2_msgs/msg/BehaviorTreeStatusChange": (
        "builtin_interfaces/Time timestamp\n"
        "string node_name\n"
        "uint16 uid\n"
        "string previous_status\n"
        "string current_status\n"),
    "nav2_msgs/msg/BehaviorTreeLog": (
        "builtin_interfaces/Time timestamp\n"
        "BehaviorTreeStatusChange[] event_log\n"),
}


@cache
def typestore() -> Any:
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    from .msgdefs import DEFINITIONS

    store = get_typestore(Stores.EMPTY)
    types: dict = {}
    for name, text in {**DEFINITIONS, **NAV2_MSGS}.items():
        types.update(get_types_from_msg(text, name))
    store.register(types)
    return store


@cache
def schema(typename: str) -> str:
    text, _ = typestore().generate_msgdef(typename, ros_version=2)
    return text


@cache
def type_hash(typename: str) -> str:
    return typestore().hash_rihs01(typename)


def serialize(message: Any, typename: str, size: int | None = None) -> bytes:
    """CDR (little endian) with rosbags' generated serializer. ``size``: the encoded size when
    the caller knows it (a reused message whose strings and sequences never change length), which
    saves rosbags' sizing pass."""
    store = typestore()
    msgdef = store.get_msgdef(typename)
    if size is None:
        size = 4 + msgdef.getsize_cdr(0, message, store)
    buffer = bytearray(size)
    buffer[1] = 1  # encapsulation: CDR little endian
    end = msgdef.serialize_cdr_le(memoryview(buffer)[4:], 0, message, store)
    if end + 4 != size:
        raise ValueError(f"{typename}: encoded {end + 4} bytes, expected {size}")
    return bytes(buffer)


def msg_class(typename: str) -> type:
    return typestore().types[typename]
