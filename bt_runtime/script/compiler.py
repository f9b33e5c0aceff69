"""AST -> nested Python closures, and the ``Script`` object callers run every tick.

Each AST node becomes a closure ``f(blackboard, enums) -> value``. The closures inline the
common case (doubles, a constant operand, a string compared with a constant) and call
``operators``/``assign`` for everything else, which holds the exact BT.CPP rules. Sub-trees
made only of literals are evaluated once here when that cannot fail. No ``eval``/``exec``.
"""

from __future__ import annotations

import operator
import re
from functools import lru_cache, partial
from typing import Any

from ..errors import BTRuntimeError
from ..ports import EMPTY
from ..status import FAILURE, SUCCESS
from .assign import make_assign, make_bad_assign
from .errors import CastError, ScriptError, ScriptRuntimeError
from .node_ticks import (
    NAMES_IN_SHAPE,
    action_maker,
    condition_maker,
    condition_node_tick,
    script_node_tick,
)
from .operators import binary, compare, ieee_div, unary
from .parser import Assign, Binary, Compare, Literal, Name, Node, ParseError, Ternary, Unary, parse
from .shortcuts import _Deferred, shortcut_assign, shortcut_maker
from .values import FLT_EPSILON, MAX_EXACT, cast_double, normalize, to_bool

Fn = Any  # Callable[[Blackboard, dict[str, int] | None], Any]

# For '<' '>' '<=' '>=': the test under which BT.CPP says the link fails (NaN-correct).
_FAILS = {"<": operator.ge, ">": operator.le, "<=": operator.gt, ">=": operator.lt}
_ARITH = {"+": operator.add, "-": operator.sub, "*": operator.mul, "/": ieee_div}


def _exact_number(value: Any) -> bool:
    """A constant that converts to double without error (so the fast path may use it)."""
    t = type(value)
    return t is float or (t is int and -MAX_EXACT <= value <= MAX_EXACT)


# --- leaves ---------------------------------------------------------------------------------

def _literal(value: Any) -> Fn:
    def literal(bb, enums):
        return value
    return literal


def _name(key: str) -> Fn:
    def name(bb, enums):
        if enums and key in enums:  # a scripting enum shadows a blackboard entry
            return float(enums[key])
        # bb.get_entry(key), whose first step (a local entry) is inlined: one call less per read
        entry = bb._resolved.get(key) or bb.get_entry(key)
        if entry is None:
            raise BTRuntimeError(f"Variable not found: {key}")
        value = entry.value
        t = type(value)
        if t is float or t is int or t is str:
            return value
        return normalize(value)
    return name


# --- operators ------------------------------------------------------------------------------

def _unary(op: str, f: Fn, operand: Node | None = None) -> Fn:
    if op == "!" and isinstance(operand, Name):
        key = operand.name

        def not_name(bb, enums):
            # f(bb, enums) inlined for a double in an entry already found (the usual '!flag')
            entry = None if enums and key in enums else bb._resolved.get(key)
            if entry is not None:
                v = entry.value
                if type(v) is float:
                    return 0.0 if v else 1.0
            v = f(bb, enums)
            if type(v) is float:
                return 0.0 if v else 1.0
            return unary("!", v)
        return not_name
    if op == "-":
        def negate(bb, enums):
            v = f(bb, enums)
            if type(v) is float:
                return -v
            return unary("-", v)
        return negate
    if op == "!":
        def logical_not(bb, enums):
            v = f(bb, enums)
            if type(v) is float:
                return 0.0 if v else 1.0
            return unary("!", v)
        return logical_not

    def complement(bb, enums):
        return unary(op, f(bb, enums))
    return complement


