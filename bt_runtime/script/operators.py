"""The operators' full semantics on evaluated values (spec 6.4), shared by every closure.

The compiler's closures handle the common case (two doubles, a double and a constant)
inline and fall back to these functions for everything else, so the rules live in one place.
Messages are BT.CPP's; ``BTRuntimeError`` ones get wrapped with the script text by
``Script.run``, ``CastError`` ones do not.
"""

from __future__ import annotations

import math
from typing import Any

from ..errors import BTRuntimeError
from ..ports import EMPTY
from .errors import CastError
from .values import (
    FLT_EPSILON,
    TWO_63,
    cast_bool,
    cast_string,
    is_number,
    string_to_double,
    to_double,
    to_int64,
    type_name,
)

_INF = math.inf
# The hardware's default NaN (what 0.0/0.0 gives in C++; negative on x86-64).
_DEFAULT_NAN = _INF - _INF


def not_init(side: str, op: str) -> BTRuntimeError:
    return BTRuntimeError(f"The {side} operand of the operator [{op}] is not initialized")


def ieee_div(lv: float, rv: float) -> float:
    """Double division without Python's ZeroDivisionError: x/0 is +-inf, 0/0 and nan/0 NaN."""
    try:
        return lv / rv
    except ZeroDivisionError:
        if lv == 0.0 or lv != lv:
            return _DEFAULT_NAN if lv == 0.0 else lv
        return math.copysign(_INF, lv) * math.copysign(1.0, rv)


# --- unary ----------------------------------------------------------------------------------

def unary(op: str, v: Any) -> float:
    if is_number(v):
        rv = to_double(v)
        if op == "-":
            return -rv
        if op == "!":
            return 0.0 if rv else 1.0
        if rv > TWO_63 or rv < -TWO_63:
            raise BTRuntimeError("Number out of range for bitwise operation")
        # static_cast<int64_t>: truncation; NaN and 2^63 give INT64_MIN on x86-64.
        i = -(2**63) if rv != rv or rv == TWO_63 else int(rv)
        return float(~i)
    if type(v) is str:
        raise BTRuntimeError("Invalid operator for std::string")
    raise BTRuntimeError("ExprUnaryArithmetic: undefined")


# --- binary ---------------------------------------------------------------------------------

def _number_op(op: str, x: Any, y: Any) -> Any:
    lv = to_double(x)  # BT.CPP casts both to double before looking at the operator
    rv = to_double(y)
    if op == "+":
        return lv + rv
    if op == "-":
        return lv - rv
    if op == "*":
        return lv * rv
    if op == "/":
        return ieee_div(lv, rv)
    if op in ("&", "|", "^"):
        try:
            li = to_int64(x)
            ri = to_int64(y)
        except CastError:
            raise BTRuntimeError("Binary operators are not allowed if one of the operands is not "
                                 "an integer") from None
        return float(li & ri if op == "&" else li | ri if op == "|" else li ^ ri)
    if op in ("&&", "||"):
        try:
            lb = cast_bool(x)
            rb = cast_bool(y)
        except CastError:
            raise BTRuntimeError("Logic operators are not allowed if one of the operands is not "
                                 "castable to bool") from None
        return 1.0 if (lb and rb if op == "&&" else lb or rb) else 0.0
    return EMPTY  # '..' on two numbers falls through every case in BT.CPP: an empty value


def binary(op: str, x: Any, y: Any) -> Any:
    """``x op y`` for ``+ - * / & | ^ && || ..`` with both sides already evaluated."""
    if x is EMPTY:
        raise not_init("left", op)
    if y is EMPTY:
        raise not_init("right", op)
    tx = type(x)
    ty = type(y)
    x_num = tx is float or tx is int
    y_num = ty is float or ty is int
    if x_num and y_num:
        return _number_op(op, x, y)
    if tx is str and ty is str and op == "+":
        return x + y
    if op == ".." and ((tx is str and (ty is str or y_num)) or (x_num and ty is str)):
        return cast_string(x) + cast_string(y)
    raise BTRuntimeError("Operation not permitted")


# --- comparison -----------------------------------------------------------------------------

def link_holds(op: str, lv: Any, rv: Any) -> bool:
    """One comparison link, written as BT.CPP's 'fails when' tests (so NaN < 1 holds)."""
    if op == "==":
        return abs(lv - rv) <= FLT_EPSILON if type(lv) is float else lv == rv
    if op == "!=":
        return not (abs(lv - rv) <= FLT_EPSILON) if type(lv) is float else lv != rv
    if op == "<":
        return not (lv >= rv)
    if op == ">":
        return not (lv <= rv)
    if op == "<=":
        return not (lv > rv)
    return not (lv < rv)  # '>='


def compare(op: str, x: Any, y: Any, enums: dict[str, int] | None) -> bool:
    """Whether the link ``x op y`` holds; both sides already evaluated."""
    if x is EMPTY:
        raise not_init("left", op)
    if y is EMPTY:
        raise not_init("right", op)
    tx = type(x)
    ty = type(y)
    x_num = tx is float or tx is int
    y_num = ty is float or ty is int
    if x_num and y_num:
        return link_holds(op, to_double(x), to_double(y))
    if tx is str:
        if ty is str:
            return link_holds(op, x, y)
        if y_num:
            lv = string_to_double(x, enums)
            return link_holds(op, lv, to_double(y))
    elif x_num and ty is str:
        lv = to_double(x)
        return link_holds(op, lv, string_to_double(y, enums))
    raise BTRuntimeError(f"Can't mix different types in Comparison. Left operand [{type_name(x)}] "
                         f"right operand [{type_name(y)}]")
