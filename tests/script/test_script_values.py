"""Value-layer rules the script engine relies on: from_chars parsing, Any casts, kinds.

Also pins two fixes made in the shared layer while writing the engine: ``parse_float``
reports ``from_chars``'s out-of-range results (``ports.py``) and a second ``@`` in a
created key is a ``LogicError`` (``blackboard.py``).
"""

from __future__ import annotations

import math

import pytest

from bt_runtime.errors import BTRuntimeError
from bt_runtime.ports import EMPTY, parse_float
from bt_runtime.script import CastError
from bt_runtime.script.values import (
    cast_bool,
    cast_double,
    cast_string,
    double_to_int64,
    from_chars_double,
    normalize,
    string_to_double,
    to_double,
    to_uint64,
    type_name,
)
from bt_runtime.status import NodeStatus


@pytest.mark.parametrize("text, expected", [
    ("12abc", 12.0), (".5", 0.5), ("5.", 5.0), ("-.5e-3x", -0.0005), ("1e", 1.0), ("1e+", 1.0),
    ("0x10", 0.0), ("1e-320", 1e-320), ("infinity", math.inf), ("-INF", -math.inf), ("infx", math.inf),
    ("-0", -0.0), ("0e-999", 0.0),
])
def test_from_chars_prefix_rules(text, expected):
    assert from_chars_double(text) == expected


@pytest.mark.parametrize("text", ["", " 5", "+5", "-", ".", "abc", "1e999", "-1e999", "1e-400", "x1"])
def test_from_chars_failures(text):
    assert from_chars_double(text) is None


def test_from_chars_nan_keeps_its_sign():
    assert math.isnan(from_chars_double("nan(123)"))
    assert math.copysign(1, from_chars_double("-nan")) == -1


def test_string_to_double_prefers_booleans_then_enums():
    assert string_to_double("true", None) == 1.0 and string_to_double("false", {}) == 0.0
    assert string_to_double("RED", {"RED": 4}) == 4.0
    with pytest.raises(CastError, match="Any failed string to number conversion"):
        string_to_double("RED", None)


def test_number_casts():
    assert to_double(2**53 - 1) == float(2**53 - 1)
    with pytest.raises(CastError, match="Loss of precision"):
        to_double(2**53)
    assert to_double(-(2**63)) == -(2.0**63)      # std::abs(INT64_MIN) wraps in C++
    assert double_to_int64(-(2.0**63)) == -(2**63)
    for bad in (2.0**63, 1.5, math.nan, math.inf):
        with pytest.raises(CastError, match="Invalid floating point to integer conversion"):
            double_to_int64(bad)
    with pytest.raises(CastError, match="Value is negative and can't be converted to unsigned"):
        to_uint64(-1)
    assert to_uint64(3.0) == 3


def test_other_casts():
    assert cast_bool(0) is False and cast_bool(1.5) is True
    assert cast_double("2.5") == 2.5
    assert cast_string(3) == "3" and cast_string(0.5) == "0.500000" and cast_string("s") == "s"
    with pytest.raises(CastError, match="Any::cast failed because it is empty"):
        cast_double(EMPTY)
    with pytest.raises(CastError, match=r"between \[std::vector<int.*\] and \[std::string\]"):
        cast_string([1])


def test_normalize_and_type_names():
    assert normalize(True) == 1 and type(normalize(True)) is int
    assert normalize(NodeStatus.FAILURE) == 3 and type(normalize(NodeStatus.FAILURE)) is int
    assert [type_name(v) for v in (1, 2**63, 1.0, "s", True)] == [
        "long", "unsigned long", "double", "std::string", "bool"]


@pytest.mark.parametrize("text, type_name_", [("1e999", "double"), ("-1e999", "double"),
                                              ("1e-400", "double"), ("1e39", "float"),
                                              ("1e-50", "float")])
def test_parse_float_out_of_range(text, type_name_):
    with pytest.raises(BTRuntimeError, match=rf"Can't convert string \[{text}\] to {type_name_}"):
        parse_float(text, type_name_)


def test_parse_float_in_range():
    assert parse_float("1e-320") == 1e-320
    assert parse_float("3.40282356e38", "float") == 3.40282356e38   # rounds to FLT_MAX
    assert parse_float("-inf") == -math.inf and math.isnan(parse_float("nan"))
    assert parse_float("0e-999") == 0.0


def test_second_at_in_a_created_key_is_a_logic_error():
    # BT.CPP 4.10 Blackboard::createEntry throws LogicError here (blackboard.py fix)
    from bt_runtime.blackboard import Blackboard
    from bt_runtime.errors import LogicError
    with pytest.raises(LogicError, match="Character '@' used multiple times in the key"):
        Blackboard().create_entry("@a@b")
