"""Script values and BT.CPP's ``Any`` cast rules, as the evaluator needs them (spec 6.3, 7.5).

Inside the evaluator a value is one of: ``int`` (int64, or uint64 when above INT64_MAX),
``float`` (double), ``str``, ``EMPTY`` or any other object. ``normalize`` maps what a
blackboard may hold onto that set (``bool`` and int enums are int64 in BT.CPP), so operators
only test ``type(v) is float`` and friends. Errors raised here are ``CastError``: BT.CPP throws
them as plain ``std::runtime_error`` and the script wrapper lets them through unwrapped.
"""

from __future__ import annotations

import math
import re
from enum import Enum
from typing import Any

from ..ports import EMPTY, format_double, type_of_value
from .errors import CastError

INT64_MIN, INT64_MAX = -(2**63), 2**63 - 1
UINT64_MAX = 2**64 - 1
MAX_EXACT = 2**53 - 1          # largest int a double holds exactly (BT.CPP checkTruncation)
TWO_63 = 2.0**63
TWO_64 = 2.0**64
FLT_EPSILON = 1.1920928955078125e-07

# std::from_chars(double), chars_format::general: no leading '+'/space, no hex, trailing ignored.
_FROM_CHARS = re.compile(
    r"-?(?:(?P<special>inf(?:inity)?|nan(?:\([0-9A-Za-z_]*\))?)"
    r"|(?P<mant>[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?)", re.IGNORECASE)


def from_chars_double(text: str) -> float | None:
    """``std::from_chars`` for a double: the value of the longest valid prefix, or None.

    None also for overflow to infinity and underflow to zero (``result_out_of_range``).
    """
    m = _FROM_CHARS.match(text)
    if m is None:
        return None
    special = m.group("special")
    if special is not None:
        value = math.inf if special[0] in "iI" else math.nan
        return -value if text[0] == "-" else value
    value = float(m.group(0))
    if math.isinf(value):
        return None
    if value == 0.0 and m.group("mant").strip("0.") != "":
        return None
    return value


def normalize(value: Any) -> Any:
    """Map a blackboard value onto the evaluator's kinds (bool and int enums become int)."""
    t = type(value)
    if t is int or t is float or t is str or value is EMPTY:
        return value
    if isinstance(value, int):  # bool, IntEnum (NodeStatus)
        return int(value)
    if isinstance(value, float):
        return float(value)
    if isinstance(value, str):
        return str(value)
    if isinstance(value, Enum) and isinstance(value.value, int):
        return int(value.value)
    return value


def is_number(value: Any) -> bool:
    t = type(value)
    return t is float or t is int


def type_name(value: Any) -> str:
    """The C++ type name BT.CPP prints for a script value (``long``, ``double``, ``std::string``)."""
    t = type(value)
    if t is int:
        return "long" if value <= INT64_MAX else "unsigned long"
    if t is float:
        return "double"
    if t is str:
        return "std::string"
    if t is bool:
        return "bool"
    if value is EMPTY:
        return "BT::Any"
    return type_of_value(value).name


def to_double(value: Any) -> float:
    """``Any::cast<double>`` of a number: an int beyond 2^53-1 cannot be converted."""
    if type(value) is float:
        return value
    if -MAX_EXACT <= value <= MAX_EXACT or value == INT64_MIN:  # abs(INT64_MIN) wraps in C++
        return float(value)
    raise CastError(f"Loss of precision when converting a large integer number to floating point:{value}")


def double_to_int64(value: float) -> int:
    """``Any::cast<int64_t>`` of a double: whole and in range, else an error."""
    if value >= TWO_63 or value < -TWO_63 or value != value or value != math.floor(value):
        raise CastError("Invalid floating point to integer conversion")
    return int(value)


def to_int64(value: Any) -> int:
    """``Any::cast<int64_t>`` of a number."""
    if type(value) is float:
        return double_to_int64(value)
    if value > INT64_MAX:
        raise CastError("Value outside the max numerical limit.")
    return value


NEGATIVE_TO_UNSIGNED = "Value is negative and can't be converted to unsigned"


def to_uint64(value: Any) -> int:
    """``Any::cast<uint64_t>`` of a number."""
    if value < 0:
        raise CastError("Value is negative and can't be converted to unsigned")
    if type(value) is float:
        if value >= TWO_64 or value != value or value != math.floor(value):
            raise CastError("Invalid floating point to integer conversion")
        return int(value)
    return value


def cast_bool(value: Any) -> bool:
    """``Any::cast<bool>``: double != 0; an integer must be 0 or 1; nothing else converts.
    bool is unsigned for BT.CPP's convertNumber, so any negative number is rejected first."""
    t = type(value)
    if t is float:
        if value < 0.0:
            raise CastError(NEGATIVE_TO_UNSIGNED)
        return value != 0.0
    if t is int:
        if value == 0 or value == 1:
            return value == 1
        if value < 0:
            raise CastError(NEGATIVE_TO_UNSIGNED)
        raise CastError("Implicit casting to bool is not allowed")
    value = normalize(value)
    if value is EMPTY:
        raise CastError("Any::cast failed because it is empty")
    if type(value) in (int, float):
        return cast_bool(value)
    raise CastError(f"[Any::convert]: no known safe conversion between [{type_name(value)}] and [bool]")


def cast_double(value: Any) -> float:
    """``Any::cast<double>`` of any value (a string is parsed with from_chars)."""
    t = type(value)
    if t is float or t is int:
        return to_double(value)
    if value is EMPTY:
        raise CastError("Any::cast failed because it is empty")
    if t is str:
        parsed = from_chars_double(value)
        if parsed is None:
            raise CastError("Any failed string to number conversion")
        return parsed
    raise CastError(f"[Any::convert]: no known safe conversion between [{type_name(value)}] and [double]")


def cast_string(value: Any) -> str:
    """``Any::cast<std::string>``: integers in decimal, doubles like ``%f``."""
    t = type(value)
    if t is str:
        return value
    if t is int:
        return str(value)
    if t is float:
        return format_double(value)
    if value is EMPTY:
        raise CastError("Any::cast failed because it is empty")
    raise CastError(f"[Any::convert]: no known safe conversion between [{type_name(value)}] and [std::string]")


def string_to_double(text: str, enums: dict[str, int] | None) -> float:
    """BT.CPP ``StringToDouble``: 'true'/'false', then a scripting enum, then a numeric parse."""
    if text == "true":
        return 1.0
    if text == "false":
        return 0.0
    if enums and text in enums:
        return float(enums[text])
    parsed = from_chars_double(text)
    if parsed is None:
        raise CastError("Any failed string to number conversion")
    return parsed


def to_bool(value: Any) -> bool:
    """A script result as a condition (spec 6.5): ScriptCondition, pre-conditions, Precondition."""
    return cast_bool(value)
