"""The whole tick of a Script node whose code is one shortcut statement (``x += 1``,
``x := y * 2``...) and of a ScriptCondition comparing a variable with a number (``x > 0``), in
one call: what a parent calls for such a node, instead of the node's tick calling the script.

Each handles only entries already found and holding doubles (or, for a constant or a copy, the
destination's own kind), with no side effect before it decides, and otherwise calls ``slow``,
the node's general tick, which holds every rule and reports errors. The statement forms are
read from the ``shape`` of the compiled closures (shortcuts.py, compiler.py). What a tick
reads comes in as default arguments: local variables, cheaper to read than closure cells, and
one tuple per tick function instead of a cell object per value (parents pass the node alone).
"""

from __future__ import annotations

import operator
from collections.abc import Callable
from functools import partial
from time import monotonic_ns as _monotonic_ns
from typing import Any

from ..errors import BTRuntimeError
from ..status import FAILURE, SUCCESS, NodeStatus
from .errors import CastError, ScriptRuntimeError
from .values import FLT_EPSILON

NodeTick = Callable[[Any], NodeStatus]


def script_node_tick(fn: Any, slow: NodeTick, text: str = "") -> NodeTick | None:
    """A one-call tick for a Script node whose compiled script is ``fn`` (source ``text``), or
    None."""
    shape = getattr(fn, "shape", None)
    return None if shape is None else shape_node_tick(shape, slow, text)


def shape_node_tick(shape: tuple, slow: NodeTick, text: str = "") -> NodeTick | None:
    """``script_node_tick`` for a compiled script of this ``shape``."""
    kind = shape[0]
    if kind == "sequence":
        return _statements(shape[1], text)
    make = _ACTION_MAKERS.get(kind)  # (None for a comparison: a Script node has no one-call tick for it)
    if make is None:
        return None
    names = NAMES_IN_SHAPE[kind]
    return make(*shape[1 + names:], slow, *shape[1:1 + names])


def condition_node_tick(fn: Any, slow: NodeTick) -> NodeTick | None:
    """A one-call tick for a ScriptCondition node whose compiled script is ``fn``, or None."""
    shape = getattr(fn, "shape", None)
    return None if shape is None else shape_condition_tick(shape, slow)


def shape_condition_tick(shape: tuple, slow: NodeTick) -> NodeTick | None:
    """``condition_node_tick`` for a compiled script of this ``shape``."""
    make = _CONDITION_MAKERS.get(shape[0])
    if make is None:
        return None
    _, key, *rest = shape
    return make(*rest, slow, key)


def action_maker(kind: str, rest: tuple, slow: NodeTick) -> Callable[..., NodeTick] | None:
    """``f(*names) -> the one-call tick`` of a Script node holding a statement of this kind
    (``shape`` = (kind, *names, *rest)), ``slow`` fixed; None when the kind has none. Worked out
    once per script template: making a node's tick is then one call."""
    make = _ACTION_MAKERS.get(kind)
    return None if make is None else partial(make, *rest, slow)


def condition_maker(kind: str, rest: tuple, slow: NodeTick) -> Callable[..., NodeTick] | None:
    """``action_maker`` for a ScriptCondition node."""
    make = _CONDITION_MAKERS.get(kind)
    return None if make is None else partial(make, *rest, slow)


# The statement shapes with a one-call tick: how many variable names follow the kind.
NAMES_IN_SHAPE = {"update": 1, "arith": 2, "constant": 1, "copy": 2, "order": 1, "equal": 1}


def _order(fails: Callable[[float, float], bool], number: float, slow: NodeTick, key: str) -> NodeTick:
    def order_tick(node, key=key, fails=fails, number=number, slow=slow):
        cfg = node.config
        entry = cfg.blackboard._resolved.get(key)
        if entry is not None:
            enums = cfg.enums
            if not (enums and key in enums):
                x = entry.value
                if type(x) is float:
                    return FAILURE if fails(x, number) else SUCCESS
        return slow(node)
    return order_tick


def _equal(equal: bool, number: float, slow: NodeTick, key: str) -> NodeTick:
    """``key == number`` (``equal``) or ``key != number``: equal within FLT_EPSILON, as BT.CPP."""
    hit, miss = (SUCCESS, FAILURE) if equal else (FAILURE, SUCCESS)

    def equal_tick(node, key=key, number=number, slow=slow, hit=hit, miss=miss):
        cfg = node.config
        entry = cfg.blackboard._resolved.get(key)
        if entry is not None:
            enums = cfg.enums
            if not (enums and key in enums):
                x = entry.value
                if type(x) is float:
                    return hit if abs(x - number) <= FLT_EPSILON else miss
        return slow(node)
    return equal_tick


def _statements(fns: tuple, text: str) -> NodeTick:
    """``a; b; c``: the statements' closures called from the node's tick, errors reported as
    ``Script.run`` reports them (compiler._run_action and the statement list in one frame)."""
    def statements_tick(node, fns=fns, text=text):
        cfg = node.config
        bb = cfg.blackboard
        enums = cfg.enums
        try:
            for f in fns:
                f(bb, enums)
        except CastError:
            raise
        except BTRuntimeError as exc:
            raise ScriptRuntimeError(f"Error in script [{text}]\n{exc}") from exc
        return SUCCESS
    return statements_tick


