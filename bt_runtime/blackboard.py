"""Hierarchical blackboards with BT.CPP's lookup, remapping and type-locking rules (spec 8).

Each SubTree expansion gets a child blackboard. A key resolves, in order: ``@key`` in the
root; the local map; an explicit subtree remapping to the parent; the parent itself when
autoremap is on (private ``_keys`` excepted). Entries are shared objects, so a remapped key in
a subtree *is* the parent's entry. Everything runs on one event loop, so there are no locks.
"""

from __future__ import annotations

import time
import weakref
from collections.abc import Callable
from typing import Any

from .errors import BTRuntimeError, LogicError
from .ports import ANY, ANYTYPE, EMPTY, PortType, casting_safe, type_of_value, value_to_string


class Entry:
    """One blackboard slot: value (or EMPTY), declared type, write counter and timestamp."""

    __slots__ = ("value", "type", "sequence_id", "stamp", "__weakref__")

    def __init__(self, type_: PortType = ANYTYPE, value: Any = EMPTY):
        self.value = value
        self.type = type_
        self.sequence_id = 0
        self.stamp = 0

    def write(self, value: Any) -> None:
        """Store without any checks, bumping the sequence id and the timestamp."""
        self.value = value
        self.sequence_id += 1
        self.stamp = time.monotonic_ns()

    @property
    def is_empty(self) -> bool:
        return self.value is EMPTY

    def __repr__(self) -> str:
        return f"Entry({self.value!r}, type={self.type.name}, seq={self.sequence_id})"


def _copy_into(value: Any, entry: Entry) -> Any:
    """BT.CPP ``Any::copyInto``: an empty entry takes the value as it is; otherwise the value is
    converted to the kind already stored (int64, uint64, double, string), so an int entry that
    first received 2.0 keeps holding doubles."""
    old = entry.value
    if old is EMPTY or type(old) is type(value):
        return value
    from .script.assign import _copy_into as copy_into
    from .script.values import normalize

    return copy_into(normalize(value), entry)


def _type_mismatch(key: str, previous: PortType, current: PortType) -> LogicError:
    return LogicError(f"Blackboard entry [{key}]: once declared, the type of a port shall not change. "
                      f"Previously declared type [{previous.name}], current type [{current.name}]")


_new_blackboard = object.__new__

# Blackboards whose look-up memory (``_resolved``) holds something: a change of structure
# empties exactly these, so a memory is always valid and a read never checks a generation.
_REMEMBERING: weakref.WeakSet[Blackboard] = weakref.WeakSet()