def _binary(op: str, lf: Fn, rf: Fn, right: Node, left: Node | None = None) -> Fn:
    arith = _ARITH.get(op)
    if arith is not None:
        if isinstance(right, Literal) and _exact_number(right.value) and not (op == "/" and right.value == 0):
            const = right.value
            rv = float(const)
            if isinstance(left, Name):
                key = left.name

                def name_arith_const(bb, enums):
                    # lf(bb, enums) inlined for a number in a local entry (the usual 'x + 1');
                    # anything else (an enum, a remapped key, another type) takes lf itself
                    entry = None if enums and key in enums else bb._resolved.get(key)
                    if entry is not None:
                        x = entry.value
                        t = type(x)
                        if t is float or (t is int and -MAX_EXACT <= x <= MAX_EXACT):
                            return arith(x, rv)
                    x = lf(bb, enums)
                    t = type(x)
                    if t is float or (t is int and -MAX_EXACT <= x <= MAX_EXACT):
                        return arith(x, rv)
                    return binary(op, x, const)
                return name_arith_const

            def arith_const(bb, enums):
                x = lf(bb, enums)
                t = type(x)
                if t is float or (t is int and -MAX_EXACT <= x <= MAX_EXACT):
                    return arith(x, rv)
                return binary(op, x, const)
            return arith_const

        def arith_any(bb, enums):
            x = lf(bb, enums)
            y = rf(bb, enums)
            if type(x) is float and type(y) is float:
                return arith(x, y)
            return binary(op, x, y)
        return arith_any

    if op == "&&":
        def logic_and(bb, enums):
            x = lf(bb, enums)
            y = rf(bb, enums)  # no short-circuit: both sides always run
            if type(x) is float and type(y) is float and x >= 0.0 and y >= 0.0:
                return 1.0 if (x != 0.0 and y != 0.0) else 0.0
            return binary(op, x, y)  # also the error for a negative (not castable to bool) side
        return logic_and
    if op == "||":
        def logic_or(bb, enums):
            x = lf(bb, enums)
            y = rf(bb, enums)
            if type(x) is float and type(y) is float and x >= 0.0 and y >= 0.0:
                return 1.0 if (x != 0.0 or y != 0.0) else 0.0
            return binary(op, x, y)
        return logic_or

    def other(bb, enums):  # & | ^ ..
        return binary(op, lf(bb, enums), rf(bb, enums))
    return other


def _compare_one(op: str, lf: Fn, rf: Fn, right: Node, left: Node | None = None) -> Fn:
    """A single comparison link (the usual case), with fast paths."""
    const = right.value if isinstance(right, Literal) else EMPTY
    if _exact_number(const):
        rv = float(const)
        if op not in ("==", "!=") and isinstance(left, Name):
            fails = _FAILS[op]
            key = left.name

            def name_order_number(bb, enums):
                # lf(bb, enums) inlined for a number in a local entry (the usual 'x > 0')
                entry = None if enums and key in enums else bb._resolved.get(key)
                if entry is not None:
                    x = entry.value
                    t = type(x)
                    if t is float or (t is int and -MAX_EXACT <= x <= MAX_EXACT):
                        return 0.0 if fails(x, rv) else 1.0
                x = lf(bb, enums)
                t = type(x)
                if t is float or (t is int and -MAX_EXACT <= x <= MAX_EXACT):
                    return 0.0 if fails(x, rv) else 1.0
                return 1.0 if compare(op, x, const, enums) else 0.0
            name_order_number.shape = ("order", key, fails, rv)  # type: ignore[attr-defined]  # node_ticks
            return name_order_number
        if op in ("==", "!="):
            same, differ = (1.0, 0.0) if op == "==" else (0.0, 1.0)
            if isinstance(left, Name):
                key = left.name

                def name_eq_number(bb, enums):
                    # lf(bb, enums) inlined for a number in a local entry (the usual 'code == 3')
                    entry = None if enums and key in enums else bb._resolved.get(key)
                    if entry is not None:
                        x = entry.value
                        t = type(x)
                        if t is float or (t is int and -MAX_EXACT <= x <= MAX_EXACT):
                            return same if abs(x - rv) <= FLT_EPSILON else differ
                    x = lf(bb, enums)
                    t = type(x)
                    if t is float or (t is int and -MAX_EXACT <= x <= MAX_EXACT):
                        return same if abs(x - rv) <= FLT_EPSILON else differ
                    return 1.0 if compare(op, x, const, enums) else 0.0
                name_eq_number.shape = ("equal", key, op == "==", rv)  # type: ignore[attr-defined]  # node_ticks
                return name_eq_number

            def eq_number(bb, enums):
                x = lf(bb, enums)
                t = type(x)
                if t is float or (t is int and -MAX_EXACT <= x <= MAX_EXACT):
                    return same if abs(x - rv) <= FLT_EPSILON else differ
                return 1.0 if compare(op, x, const, enums) else 0.0
            return eq_number
        fails = _FAILS[op]

        def ordey_number(bb, enums):
            x = lf(bb, enums)
            t = type(x)
            if t is float or (t is int and -MAX_EXACT <= x <= MAX_EXACT):
                return 0.0 if fails(x, rv) else 1.0
            return 1.0 if compare(op, x, const, enums) else 0.0
        return ordey_number

    if type(const) is str:
        test = {"==": operator.eq, "!=": operator.ne, "<": operator.lt, ">": operator.gt,
                "<=": operator.le, ">=": operator.ge}[op]

        def with_string(bb, enums):
            x = lf(bb, enums)
            if type(x) is str:
                return 1.0 if test(x, const) else 0.0
            return 1.0 if compare(op, x, const, enums) else 0.0
        return with_string

    def general(bb, enums):
        x = lf(bb, enums)
        y = rf(bb, enums)
        return 1.0 if compare(op, x, y, enums) else 0.0
    return general


