"""Assignment (``:= = += -= *= /=``) into a blackboard entry, with BT.CPP's storage rules.

BT.CPP writes the entry's value directly (not through ``Blackboard.set``), so the type-lock
rules of ``set`` do not apply; instead the destination keeps its stored kind (int64, uint64,
double, string) and the value is converted into it (``Any::copyInto``), spec 6.4.
"""

from __future__ import annotations

import operator
from time import monotonic_ns as _monotonic_ns
from typing import Any

from ..blackboard import Blackboard, Entry
from ..errors import BTRuntimeError
from ..ports import ANYTYPE, EMPTY
from .errors import CastError
from .operators import ieee_div, not_init
from .values import (
    INT64_MAX,
    MAX_EXACT,
    TWO_63,
    UINT64_MAX,
    cast_string,
    normalize,
    string_to_double,
    to_double,
    to_int64,
    to_uint64,
    type_name,
)


def _kind(value: Any, entry: Entry | None = None) -> str:
    """BT.CPP's storage kind: 'i' int64, 'u' uint64, 'd' double, 's' string, else the type."""
    t = type(value)
    if t is float:
        return "d"
    if t is int:
        if value > INT64_MAX:
            return "u"
        if entry is not None:
            declared = entry.type
            if declared.kind == "int" and declared.lo == 0 and declared.hi == UINT64_MAX:
                return "u"
        return "i"
    if t is str:
        return "s"
    return t.__qualname__


def _copy_into(value: Any, entry: Entry) -> Any:
    """``value.copyInto(dst)``: the value converted to the destination's kind (CastError if not)."""
    dst = entry.value
    if dst is EMPTY:
        return value
    dst_kind = _kind(normalize(dst), entry)
    src_kind = _kind(value)
    if src_kind == dst_kind:
        return value
    if src_kind in ("i", "u", "d") and dst_kind in ("i", "u", "d"):
        if dst_kind == "i":
            return to_int64(value)
        if dst_kind == "u":
            return to_uint64(value)
        return to_double(value)
    raise CastError("Any::copyInto fails")


def _dst_type_name(entry: Entry) -> str:
    """What BT.CPP prints as the destination type: the declared type, or the stored value's."""
    if entry.value is EMPTY or entry.type.strongly_typed:
        return entry.type.name
    return type_name(entry.value)


def _has_converter(entry: Entry) -> bool:
    # BT.CPP gives enum-typed entries (NodeStatus included) no string converter: a string goes
    # through the number rule instead (scripting enums, then a numeric parse).
    declared = entry.type
    return declared.has_converter and declared.kind not in ("enum", "status")


def _source_type_name(value: Any, bb: Blackboard | None, source: str | None) -> str:
    """The type BT.CPP names for the right operand: a variable's value keeps its original C++
    type (a host ``bool`` or ``int`` entry), any other value is what the evaluator made."""
    if bb is not None and source is not None:
        entry = bb.get_entry(source)
        if entry is not None and entry.type.strongly_typed:
            return entry.type.name
    return type_name(value)


def _store(key: str, entry: Entry, value: Any, enums: dict[str, int] | None,
           bb: Blackboard | None = None, source: str | None = None) -> Any:
    """The ``:=`` / ``=`` rules once the entry exists and the value is known; ``source`` is the
    variable the value was read from, if the right side is a bare name (for the error text)."""
    dst = normalize(entry.value)
    if dst is EMPTY and entry.type.kind == "anytype":
        new = value
    elif type(value) is str and type(dst) is not str:
        if _has_converter(entry):
            new = entry.type.from_string(value)
        elif type(dst) in (int, float):
            new = string_to_double(value, enums)
        else:
            tn = _dst_type_name(entry)
            raise BTRuntimeError(f"Error assigning a value to entry [{key}] with type [{tn}]. "
                                 f"\nThe right operand is a string, can't convert to {tn}")
    else:
        try:
            new = _copy_into(value, entry)
        except CastError:
            tn = _dst_type_name(entry)
            raise BTRuntimeError(f"Error assigning a value to entry [{key}] with type [{tn}]. "
                                 f"\nThe right operand has type [{_source_type_name(value, bb, source)}] "
                                 "and can't be "
                                 f"converted to [{tn}]") from None
    entry.write(new)
    return normalize(new)