class Blackboard:
    """A scoped key -> Entry map with a parent, subtree remappings and optional autoremap.

    Every key found (local, through '@', remapping or autoremap) is remembered per blackboard
    in ``_resolved``, so a SubTree three levels deep does not walk the chain on every read and
    the compiled scripts read any variable with one dict look-up. Only entries that exist are
    remembered, so a new entry needs nothing; anything that could change what a key resolves
    to (a removed entry, entries replaced by cloning, a new remapping or autoremap setting)
    calls ``_structure_changed``, which empties every memory at once. (Adding or removing keys
    in the dict returned by ``local_entries()`` by hand bypasses this: use ``create_entry``,
    ``set`` and ``unset``.)"""

    __slots__ = ("_storage", "parent", "_remapping", "autoremap", "_resolved", "__weakref__")

    def __init__(self, parent: Blackboard | None = None):
        self._storage: dict[str, Entry] = {}
        self.parent = parent
        self._remapping: dict[str, str] = {}
        self.autoremap = False
        self._resolved: dict[str, Entry] = {}

    @staticmethod
    def _structure_changed() -> None:
        """Forget every remembered look-up (of every blackboard): the rare, load-time case."""
        if _REMEMBERING:
            for bb in list(_REMEMBERING):
                bb._resolved.clear()
            _REMEMBERING.clear()

    @classmethod
    def create(cls, parent: Blackboard | None = None) -> Blackboard:
        return cls(parent)

    @classmethod
    def _for_subtree(cls, parent: Blackboard, remapping: dict[str, str], autoremap: bool) -> Blackboard:
        """A new SubTree's blackboard, its remappings and autoremap set in one step (the tree
        builder, once per SubTree). Nothing has resolved a key through a blackboard not yet
        made, so no remembered look-up can be stale: no ``_structure_changed``."""
        self = _new_blackboard(cls)
        self._storage = {}
        self.parent = parent
        self._remapping = remapping
        self.autoremap = autoremap
        self._resolved = {}
        return self

    # -- structure -----------------------------------------------------------------------------
    def root(self) -> Blackboard:
        bb = self
        while bb.parent is not None:
            bb = bb.parent
        return bb

    def add_subtree_remapping(self, internal: str, external: str) -> None:
        self._remapping[internal] = external
        self._structure_changed()

    def enable_auto_remapping(self, enabled: bool = True) -> None:
        if enabled != self.autoremap:
            self.autoremap = enabled
            self._structure_changed()

    @property
    def remappings(self) -> dict[str, str]:
        return dict(self._remapping)

    # -- lookup --------------------------------------------------------------------------------
    def get_entry(self, key: str) -> Entry | None:
        """Resolve ``key`` through '@', the local map, remappings and autoremap (spec 8.2)."""
        resolved = self._resolved
        entry = resolved.get(key)
        if entry is not None:
            return entry
        entry = self._storage.get(key)  # local keys never start with '@'
        if entry is None:
            if key[:1] == "@":
                entry = self.root().get_entry(key[1:])
            else:
                parent = self.parent
                if parent is None:
                    return None
                ext = self._remapping.get(key)
                if ext is not None:
                    entry = parent.get_entry(ext)
                elif self.autoremap and key[:1] != "_":
                    entry = parent.get_entry(key)
            if entry is None:
                return None
        if not resolved:
            _REMEMBERING.add(self)
        resolved[key] = entry
        return entry

    def __contains__(self, key: str) -> bool:
        return self.get_entry(key) is not None

    def keys(self) -> list[str]:
        """Local keys only, like BT.CPP getKeys()."""
        return list(self._storage)

    get_keys = keys

    def local_entries(self) -> dict[str, Entry]:
        return self._storage

    # -- creation ------------------------------------------------------------------------------
    def create_entry(self, key: str, type_: PortType = ANYTYPE) -> Entry:
        """Create (or return, after a type check) the entry ``key`` (spec 8.3)."""
        if key[:1] == "@":
            if "@" in key[1:]:
                raise LogicError("Character '@' used multiple times in the key")
            return self.root().create_entry(key[1:], type_)
        entry = self._storage.get(key)
        if entry is not None:
            if entry.type.strongly_typed and type_.strongly_typed and entry.type != type_:
                raise _type_mismatch(key, entry.type, type_)
            return entry
        parent = self.parent
        if parent is not None:
            ext = self._remapping.get(key)
            if ext is not None:
                return parent.create_entry(ext, type_)
            if self.autoremap and key[:1] != "_":
                return parent.create_entry(key, type_)
        entry = Entry(type_)
        self._storage[key] = entry
        return entry

    # -- writing -------------------------------------------------------------------------------
    def set(self, key: str, value: Any, value_type: PortType | None = None) -> None:
        """Write with BT.CPP's rules (spec 8.4): first typed write locks the entry's type.

        ``value_type`` is the value's static type when the writer knows it (an output port's
        declared type, as C++'s ``setOutput<T>``); otherwise it is inferred from the value.
        """
        if key[:1] == "@":
            self.root().set(key[1:], value, value_type)
            return
        entry = self._storage.get(key)
        if entry is None:
            # Not local: create through remapping/autoremap rules (may land in a parent); an
            # existing entry found that way is type-checked strictly and written as is.
            if isinstance(value, str) and (value_type is None or value_type.kind == "string"):
                new_type = ANYTYPE
            else:
                new_type = value_type or type_of_value(value)
            self.create_entry(key, new_type).write(value)
            return
        self._write_local(key, entry, value, value_type)

    def _write_local(self, key: str, entry: Entry, value: Any, static_type: PortType | None = None) -> None:
        """BT.CPP ``Blackboard::set`` on an existing local entry (spec 8.4); ``static_type`` is
        the value's declared type when the writer knows it (an output port's)."""
        declared = entry.type
        if not declared.strongly_typed:
            entry.type = static_type or type_of_value(value)
            entry.write(value)
            return
        value_type = static_type or type_of_value(value)
        if value_type == declared:
            new = value
        elif isinstance(value, str):
            if not declared.has_converter:  # e.g. NodeStatus or enum entries
                raise self._set_mismatch(key, declared, value_type)
            new = declared.from_string(value)
        elif casting_safe(value, declared):
            new = value  # kept as it is: copyInto below decides the stored kind
        elif ((declared.kind == "custom" and declared.py_type is not None and isinstance(value, declared.py_type))
              or (declared.kind == "list" and isinstance(value, list))):
            entry.write(value)
            return
        else:
            raise self._set_mismatch(key, declared, value_type)
        entry.write(_copy_into(new, entry))

    def set_any(self, key: str, value: Any, value_type: PortType) -> None:
        """BT.CPP ``Blackboard::set<BT::Any>`` (what SetBlackboard calls): a new entry takes the
        value's own type, even std::string, so repeated string writes stay legal; an untyped
        entry becomes ``BT::Any``; a typed entry accepts only a value of its type, stored as is
        (no string or number conversion)."""
        if key[:1] == "@":
            self.root().set_any(key[1:], value, value_type)
            return
        entry = self._storage.get(key)
        if entry is None:
            self.create_entry(key, value_type).write(value)
            return
        declared = entry.type
        if not declared.strongly_typed:
            entry.type = ANY
        elif declared != value_type:
            raise self._set_mismatch(key, declared, ANY)
        entry.write(value)

    def _set_mismatch(self, key: str, previous: PortType, current: PortType) -> LogicError:
        return LogicError(f"Blackboard::set({key}): once declared, the type of a port shall not change. "
                          f"Previously declared type [{previous.name}], current type [{current.name}]")

    def unset(self, key: str) -> None:
        """Remove a *local* key (no '@', no remapping); nothing happens if it is absent."""
        if self._storage.pop(key, None) is not None:
            self._structure_changed()

    # -- reading -------------------------------------------------------------------------------
    def get(self, key: str, type_: PortType | type | None = None, default: Any = EMPTY) -> Any:
        """Read ``key``; optionally cast it to ``type_`` (spec 8.5). ``default`` if missing."""
        entry = self.get_entry(key)
        if entry is None:
            if default is not EMPTY:
                return default
            raise BTRuntimeError(f"Blackboard::get() error. Missing key [{key}]")
        if entry.value is EMPTY:
            if default is not EMPTY:
                return default
            raise BTRuntimeError(f"Blackboard::get() error. Entry [{key}] hasn't been initialized, yet")
        if type_ is None:
            return entry.value
        from .ports import port_type
        return port_type(type_).coerce(entry.value)

    def get_stamped(self, key: str) -> tuple[Any, int, int]:
        """(value, sequence_id, timestamp_ns) of ``key``."""
        entry = self.get_entry(key)
        if entry is None or entry.value is EMPTY:
            raise BTRuntimeError(f"Blackboard::get() error. Missing key [{key}]")
        return entry.value, entry.sequence_id, entry.stamp

    def clone_into(self, dst: Blackboard) -> None:
        """Copy every local entry into ``dst``; keys of dst not in self are removed."""
        self._structure_changed()
        for key in list(dst._storage):
            if key not in self._storage:
                del dst._storage[key]
        for key, src in self._storage.items():
            existing = dst._storage.get(key)
            if existing is not None:
                existing.type = src.type
                existing.write(src.value)
            else:
                clone = Entry(src.type, src.value)
                clone.sequence_id = src.sequence_id
                clone.stamp = src.stamp
                dst._storage[key] = clone

    def debug_message(self) -> str:
        """Print (as BT.CPP's debugMessage does) and return one line per local entry, with its
        type and value, and per remapping, with the type of the parent's entry it reaches."""
        lines = []
        for key, entry in self._storage.items():
            lines.append(f"{key} ({entry.type.name}) -> {value_to_string(entry.value)}")
        for internal, external in self._remapping.items():
            line = f"[{internal}] remapped to port of parent tree [{external}]"
            target = self.parent.get_entry(external) if self.parent is not None else None
            if target is not None:
                line += f" ({target.type.name})"
            lines.append(line)
        text = "\n".join(lines)
        print(text)
        return text

    def to_dict(self, convert: Callable[[Any], Any] | None = None) -> dict[str, Any]:
        """Local entries as plain values (EMPTY -> None); ``convert`` maps each value."""
        out = {}
        for key, entry in self._storage.items():
            value = None if entry.value is EMPTY else entry.value
            out[key] = convert(value) if convert else value
        return out

    def __repr__(self) -> str:
        return f"Blackboard(keys={self.keys()}, remap={self._remapping}, autoremap={self.autoremap})"