def _compare_chain(ops: list[str], fns: list[Fn]) -> Fn:
    first = fns[0]
    links = list(zip(ops, fns[1:]))

    def chain(bb, enums):
        x = first(bb, enums)
        for op, f in links:
            y = f(bb, enums)  # later operands only run while the chain holds
            if not compare(op, x, y, enums):
                return 0.0
            x = y
        return 1.0
    return chain


def _ternary(cf: Fn, tf: Fn, ef: Fn) -> Fn:
    def ternary(bb, enums):
        c = cf(bb, enums)
        # BT.CPP means "non-empty string is true" but its type test never matches a string,
        # so a string condition goes through the numeric cast (and fails if not numeric).
        if (c != 0.0) if type(c) is float else (cast_double(c) != 0.0):
            return tf(bb, enums)
        return ef(bb, enums)
    return ternary


def _sequence(fns: list[Fn]) -> Fn:
    if len(fns) == 1:
        return fns[0]
    head = fns[:-1]
    last = fns[-1]

    def sequence(bb, enums):
        for f in head:
            f(bb, enums)
        return last(bb, enums)
    sequence.shape = ("sequence", tuple(fns))  # type: ignore[attr-defined]  # node_ticks
    return sequence


# --- folding and dispatch -------------------------------------------------------------------

def _fold(node: Node) -> Node:
    """Replace a unary/binary operator over literals by its value, when that cannot fail."""
    if isinstance(node, Unary):
        operand = _fold(node.operand)
        if isinstance(operand, Literal):
            try:
                return Literal(unary(node.op, operand.value))
            except BTRuntimeError:
                pass
        return Unary(node.op, operand)
    if isinstance(node, Binary):
        left, right = _fold(node.left), _fold(node.right)
        if isinstance(left, Literal) and isinstance(right, Literal):
            try:
                value = binary(node.op, left.value, right.value)
                if value is not EMPTY:
                    return Literal(value)
            except BTRuntimeError:
                pass
        return Binary(node.op, left, right)
    return node


