"""Random trees of built-in nodes and scripted leaves, run in bt_runtime and in BT.CPP 4.8.2.

Hypothesis (derandomized, so the run is reproducible) composes controls, decorators, leaves
and pre/post-condition scripts, picks per-step tick modes, blackboard writes and halts, and
both engines must produce the same trace (see ``harness.py``). Time-based nodes, TryCatch,
blackboard loop queues and everything else where 4.8.2 and 4.10 differ are left out.
"""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from .harness import Case, run_oracle, run_ours, tree

pytest.importorskip("behaviortreepy", exc_type=ImportError)
pytestmark = pytest.mark.oracle

STATUSES = ["SUCCESS", "FAILURE", "RUNNING"]


class _Names:
    def __init__(self) -> None:
        self.n = 0

    def next(self) -> str:
        self.n += 1
        return f"n{self.n}"


@st.composite
def _conditions(draw) -> str:
    """Optional pre/post-condition attributes over the counters x (int) and y (int)."""
    attrs = []
    if draw(st.integers(0, 5)) == 0:
        which = draw(st.sampled_from(["_skipIf", "_successIf", "_failureIf", "_while"]))
        op = draw(st.sampled_from(["==", "!=", "&lt;", "&gt;="]))
        attrs.append(f'{which}="x {op} {draw(st.integers(0, 3))}"')
    if draw(st.integers(0, 6)) == 0:
        which = draw(st.sampled_from(["_onSuccess", "_onFailure", "_post", "_onHalted"]))
        attrs.append(f'{which}="y := y + {draw(st.integers(1, 9))}"')
    return (" " + " ".join(attrs)) if attrs else ""


