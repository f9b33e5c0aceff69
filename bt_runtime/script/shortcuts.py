"""One-frame closures for the statements trees use most: ``x := 1``, ``x := y``, ``x := y + 1``,
``x += 1``. The general closure of an assignment is three calls deep (the assignment, its value,
the variable it reads); these do the whole statement in one call when every entry involved
already exists and holds a double (or, for a copy or a constant, the destination's own kind),
and otherwise call the general closure, which holds the full rules. The fast path has no side
effect before it decides (finding an entry only fills the blackboard's look-up memory), so the
two can never disagree on what a statement does. Each closure's ``shape`` describes it, so
``node_ticks`` can make the whole tick of a Script node holding just that statement. The
general closure is built on first use: a statement that always takes the fast path never pays
for it at load.
"""

from __future__ import annotations

import operator
from collections.abc import Callable
from time import monotonic_ns as _monotonic_ns
from typing import Any

from .operators import ieee_div
from .parser import Binary, Literal, Name, Node
from .values import MAX_EXACT

Fn = Any  # Callable[[Blackboard, dict[str, int] | None], Any]

_ARITH = {"+": operator.add, "-": operator.sub, "*": operator.mul, "/": ieee_div}
_UPDATE = {"+=": operator.add, "-=": operator.sub, "*=": operator.mul, "/=": ieee_div}


def _number(node: Node) -> float | None:
    """The value of a numeric literal that converts to double exactly, else None."""
    if isinstance(node, Literal):
        value = node.value
        if type(value) is float or (type(value) is int and -MAX_EXACT <= value <= MAX_EXACT):
            return float(value)
    return None


class _Deferred:
    """``build(*args)(bb, enums)``, with ``build`` called once, on first use (a slotted object,
    not closures: two objects for the collector per statement instead of eight)."""

    __slots__ = ("_build", "_args", "_general")

    def __init__(self, build: Callable[..., Fn], args: tuple):
        self._build = build
        self._args = args
        self._general = None

    def __call__(self, bb, enums):
        general = self._general
        if general is None:
            general = self._general = self._build(*self._args)
        return general(bb, enums)


def shortcut_assign(op: str, key: str, value: Node, names: dict[str, str],
                    build: Callable[[str, str, Node, dict[str, str]], Fn]) -> Fn | None:
    """A one-frame closure for ``key op value`` that falls back on the general closure
    ``build(op, key, value, names)`` makes, or None when the statement has no shortcut.
    ``value`` is folded; ``names`` renames its variables."""
    general = _Deferred(build, (op, key, value, names))  # (dropped when there is no shortcut)
    if op in ("+=", "-=", "*=", "/="):
        number = _number(value)
        if number is None or (op == "/=" and number == 0.0):
            return None
        return _update_by_constant(key, _UPDATE[op], number, op == "+=", general)
    if op not in (":=", "="):
        return None
    if isinstance(value, Literal):
        constant = value.value
        if type(constant) is float or type(constant) is str:
            return _assign_same_kind(key, constant, general)
        if type(constant) is int and -MAX_EXACT <= constant <= MAX_EXACT:
            # ``x := 1`` into a double entry stores 1.0 (BT.CPP converts into the stored kind);
            # into any other kind of entry the general path decides
            return _assign_same_kind(key, float(constant), general)
        return None
    if isinstance(value, Name):
        return _copy(key, names.get(value.name, value.name), general)
    if isinstance(value, Binary) and isinstance(value.left, Name) and value.op in _ARITH:
        number = _number(value.right)
        if number is None or (value.op == "/" and number == 0.0):
            return None
        source = names.get(value.left.name, value.left.name)
        if value.op == "+":
            return _assign_name_plus(key, source, number, general)
        return _assign_name_arith(key, source, _ARITH[value.op], number, general)
    return None


def _update_by_constant(key: str, arith, number: float, plus: bool, general: Fn) -> Fn:
    if plus:
        def add_constant(bb, enums):
            entry = bb._resolved.get(key) or bb.get_entry(key)
            if entry is not None:
                old = entry.value
                if type(old) is float:
                    new = old + number
                    entry.value = new  # entry.write(new), inlined
                    entry.sequence_id += 1
                    entry.stamp = _monotonic_ns()
                    return new
            return general(bb, enums)
        add_constant.shape = ("update", key, operator.add, number)  # type: ignore[attr-defined]
        return add_constant

    def update_by_constant(bb, enums):
        entry = bb._resolved.get(key) or bb.get_entry(key)
        if entry is not None:
            old = entry.value
            if type(old) is float:
                new = arith(old, number)
                entry.value = new
                entry.sequence_id += 1
                entry.stamp = _monotonic_ns()
                return new
        return general(bb, enums)
    update_by_constant.shape = ("update", key, arith, number)  # type: ignore[attr-defined]
    return update_by_constant