def _fold_all(node: Node) -> Node:
    """``_fold`` applied wherever compiling folds: at every node (``_fold`` itself stops at
    comparisons, ternaries and assignments)."""
    node = _fold(node)
    if isinstance(node, Unary):
        return Unary(node.op, _fold_all(node.operand))
    if isinstance(node, Binary):
        return Binary(node.op, _fold_all(node.left), _fold_all(node.right))
    if isinstance(node, Compare):
        return Compare(node.ops, [_fold_all(n) for n in node.operands])
    if isinstance(node, Ternary):
        return Ternary(_fold_all(node.cond), _fold_all(node.then), _fold_all(node.other))
    if isinstance(node, Assign):
        return Assign(node.op, node.target, _fold_all(node.value))
    return node


def compile_node(node: Node, names: dict[str, str] | None = None) -> Fn:
    """The closure of ``node``; ``names`` renames variables (a template's placeholders)."""
    return _emit(_fold_all(node), names or {})


def _general_assign(op: str, key: str, value: Node, names: dict[str, str]) -> Fn:
    """The general closure of ``key op value`` (a shortcut makes it only if it needs it)."""
    source = names.get(value.name, value.name) if isinstance(value, Name) else None
    return make_assign(op, key, _emit(value, names), source)


def _emit(node: Node, names: dict[str, str]) -> Fn:
    """``compile_node`` of a node already through ``_fold_all``."""
    emit = _EMITTERS.get(type(node))  # one look-up instead of a chain of isinstance tests
    if emit is None:
        for kind, emit in _EMITTERS.items():  # (a subclass of an AST node class)
            if isinstance(node, kind):
                return emit(node, names)
        raise TypeError(f"unknown AST node {node!r}")
    return emit(node, names)


def _emit_literal(node: Literal, names: dict[str, str]) -> Fn:
    return _literal(node.value)


def _emit_name(node: Name, names: dict[str, str]) -> Fn:
    return _name(names.get(node.name, node.name))


def _emit_unary(node: Unary, names: dict[str, str]) -> Fn:
    operand = node.operand
    if isinstance(operand, Name):
        operand = Name(names.get(operand.name, operand.name))
    return _unary(node.op, _emit(node.operand, names), operand)


def _emit_binary(node: Binary, names: dict[str, str]) -> Fn:
    left = node.left
    if isinstance(left, Name):
        left = Name(names.get(left.name, left.name))
    return _binary(node.op, _emit(node.left, names), _emit(node.right, names), node.right, left)


def _emit_compare(node: Compare, names: dict[str, str]) -> Fn:
    operands = node.operands
    if len(node.ops) == 1:
        left, right = operands
        fns = (_emit(left, names), _emit(right, names))
        if isinstance(left, Name):
            left = Name(names.get(left.name, left.name))
        return _compare_one(node.ops[0], fns[0], fns[1], right, left)
    return _compare_chain(node.ops, [_emit(n, names) for n in operands])


def _emit_ternary(node: Ternary, names: dict[str, str]) -> Fn:
    return _ternary(_emit(node.cond, names), _emit(node.then, names), _emit(node.other, names))


def _emit_assign(node: Assign, names: dict[str, str]) -> Fn:
    if isinstance(node.target, Name):
        key = names.get(node.target.name, node.target.name)
        return (shortcut_assign(node.op, key, node.value, names, _general_assign)
                or _general_assign(node.op, key, node.value, names))
    return make_bad_assign(node.op)


_EMITTERS: dict[type, Any] = {Literal: _emit_literal, Name: _emit_name, Unary: _emit_unary, Binary: _emit_binary,
                              Compare: _emit_compare, Ternary: _emit_ternary, Assign: _emit_assign}


# --- templates: scripts that differ only in their variable names share one parse ---------------