@st.composite
def _node(draw, names: _Names, scripts: dict, depth: int, subtrees: dict) -> str:
    leaf_only = depth >= 4
    kind = draw(st.sampled_from(["leaf"] * 4 + ([] if leaf_only else ["control"] * 3 + ["decorator"] * 2)))
    cond = draw(_conditions())
    if kind == "leaf":
        leaf = draw(st.sampled_from(["C", "A", "R", "R", "Ok", "Fail", "Script", "ScriptCondition", "SubTree",
                                     "SetBlackboard", "WasEntryUpdated", "AlwaysSuccess"]))
        name = names.next()
        if leaf == "SubTree" and depth < 3:
            sub_id = f"Sub{len(subtrees)}"
            subtrees[sub_id] = ""  # reserve the ID before drawing the body (nested subtrees)
            subtrees[sub_id] = draw(_node(names, scripts, depth + 1, subtrees))
            remap = draw(st.sampled_from([' _autoremap="true"', ' x="{x}" y="{y}"', ' x="{x}" y="{y}" v="{v}"']))
            return f'<SubTree ID="{sub_id}" name="{name}"{remap}{cond}/>'
        if leaf in ("SubTree", "AlwaysSuccess"):
            return f'<AlwaysSuccess name="{name}"{cond}/>'
        if leaf == "SetBlackboard":
            return f'<SetBlackboard name="{name}" output_key="x" value="{draw(st.integers(0, 3))}"{cond}/>'
        if leaf == "WasEntryUpdated":
            return f'<WasEntryUpdated name="{name}" entry="x"{cond}/>'
        if leaf == "Script":
            return f'<Script name="{name}" code="x := x + 1"{cond}/>'
        if leaf == "ScriptCondition":
            return f'<ScriptCondition name="{name}" code="x &lt; {draw(st.integers(0, 4))}"{cond}/>'
        if leaf in ("C", "A", "R"):
            allowed = STATUSES if leaf != "A" else ["SUCCESS", "FAILURE"]
            scripts[name] = draw(st.lists(st.sampled_from(allowed), min_size=1, max_size=6))
        return f'<{leaf} name="{name}"{cond}/>'

    def kids(lo: int, hi: int) -> str:
        count = draw(st.integers(lo, hi))
        return "".join(draw(_node(names, scripts, depth + 1, subtrees)) for _ in range(count))

    if kind == "control":
        ctl = draw(st.sampled_from(["Sequence", "Fallback", "AsyncSequence", "AsyncFallback",
                                    "SequenceWithMemory", "ReactiveSequence", "ReactiveFallback",
                                    "Parallel", "ParallelAll", "IfThenElse", "WhileDoElse", "Switch2"]))
        if ctl == "Parallel":
            n = draw(st.integers(1, 3))
            s = draw(st.integers(-n - 1, n))
            f = draw(st.integers(-n - 1, n))
            body = "".join(draw(_node(names, scripts, depth + 1, subtrees)) for _ in range(n))
            return f'<Parallel success_count="{s}" failure_count="{f}"{cond}>{body}</Parallel>'
        if ctl == "ParallelAll":
            n = draw(st.integers(1, 3))
            m = draw(st.integers(-n, n))
            body = "".join(draw(_node(names, scripts, depth + 1, subtrees)) for _ in range(n))
            return f'<ParallelAll max_failures="{m}"{cond}>{body}</ParallelAll>'
        if ctl in ("IfThenElse", "WhileDoElse"):
            return f"<{ctl}{cond}>{kids(2, 3)}</{ctl}>"
        if ctl == "Switch2":
            var = draw(st.sampled_from(["{s}", "1", "2", "3"]))
            return (f'<Switch2 variable="{var}" case_1="1" case_2="2"{cond}>'
                    f"{kids(3, 3)}</Switch2>")
        return f"<{ctl}{cond}>{kids(1, 3)}</{ctl}>"

    dec = draw(st.sampled_from(["Inverter", "ForceSuccess", "ForceFailure", "KeepRunningUntilFailure",
                                "Repeat", "RetryUntilSuccessful", "RunOnce", "Precondition", "LoopInt",
                                "SkipUnlessUpdated"]))
    child = draw(_node(names, scripts, depth + 1, subtrees))
    if dec == "Repeat":
        return f'<Repeat num_cycles="{draw(st.sampled_from([-2, 0, 1, 2, 3]))}"{cond}>{child}</Repeat>'
    if dec == "RetryUntilSuccessful":
        return f'<RetryUntilSuccessful num_attempts="{draw(st.integers(0, 3))}"{cond}>{child}</RetryUntilSuccessful>'
    if dec == "RunOnce":
        return f'<RunOnce then_skip="{draw(st.sampled_from(["true", "false"]))}"{cond}>{child}</RunOnce>'
    if dec == "Precondition":
        els = draw(st.sampled_from(["SUCCESS", "FAILURE", "RUNNING", "SKIPPED"]))
        return f'<Precondition if="x &lt; {draw(st.integers(0, 3))}" else="{els}"{cond}>{child}</Precondition>'
    if dec == "SkipUnlessUpdated":
        return f'<SkipUnlessUpdated entry="{draw(st.sampled_from(["x", "{x}", "s"]))}"{cond}>{child}</SkipUnlessUpdated>'
    if dec == "LoopInt":
        queue = ";".join(str(v) for v in draw(st.lists(st.integers(0, 9), max_size=3)))
        return f'<LoopInt queue="{queue}" value="{{v}}"{cond}>{child}</LoopInt>'
    return f"<{dec}{cond}>{child}</{dec}>"


@st.composite
def cases(draw) -> Case:
    scripts: dict[str, list[str]] = {}
    subtrees: dict[str, str] = {}
    body = draw(_node(_Names(), scripts, 0, subtrees))
    extra = "".join(f'<BehaviorTree ID="{k}">{v}</BehaviorTree>' for k, v in subtrees.items())
    ticks = draw(st.integers(1, 8))
    modes = draw(st.lists(st.sampled_from(["exactly_once", "once"]), min_size=ticks, max_size=ticks))
    halts = draw(st.lists(st.integers(0, ticks - 1), max_size=2, unique=True))
    between = draw(st.dictionaries(st.integers(0, ticks - 1),
                                   st.fixed_dictionaries({"x": st.integers(0, 3),
                                                          "s": st.sampled_from(["1", "2", "2.0", "x"])}),
                                   max_size=3))
    return Case("random", tree(body, extra), scripts=scripts, ticks=ticks, mode=modes, halt_after=halts,
                setup={"y": 0, "x": 0, "s": "1"}, between=between,
                keys={"x": "int", "y": "int", "v": "int", "s": "string"})


@settings(max_examples=800, derandomize=True, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(cases())
def test_random_tree_same_as_btcpp(case: Case):
    ours = run_ours(case)
    oracle = run_oracle(case)
    diff = ours.first_difference(oracle)
    assert diff is None, f"{case.xml}\nscripts={case.scripts} modes={case.mode} halts={case.halt_after} " \
                         f"between={case.between}\n{diff}"
