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
    lean = _lean_get_msgdef(store)
    if lean is not None:
        store.get_msgdef = lean  # the instance's own: rosbags' generated code looks it up on the store
    return store


def _lean_get_msgdef(store: Any) -> Any:
    """rosbags' ``get_msgdef`` generates and compiles 15 functions per type (CDR and ROS 1, both
    byte orders, both directions); a recording needs 2 (CDR size and little-endian serializer),
    and the compiling was ~60 % of a recording's start-up. This one generates those two (and
    the ROS 1 size, a number rosbags' generators read from nested types) at once and the others
    on first use (through rosbags' own ``get_msgdef``). None when rosbags'
    generators are not where this rosbags version keeps them: rosbags' own is used then."""
    try:
        from dataclasses import fields

        from rosbags.interfaces import Msgdef
        from rosbags.serde.cdr import generate_getsize_cdr, generate_serialize_cdr
        from rosbags.serde.ros1 import generate_getsize_ros1
        from rosbags.typesys.base import normalize_fieldname
    except ImportError:
        return None
    names = [f.name for f in fields(Msgdef)]
    if names[:6] != ["name", "fields", "cls", "size_cdr", "getsize_cdr", "serialize_cdr_le"]:
        return None
    full = store.get_msgdef
    made: dict[str, Any] = {}

    def later(typename: str, attr: str) -> Any:
        return lambda *args: getattr(full(typename), attr)(*args)

    def get_msgdef(typename: str) -> Any:
        found = made.get(typename)
        if found is None:
            entries = [(normalize_fieldname(name), desc) for name, desc in store.fielddefs[typename][1]]
            getsize, size = generate_getsize_cdr(entries, store)
            values = {"name": typename, "fields": entries, "cls": store.types[typename], "size_cdr": size,
                      "getsize_cdr": getsize, "serialize_cdr_le": generate_serialize_cdr(entries, store, "le")}
            # the ROS 1 size is a plain number that rosbags' generators read from nested types
            values["getsize_ros1"], values["size_ros1"] = generate_getsize_ros1(entries, store)
            rest = {name: later(typename, name) for name in names if name not in values}
            found = made[typename] = Msgdef(**values, **rest)
        return found

    return get_msgdef


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