# A run of identifier characters where the lexer starts an identifier token: after a character
# that is not one of [A-Za-z0-9_] (\b, ASCII), so not inside a number such as 1e5, 0x1f or the
# error token 3foo. The split keeps the names.
_IDENTIFIER = re.compile(r"(?a)\b([A-Za-z_]\w*)")
_MARK = "\x00"  # stands for a variable in a template's key (the text itself never contains it)
# key -> the template, None when the key has none: texts the template path leaves to the plain
# parse (string literals and '@', with identifiers inside them; non-ASCII; an identifier right
# after a dot, as in 'a..b' or '65.x', which the lexer may read as part of a number), and keys
# whose template does not parse. All of these show in the key, which is tested once.
_templates: dict[str, _Template | None] = {}
_PLACEHOLDERS = tuple(f"_{i}" for i in range(32))  # what a template's variables are renamed to
_TEMPLATES_KEPT = 4096


class _Template:
    """The folded statements of a template (variables renamed ``_0``, ``_1``... in order of
    appearance), its placeholders, and for a one-statement template with a one-call node
    tick its ``form``: the compiled statement's ``shape`` with each variable name replaced by
    its placeholder's index, and the makers of that tick for a Script and a ScriptCondition
    node (node_ticks.action_maker: ``f(*names) -> tick``). With a form, a script of the
    template needs no closure to be ticked by a node (``Script.action_tick``); its closure is
    compiled on first need. ``form`` is (kind, index of the first name, index of the second
    or None, the rest).

    For a template of several statements, ``steps`` holds per statement the maker of its
    shortcut closure (shortcuts.shortcut_maker: ``f(names, general)``), or None for a
    statement that is compiled in full."""

    __slots__ = ("statements", "placeholders", "form", "make_action", "make_condition", "steps")

    def __init__(self, statements: list[Node], placeholders: tuple[str, ...]):
        self.statements = statements
        self.placeholders = placeholders
        self.form = self.make_action = self.make_condition = self.steps = None
        if len(statements) > 1:
            index = {p: i for i, p in enumerate(placeholders)}
            steps = []
            for statement in statements:
                shape = getattr(_emit(statement, {}), "shape", None)
                steps.append(shortcut_maker(shape, index) if shape is not None else None)
            if any(steps):
                self.steps = tuple(steps)
        elif len(statements) == 1:
            shape = getattr(_emit(statements[0], {}), "shape", None)
            count = NAMES_IN_SHAPE.get(shape[0]) if shape is not None else None
            if count is not None:
                index = {p: i for i, p in enumerate(placeholders)}
                kind, rest = shape[0], shape[1 + count:]
                self.form = (kind, index[shape[1]], None if count == 1 else index[shape[2]], rest)
                self.make_action = action_maker(kind, rest, _action_slow)
                self.make_condition = condition_maker(kind, rest, _condition_slow)


def _new_template(key: str) -> _Template | None:
    """The template of ``key`` (see _templates), made and kept."""
    template = None
    if not ("'" in key or "@" in key or not key.isascii() or ".\x00" in key):
        pieces = key.split(_MARK)
        count = len(pieces) - 1
        placeholders = (_PLACEHOLDERS[:count] if count <= len(_PLACEHOLDERS)
                        else tuple(f"_{i}" for i in range(count)))
        text = [pieces[0]]  # (a loop: cheaper than generators for a few names)
        for i in range(count):
            text.append(placeholders[i])
            text.append(pieces[i + 1])
        try:
            template = _Template([_fold_all(s) for s in parse("".join(text))], placeholders)
        except (ParseError, RecursionError):  # (the plain parse reports the error; a try costs
            template = None                    # less than contextlib.suppress)
    if len(_templates) >= _TEMPLATES_KEPT:
        _templates.clear()
    _templates[key] = template
    return template


# --- public object --------------------------------------------------------------------------

def _run_action(fn: Fn, text: str, node: Any) -> Any:
    """The general tick of a Script node (``Script.action_tick``)."""
    cfg = node.config
    try:
        fn(cfg.blackboard, cfg.enums)
    except CastError:
        raise
    except BTRuntimeError as exc:
        raise ScriptRuntimeError(f"Error in script [{text}]\n{exc}") from exc
    return SUCCESS


