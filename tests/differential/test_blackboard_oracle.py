"""Blackboard set/get rules against BT.CPP 4.8.2: random sequences of typed writes, reads and
unsets on a root and a child blackboard must succeed or fail alike and read the same values."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bt_runtime import Blackboard

bt = pytest.importorskip("behaviortreepy", exc_type=ImportError)
pytestmark = pytest.mark.oracle

KEYS = ["a", "b", "c"]
VALUES = st.one_of(
    st.tuples(st.just("int"), st.sampled_from([0, 1, 2, -3, 100, 2**31 - 1])),
    st.tuples(st.just("double"), st.sampled_from([0.0, 1.0, 2.0, 2.5, -1.5, 1e10])),
    st.tuples(st.just("bool"), st.booleans()),
    st.tuples(st.just("string"), st.sampled_from(["", "0", "1", "42", "2.5", "abc", "true", "false", "-7", "3x"])),
)
OPS = st.one_of(
    st.tuples(st.just("set"), st.sampled_from(["root", "child"]), st.sampled_from(KEYS), VALUES),
    st.tuples(st.just("get"), st.sampled_from(["root", "child"]), st.sampled_from(KEYS),
              st.sampled_from(["int", "double", "bool", "string"])),
    st.tuples(st.just("unset"), st.sampled_from(["root", "child"]), st.sampled_from(KEYS), st.none()),
)
PY = {"int": int, "double": float, "bool": bool, "string": str}


def _ours(ops) -> list:
    root = Blackboard()
    child = Blackboard(root)
    boards = {"root": root, "child": child}
    out = []
    for op, where, key, arg in ops:
        bb = boards[where]
        try:
            if op == "set":
                bb.set(key, PY[arg[0]](arg[1]))
                out.append("ok")
            elif op == "get":
                value = bb.get(key, PY[arg])
                out.append(round(value, 6) if isinstance(value, float) else value)
            else:
                bb.unset(key)
                out.append("ok")
        except Exception:  # noqa: BLE001 - only "it failed" is compared
            out.append("error")
    return out


def _oracle(ops) -> list:
    root = bt.Blackboard.create()
    child = bt.Blackboard.create(root)
    boards = {"root": root, "child": child}
    out = []
    for op, where, key, arg in ops:
        bb = boards[where]
        try:
            if op == "set":
                getattr(bb, f"set_{arg[0]}")(key, PY[arg[0]](arg[1]))
                out.append("ok")
            elif op == "get":
                value = getattr(bb, f"get_{arg}")(key)
                out.append(round(value, 6) if isinstance(value, float) else value)
            else:
                bb.unset(key)
                out.append("ok")
        except Exception:  # noqa: BLE001
            out.append("error")
    return out


@settings(max_examples=500, derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(OPS, min_size=1, max_size=12))
def test_blackboard_rules_same_as_btcpp(ops):
    expected = _oracle(ops)  # (BT.CPP prints the entries to stdout on a type mismatch)
    assert _ours(ops) == expected, ops