def _assign_same_kind(key: str, constant: float | str, general: Fn) -> Fn:
    kind = type(constant)

    def assign_constant(bb, enums):
        entry = bb._resolved.get(key) or bb.get_entry(key)
        if entry is not None and type(entry.value) is kind:
            entry.value = constant
            entry.sequence_id += 1
            entry.stamp = _monotonic_ns()
            return constant
        return general(bb, enums)
    assign_constant.shape = ("constant", key, kind, constant)  # type: ignore[attr-defined]
    return assign_constant


def _copy(key: str, source: str, general: Fn) -> Fn:
    def copy(bb, enums):
        resolved = bb._resolved
        entry = resolved.get(key) or bb.get_entry(key)
        src = resolved.get(source) or bb.get_entry(source)
        if entry is not None and src is not None and not (enums and source in enums):
            value = src.value
            kind = type(value)
            if (kind is float or kind is str) and type(entry.value) is kind:
                entry.value = value
                entry.sequence_id += 1
                entry.stamp = _monotonic_ns()
                return value
        return general(bb, enums)
    copy.shape = ("copy", key, source)  # type: ignore[attr-defined]
    return copy


def _assign_name_plus(key: str, source: str, number: float, general: Fn) -> Fn:
    def assign_plus(bb, enums):
        resolved = bb._resolved
        entry = resolved.get(key) or bb.get_entry(key)
        src = resolved.get(source) or bb.get_entry(source)
        if entry is not None and src is not None and not (enums and source in enums):
            x = src.value
            if type(x) is float and type(entry.value) is float:
                new = x + number
                entry.value = new
                entry.sequence_id += 1
                entry.stamp = _monotonic_ns()
                return new
        return general(bb, enums)
    assign_plus.shape = ("arith", key, source, operator.add, number)  # type: ignore[attr-defined]
    return assign_plus


def _assign_name_arith(key: str, source: str, arith, number: float, general: Fn) -> Fn:
    def assign_arith(bb, enums):
        resolved = bb._resolved
        entry = resolved.get(key) or bb.get_entry(key)
        src = resolved.get(source) or bb.get_entry(source)
        if entry is not None and src is not None and not (enums and source in enums):
            x = src.value
            if type(x) is float and type(entry.value) is float:
                new = arith(x, number)
                entry.value = new
                entry.sequence_id += 1
                entry.stamp = _monotonic_ns()
                return new
        return general(bb, enums)
    assign_arith.shape = ("arith", key, source, arith, number)  # type: ignore[attr-defined]
    return assign_arith



def shortcut_maker(shape: tuple, index: dict[str, int]) -> Callable[[list[str], Fn], Fn] | None:
    """``f(names, general)``: the closure ``shortcut_assign`` makes for a statement of this
    ``shape`` (its own variables standing for placeholders, ``index`` their positions in
    ``names``) with the variables ``names`` and the general closure ``general``; None when the
    shape is not a shortcut's. Worked out once per template: a statement of a script of that
    template is then made without the decisions ``shortcut_assign`` takes."""
    kind = shape[0]
    if kind == "update":
        _, key, arith, number = shape
        i, plus = index[key], arith is operator.add
        return lambda names, general: _update_by_constant(names[i], arith, number, plus, general)
    if kind == "constant":
        _, key, _, constant = shape
        i = index[key]
        return lambda names, general: _assign_same_kind(names[i], constant, general)
    if kind == "copy":
        _, key, source = shape
        i, j = index[key], index[source]
        return lambda names, general: _copy(names[i], names[j], general)
    if kind == "arith":
        _, key, source, arith, number = shape
        i, j = index[key], index[source]
        if arith is operator.add:
            return lambda names, general: _assign_name_plus(names[i], names[j], number, general)
        return lambda names, general: _assign_name_arith(names[i], names[j], arith, number, general)
    return None