def _run_condition(fn: Fn, text: str, node: Any) -> Any:
    """The general tick of a ScriptCondition node (``Script.condition_tick``)."""
    cfg = node.config
    try:
        value = fn(cfg.blackboard, cfg.enums)
    except CastError:
        raise
    except BTRuntimeError as exc:
        raise ScriptRuntimeError(f"Error in script [{text}]\n{exc}") from exc
    if type(value) is float and value >= 0.0:
        return SUCCESS if value != 0.0 else FAILURE
    return SUCCESS if to_bool(value) else FAILURE


class Script:
    """A compiled script. ``run`` returns the last expression's value (int, float, str, EMPTY).

    A script of one statement that a node ticks in one call (``x := x + 1``, ``x > 0``: its
    template has a ``form``) is made without its closure: a Script or ScriptCondition node
    holding it (as ``node._script``) ticks through ``node_ticks`` and needs the closure only
    when that tick hands over (an entry not found, or of another kind), which is rare; the
    closure is compiled then, or when ``run`` or ``_fn`` is first used. The first tick of a
    node finds its entries (``_resolve``) and ticks again without the closure. Such a tick
    hands over to ``_action_slow``/``_condition_slow``, which reach the script through the
    node, so the script may keep its tick: no reference cycle, a dropped tree's scripts are
    freed by reference counting."""

    __slots__ = ("text", "_compiled", "_action_tick", "_condition_tick", "_template", "_names")

    def __init__(self, text: str, fn: Fn):
        self.text = text
        self._compiled = fn
        self._action_tick = self._condition_tick = self._template = self._names = None

    @property
    def _fn(self) -> Fn:
        """The script's closure ``f(blackboard, enums) -> value`` (compiled now if not yet)."""
        return self._compiled or self._compile()

    def _compile(self) -> Fn:
        template = self._template
        names = dict(zip(template.placeholders, self._names))
        fn = self._compiled = _emit(template.statements[0], names)
        return fn

    def _resolve(self, node: Any) -> bool:
        """Find the entries the statement's one-call tick reads that the node's blackboard has
        not remembered yet (``get_entry`` remembers what it finds; finding has no other
        effect). True when some were missing and all are found now: the tick may try again."""
        _, first, second, _ = self._template.form
        bb = node.config.blackboard
        resolved = bb._resolved
        names = self._names
        found_new = False
        for i in (first,) if second is None else (first, second):
            key = names[i]
            if key not in resolved:
                if bb.get_entry(key) is None:
                    return False
                found_new = True
        return found_new

    def action_tick(self) -> Any:
        """``f(node) -> SUCCESS`` that runs the script on the node's blackboard, errors reported
        as ``run`` reports them: the whole tick of a Script node in one call (shared by every
        node with this text; node_ticks.py makes a one-frame one for the commonest statements)."""
        tick = self._action_tick
        if tick is None:
            template = self._template
            if self._compiled is None and template.make_action is not None:  # (its names fill the form)
                _, first, second, _ = template.form
                names = self._names
                make = template.make_action
                tick = make(names[first]) if second is None else make(names[first], names[second])
            else:
                fn = self._fn
                tick = script_node_tick(fn, partial(_run_action, fn, self.text), self.text)
                if tick is None:
                    tick = partial(_run_action, fn, self.text)
            self._action_tick = tick
        return tick

    def condition_tick(self) -> Any:
        """``f(node) -> SUCCESS | FAILURE``: ``run_bool`` on the node's blackboard, the whole
        tick of a ScriptCondition node in one call."""
        tick = self._condition_tick
        if tick is None:
            template = self._template
            if self._compiled is None and template.make_condition is not None:
                _, first, second, _ = template.form
                names = self._names
                make = template.make_condition
                tick = make(names[first]) if second is None else make(names[first], names[second])
            else:
                fn = self._fn
                tick = condition_node_tick(fn, partial(_run_condition, fn, self.text))
                if tick is None:
                    tick = partial(_run_condition, fn, self.text)
            self._condition_tick = tick
        return tick

    def run(self, blackboard, enums: dict[str, int] | None = None) -> Any:
        try:
            return (self._compiled or self._compile())(blackboard, enums)
        except CastError:
            raise
        except BTRuntimeError as exc:
            raise ScriptRuntimeError(f"Error in script [{self.text}]\n{exc}") from exc

    def run_bool(self, blackboard, enums: dict[str, int] | None = None) -> bool:
        """``run`` then the bool conversion of spec 6.5 (pre-conditions, ScriptCondition)."""
        try:
            value = (self._compiled or self._compile())(blackboard, enums)
        except CastError:
            raise
        except BTRuntimeError as exc:
            raise ScriptRuntimeError(f"Error in script [{self.text}]\n{exc}") from exc
        if type(value) is float and value >= 0.0:
            return value != 0.0
        return to_bool(value)  # negative numbers do not convert to bool

    def __repr__(self) -> str:
        return f"Script({self.text!r})"


