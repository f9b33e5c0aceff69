"""Typed ports of the built-in nodes fed from the blackboard, against BT.CPP 4.8.2.

Every template reads one port from the entry ``k``; every value is written into ``k`` either
by the host (``Blackboard.set``: conversions into the entry's declared type) or by a script
(``k := value``: the stored kind is kept), then the tree is ticked. Both engines must succeed
or fail at the same step and call the same leaves, so this pins BT.CPP's conversion rules
between stored values and port types (string, int, unsigned, bool, NodeStatus, untyped).
"""

from __future__ import annotations

import pytest

from .harness import Case, run_oracle, run_ours, tree

pytest.importorskip("behaviortreepy", exc_type=ImportError)
pytestmark = pytest.mark.oracle

TEMPLATES = {
    "repeat": ('<Repeat num_cycles="{k}"><A name="a"/></Repeat>', 2),
    "retry": ('<RetryUntilSuccessful num_attempts="{k}"><Fail name="f"/></RetryUntilSuccessful>', 2),
    "parallel": ('<Parallel success_count="{k}"><A name="a"/><A name="b"/></Parallel>', 1),
    "parallel_all": ('<ParallelAll max_failures="{k}"><Fail name="f"/><A name="a"/></ParallelAll>', 1),
    "run_once": ('<Sequence><RunOnce then_skip="{k}"><A name="a"/></RunOnce><A name="b"/></Sequence>', 2),
    "precondition_else": ('<Precondition if="0" else="{k}"><A name="a"/></Precondition>', 1),
    "precondition_if": ('<Precondition if="{k}"><A name="a"/></Precondition>', 1),
    "switch": ('<Switch2 variable="{k}" case_1="1" case_2="abc"><A name="s1"/><A name="s2"/><A name="d"/>'
               "</Switch2>", 1),
    "sleep": ('<Sleep msec="{k}"/>', 1),
    "timeout": ('<Timeout msec="{k}"><A name="a"/></Timeout>', 1),
    "script_condition": ('<ScriptCondition code="{k}"/>', 1),
    "script": ('<Sequence><Script code="{k}"/><A name="a"/></Sequence>', 1),
    "loop_if_empty": ('<LoopInt queue="" if_empty="{k}"><A name="a"/></LoopInt>', 1),
    "unset": ('<Sequence><UnsetBlackboard key="{k}"/><A name="a"/></Sequence>', 1),
    "set_blackboard_value": ('<Sequence><SetBlackboard output_key="out" value="{k}"/><A name="a"/></Sequence>', 1),
    "set_blackboard_key": ('<Sequence><SetBlackboard output_key="{k}" value="7"/><A name="a"/></Sequence>', 1),
    "wait_value_update": ('<WaitValueUpdate entry="{k}"><A name="a"/></WaitValueUpdate>', 1),
}

# value as written by the host, and the same value as a script literal (None: no literal)
VALUES = [
    (0, "0"), (1, "1"), (2, "2"), (-1, "-1"), (3000000000, "3000000000"), (2.0, "2.0"), (2.5, "2.5"),
    (-1.0, "-1.0"), (0.0, "0.0"), (True, None), (False, None), ("2", "'2'"), ("2abc", "'2abc'"),
    ("2.7", "'2.7'"), ("abc", "'abc'"), ("", "''"), ("true", "'true'"), ("1", "'1'"), ("SUCCESS", "'SUCCESS'"),
    ("SKIPPED", "'SKIPPED'"), ("-1", "'-1'"), ("x := 1", None), ("x == 1", None), ("+2", "'+2'"), (" 2", "' 2'"),
]


# A script writing a negative or huge number into a BT::NodeStatus port makes BT.CPP build an
# out-of-range enum, which hangs it (nothing to compare with).
SKIP = {(t, v) for t in ("precondition_else", "loop_if_empty") for v in (-1, 3000000000, -1.0)}


def _cases() -> list[Case]:
    cases = []
    for name, (body, ticks) in TEMPLATES.items():
        for value, literal in VALUES:
            if (name, value) in SKIP and type(value) is not bool:
                continue
            label = f"{name}-{type(value).__name__}-{value!r}"
            if not (type(value) is int and abs(value) >= 2**31):  # behaviortreepy's set_int takes a C++ int
                cases.append(Case(f"host:{label}", tree(body), setup={"k": value}, ticks=ticks,
                                  mode="exactly_once", keys={"k": "string", "out": "string"}))
            if literal is not None:
                script_body = f'<Sequence><Script code="k := {literal}"/>{body}</Sequence>'
                cases.append(Case(f"script:{label}", tree(script_body), ticks=ticks, mode="exactly_once",
                                  keys={"k": "string", "out": "string"}))
    return cases


CASES = _cases()


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_port_value_same_as_btcpp(case: Case):
    diff = run_ours(case).first_difference(run_oracle(case))
    assert diff is None, diff