def _update(arith: Callable[[float, float], float], number: float, slow: NodeTick, key: str) -> NodeTick:
    if arith is operator.add:
        def add_tick(node, key=key, number=number, slow=slow):
            entry = node.config.blackboard._resolved.get(key)
            if entry is not None:
                old = entry.value
                if type(old) is float:
                    entry.value = old + number  # entry.write(...), inlined
                    entry.sequence_id += 1
                    entry.stamp = _monotonic_ns()
                    return SUCCESS
            return slow(node)
        return add_tick

    def update_tick(node, key=key, arith=arith, number=number, slow=slow):
        entry = node.config.blackboard._resolved.get(key)
        if entry is not None:
            old = entry.value
            if type(old) is float:
                entry.value = arith(old, number)
                entry.sequence_id += 1
                entry.stamp = _monotonic_ns()
                return SUCCESS
        return slow(node)
    return update_tick


def _arith(arith: Callable[[float, float], float], number: float, slow: NodeTick, key: str,
           source: str) -> NodeTick:
    if arith is operator.add and key == source:
        def increment_tick(node, key=key, number=number, slow=slow):  # x := x + C: one look-up
            cfg = node.config
            entry = cfg.blackboard._resolved.get(key)
            if entry is not None:
                enums = cfg.enums
                if not (enums and key in enums):
                    x = entry.value
                    if type(x) is float:
                        entry.value = x + number
                        entry.sequence_id += 1
                        entry.stamp = _monotonic_ns()
                        return SUCCESS
            return slow(node)
        return increment_tick

    if arith is operator.mul:
        def times_tick(node, key=key, source=source, number=number, slow=slow):
            cfg = node.config
            resolved = cfg.blackboard._resolved
            entry = resolved.get(key)
            src = resolved.get(source)
            if entry is not None and src is not None:
                enums = cfg.enums
                if not (enums and source in enums):
                    x = src.value
                    if type(x) is float and type(entry.value) is float:
                        entry.value = x * number
                        entry.sequence_id += 1
                        entry.stamp = _monotonic_ns()
                        return SUCCESS
            return slow(node)
        return times_tick

    if arith is operator.add:
        def plus_tick(node, key=key, source=source, number=number, slow=slow):
            cfg = node.config
            resolved = cfg.blackboard._resolved
            entry = resolved.get(key)
            src = resolved.get(source)
            if entry is not None and src is not None:
                enums = cfg.enums
                if not (enums and source in enums):
                    x = src.value
                    if type(x) is float and type(entry.value) is float:
                        entry.value = x + number
                        entry.sequence_id += 1
                        entry.stamp = _monotonic_ns()
                        return SUCCESS
            return slow(node)
        return plus_tick

    def arith_tick(node, key=key, source=source, arith=arith, number=number, slow=slow):
        cfg = node.config
        resolved = cfg.blackboard._resolved
        entry = resolved.get(key)
        src = resolved.get(source)
        if entry is not None and src is not None:
            enums = cfg.enums
            if not (enums and source in enums):
                x = src.value
                if type(x) is float and type(entry.value) is float:
                    entry.value = arith(x, number)
                    entry.sequence_id += 1
                    entry.stamp = _monotonic_ns()
                    return SUCCESS
        return slow(node)
    return arith_tick


def _constant(kind: type, constant: Any, slow: NodeTick, key: str) -> NodeTick:
    def constant_tick(node, key=key, kind=kind, constant=constant, slow=slow):
        entry = node.config.blackboard._resolved.get(key)
        if entry is not None and type(entry.value) is kind:
            entry.value = constant
            entry.sequence_id += 1
            entry.stamp = _monotonic_ns()
            return SUCCESS
        return slow(node)
    return constant_tick


def _copy(slow: NodeTick, key: str, source: str) -> NodeTick:
    def copy_tick(node, key=key, source=source, slow=slow):
        cfg = node.config
        resolved = cfg.blackboard._resolved
        entry = resolved.get(key)
        src = resolved.get(source)
        if entry is not None and src is not None:
            enums = cfg.enums
            if not (enums and source in enums):
                value = src.value
                kind = type(value)
                if (kind is float or kind is str) and type(entry.value) is kind:
                    entry.value = value
                    entry.sequence_id += 1
                    entry.stamp = _monotonic_ns()
                    return SUCCESS
        return slow(node)
    return copy_tick


# kind -> maker(*rest, slow, *names): the tick of a Script node holding a statement of that
# shape (the makers take the variable names last, so a partial of the rest makes them in one call)
_ACTION_MAKERS = {"update": _update, "arith": _arith, "constant": _constant, "copy": _copy}
# kind -> maker(*rest, slow, key): the tick of a ScriptCondition node holding that comparison
_CONDITION_MAKERS = {"order": _order, "equal": _equal}