def _update(op: str, entry: Entry, value: Any) -> Any:
    """The ``+= -= *= /=`` rules once the entry exists and the value is known."""
    if entry.value is EMPTY:
        raise not_init("left", op)
    temp = normalize(entry.value)
    tv = type(value)
    if tv is float or tv is int:
        tt = type(temp)
        if tt is not float and tt is not int:
            raise BTRuntimeError("This Assignment operator can't be used with a non-numeric type")
        lv = to_double(temp)
        rv = to_double(value)
        if op == "+=":
            temp = lv + rv
        elif op == "-=":
            temp = lv - rv
        elif op == "*=":
            temp = lv * rv
        else:
            temp = ieee_div(lv, rv)
    elif tv is str:
        if op != "+=":
            raise BTRuntimeError("Operator not supported for strings")
        temp = cast_string(temp) + value
    new = _copy_into(temp, entry)  # errors here are not wrapped (plain std::runtime_error)
    entry.write(new)
    return normalize(new)


def missing_entry(key: str) -> BTRuntimeError:
    return BTRuntimeError(f"The blackboard entry [{key}] doesn't exist, yet.\n"
                          "If you want to create a new one, use the operator [:=] instead of [=]")


def _fast_int(result: float, entry: Entry) -> int | None:
    """A double stored into an int64 entry, when that cannot fail; None means 'take the slow path'."""
    if result.is_integer() and -TWO_63 <= result < TWO_63 and entry.type.hi != UINT64_MAX:
        return int(result)
    return None


def make_assign(op: str, key: str, value_fn, source: str | None = None):
    """A closure ``(bb, enums) -> stored value`` for ``key op <value_fn>``; ``source`` names the
    variable when the right side is a bare name (only an error text uses it).

    The closures inline the frequent cases (a double or int64 counter, a value of the entry's
    own kind); anything else goes through ``_store``/``_update``, which hold the full rules.
    """
    create = op == ":="

    def lookup(bb: Blackboard):
        entry = bb.get_entry(key)
        if entry is None:
            if not create:
                raise missing_entry(key)
            entry = bb.create_entry(key, ANYTYPE)
        return entry

    if op in (":=", "="):
        def assign(bb: Blackboard, enums):
            entry = bb._resolved.get(key) or lookup(bb)  # a local entry without the call
            value = value_fn(bb, enums)  # after the entry exists: 'x := x' is 'not initialized'
            if value is EMPTY:
                raise not_init("right", op)
            dst = entry.value
            tv = type(value)
            if (dst is EMPTY and entry.type.kind == "anytype") or (tv is type(dst) and tv is not int):
                entry.value = value  # entry.write(value), inlined
                entry.sequence_id += 1
                entry.stamp = _monotonic_ns()
                return value
            if type(dst) is int and tv is float and dst <= INT64_MAX:
                new = _fast_int(value, entry)
                if new is not None:
                    entry.write(new)
                    return new
            return _store(key, entry, value, enums, bb, source)
        return assign

    arith = {"+=": operator.add, "-=": operator.sub, "*=": operator.mul, "/=": ieee_div}[op]

    def update(bb: Blackboard, enums):
        entry = bb._resolved.get(key) or lookup(bb)  # a local entry without the call
        value = value_fn(bb, enums)
        if value is EMPTY:
            raise not_init("right", op)
        dst = entry.value
        td = type(dst)
        tv = type(value)
        if (td is float or (td is int and -MAX_EXACT <= dst <= MAX_EXACT)) and (
                tv is float or (tv is int and -MAX_EXACT <= value <= MAX_EXACT)):
            result = arith(float(dst), float(value))
            new = result if td is float else _fast_int(result, entry)
            if new is not None:
                entry.write(new)
                return new
        return _update(op, entry, value)
    return update


def make_bad_assign(op: str):
    """BT.CPP parses ``3 = 2`` but fails when it runs."""

    def bad(bb, enums):
        raise BTRuntimeError("Assignment left operand not a blackboard entry")

    return bad