def _action_slow(node: Any) -> Any:
    """What the one-call tick of a Script node whose script has no closure yet hands over to:
    find the entries and tick again, or compile the closure and run the general tick."""
    script = node._script
    fn = script._compiled
    if fn is None:
        if script._resolve(node):
            return script._action_tick(node)
        fn = script._compile()
    return _run_action(fn, script.text, node)


def _condition_slow(node: Any) -> Any:
    """``_action_slow`` for a ScriptCondition node."""
    script = node._script
    fn = script._compiled
    if fn is None:
        if script._resolve(node):
            return script._condition_tick(node)
        fn = script._compile()
    return _run_condition(fn, script.text, node)


_new_object = object.__new__


@lru_cache(maxsize=4096)
def compile_script(text: str) -> Script:
    """Parse and compile ``text`` once (cached: a Script holds no state, so it can be shared).

    Raises ``ScriptError`` ('Error in the script "<text>"\\n<parser message>').
    """
    try:
        # The template of ``text`` and its variable names in order of appearance (what the
        # template's placeholders stand for), if the text is fit for one and its template
        # parses (else the plain parse reports the error with the text's own positions and
        # names). The token kinds of the template are those of the text, so it parses exactly
        # when the text does, into the same tree with the names renamed.
        template = None
        if _MARK not in text:
            parts = _IDENTIFIER.split(text)  # [text, name, text, name, ..., text]: one pass
            key = _MARK.join(parts[0::2])
            template = _templates.get(key, EMPTY)
            if template is EMPTY:
                template = _new_template(key)
            if template is not None:
                names = parts[1::2]
                if "true" in names or "false" in names:  # literals, not variables: no template
                    template = None
        if template is not None:
            if template.form is not None:  # made without its closure (see Script)
                script = _new_object(Script)
                script.text = text
                script._compiled = script._action_tick = script._condition_tick = None
                script._template = template
                script._names = names
                return script
            statements = template.statements
            renaming = dict(zip(template.placeholders, names))
            steps = template.steps
            if steps is not None:  # (what _emit gives, without its decisions: see _Template)
                fn = _sequence([_emit(s, renaming) if make is None else
                                make(names, _Deferred(_general_assign, (s.op, renaming[s.target.name], s.value,
                                                                        renaming)))
                                for s, make in zip(statements, steps)])
            else:
                fn = (_emit(statements[0], renaming) if len(statements) == 1
                      else _sequence([_emit(s, renaming) for s in statements]))
        else:
            fn = _sequence([compile_node(s) for s in parse(text)])
    except ParseError as exc:
        raise ScriptError(text, str(exc)) from None
    except RecursionError:
        raise ScriptError(text, "Parse error at position 0: expression nested too deeply") from None
    return Script(text, fn)


def forget_compiled() -> None:
    """Empty the caches of compiled scripts and templates (a fresh process: benchmarks)."""
    compile_script.cache_clear()
    _templates.clear()
