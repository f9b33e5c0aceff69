"""Seeded random trees that lean on the script language and on port remapping.

``test_random_trees.py`` composes every control and decorator over two int counters; this
family instead stresses what a hand-written case rarely combines: scripts over mixed-type
entries (int, double, string, numeric string, NodeStatus names), compound assignments that
change or keep an entry's type, every pre/post-condition attribute with such expressions,
SubTrees remapped explicitly, with ``_autoremap``, with ``{=}`` and with string literals,
SetBlackboard through remapped ports, Switch on string entries, Parallel thresholds, and
decorators over asynchronous (stateful) children, with halts between ticks.

``make_case(seed)`` is a pure function of the seed (``random.Random``), so a failing seed is
a reproducible test. Constructs where BT.CPP 4.8.2 (the oracle) and 4.10 (our reference)
differ are left out: unparenthesised ``+ - * /`` chains, ``true``/``false``, numeric literals
as SubTree ports, the bitwise operators (``~`` of NaN wraps to 2^63 and only 4.8.2 casts that
back), decimals compared by Switch against integers (4.8.2 accepts trailing junk), strings
that only the wheel's ``std::stod`` parses (leading ``+``, spaces, hex), a RUNNING child under
SkipUnlessUpdated when it is halted, and a Repeat count a script can set to -1 (endless).
"""

from __future__ import annotations

import random

from .harness import Case, tree

STATUSES = ["SUCCESS", "FAILURE", "RUNNING"]

# Root entries written by the host before the first tick (and between ticks).
SETUP = {"h": 0, "i": 1, "d": 0.5, "s": "abc", "n": "5", "c": 0, "sw": "abc", "b": True}  # h first: always set
KEYS = {"i": "int", "d": "double", "s": "string", "n": "string", "c": "int", "sw": "string",
        "w": "string", "p": "string", "b": "int", "h": "int"}

_NUM_LITERALS = ["0", "1", "2", "3", "0.5", "2.0", "1e1", "0x10", "(0 - 1)", "(1/0)", "(0/0)"]
_STR_LITERALS = ["'abc'", "'5'", "'2.5'", "''", "'x'", "'1'", "'SUCCESS'"]
_ENUMS = ["SUCCESS", "FAILURE", "RUNNING", "IDLE", "SKIPPED"]
_ARITH = ["+", "-", "*", "/"]
_CMP = ["==", "!=", "&lt;", "&gt;", "&lt;=", "&gt;="]
_LOGIC = ["&amp;&amp;", "||"]


class _Gen:
    def __init__(self, seed: int):
        self.r = random.Random(seed)
        self.n = 0
        self.scripts: dict[str, dict[str, str]] = {}
        self.subtrees: dict[str, str] = {}

    def name(self) -> str:
        self.n += 1
        return f"n{self.n}"

    # -- script text ---------------------------------------------------------------------------
    # A scope maps each visible entry to the kind of value it holds ("num" or "str"), so most
    # expressions are well typed and a tree runs for several ticks; one in ten is drawn over
    # any kinds, which exercises the conversion and error rules.
    def var(self, scope: dict[str, str], kind: str | None = None) -> str:
        names = [k for k, v in scope.items() if v == kind or (kind is None and v in ("num", "str"))]
        return self.r.choice(names or [k for k, v in scope.items() if v in ("num", "str")])

    def expr(self, scope: dict[str, str], depth: int, kind: str | None = None) -> str:
        r = self.r
        if kind is None:
            kind = r.choice(["num", "num", "str"])
        loose = r.random() < 0.1
        k = r.random()
        if depth <= 0 or k < 0.35:
            if r.random() < 0.5:
                return self.var(scope, None if loose else kind)
            if loose:
                return r.choice(_NUM_LITERALS + _STR_LITERALS + _ENUMS)
            return r.choice(_NUM_LITERALS if kind == "num" else _STR_LITERALS)
        if kind == "str":
            if k < 0.5:
                return f"({self.expr(scope, depth - 1)}) ? ({self.expr(scope, depth - 1, 'str')}) : " \
                       f"({self.expr(scope, depth - 1, 'str')})"
            other = None if loose else r.choice(["num", "str", "str"])
            return f"({self.expr(scope, depth - 1, 'str')}) .. ({self.expr(scope, depth - 1, other)})"
        if k < 0.45:
            return f"{r.choice(['-', '!'])}({self.expr(scope, depth - 1, 'num')})"
        if k < 0.52:
            return f"({self.expr(scope, depth - 1)}) ? ({self.expr(scope, depth - 1, 'num')}) : " \
                   f"({self.expr(scope, depth - 1, 'num')})"
        if k < 0.75:  # comparisons, some between a number and a numeric string
            side = None if loose else r.choice(["num", "num", "str"])
            a = self.expr(scope, depth - 1, side)
            if side is None or r.random() < 0.75:
                b = self.expr(scope, depth - 1, side)
            else:
                b = r.choice(["'5'", "'2.5'", "'0'"] if side == "num" else ["5", "2.5", "0"])
            return f"({a}) {r.choice(_CMP)} ({b})"
        sub = None if loose else "num"
        op = r.choice(_ARITH * 3 + _LOGIC)
        return f"({self.expr(scope, depth - 1, sub)}) {op} ({self.expr(scope, depth - 1, sub)})"

    def statement(self, scope: dict[str, str]) -> str:
        r = self.r
        if r.random() < 0.1:  # new entries: a private one and one visible from the root
            target, kind = r.choice(["w", "_t"]), "str" if r.random() < 0.5 else "num"
            op = ":="
        else:
            target = self.var(scope)
            kind = scope[target]
            op = r.choice([":=", ":=", ":=", "="] + (["+=", "-=", "*=", "/="] if kind == "num" else ["+="]))
        if r.random() < 0.1:
            kind = None
        return f"{target} {op} {self.expr(scope, 2, kind)}"

    def script(self, scope: dict[str, str]) -> str:
        return "; ".join(self.statement(scope) for _ in range(self.r.randint(1, 2)))

    def conditions(self, scope: dict[str, str]) -> str:
        r = self.r
        attrs = []
        if r.random() < 0.2:
            which = r.choice(["_skipIf", "_successIf", "_failureIf", "_while"])
            attrs.append(f'{which}="{self.expr(scope, 2, "num")}"')
        if r.random() < 0.15:
            which = r.choice(["_onSuccess", "_onFailure", "_post", "_onHalted"])
            if which != "_onHalted":
                attrs.append(f'{which}="{self.script(scope)}"')
            elif "h" in scope:
                # a script that cannot throw: BT.CPP's Tree destructor runs _onHalted (even after a
                # failed build), and an exception there aborts the process
                attrs.append(f'_onHalted="h := {r.randint(1, 99)}"')
        return (" " + " ".join(attrs)) if attrs else ""

    # -- nodes ---------------------------------------------------------------------------------
    def leaf(self, scope: dict[str, str], depth: int) -> str:
        r = self.r
        cond = self.conditions(scope)
        name = self.name()
        kind = r.choice(["C", "A", "R", "R", "Script", "Script", "ScriptCondition", "SubTree", "SubTree",
                         "SetBlackboard", "Ok", "Fail", "Unset", "Updated"])
        if kind == "Unset":  # removes a local entry only; a remapped key is left alone
            return f'<UnsetBlackboard name="{name}" key="{r.choice([self.var(scope), "k", "_t", "w"])}"{cond}/>'
        if kind == "Updated":
            entry = self.var(scope)
            return f'<WasEntryUpdated name="{name}" entry="{r.choice([entry, "{" + entry + "}"])}"{cond}/>'
        if kind == "SubTree" and depth < 3:
            return self.subtree(scope, depth, name, cond)
        if kind in ("Script", "SubTree"):
            return f'<Script name="{name}" code="{self.script(scope)}"{cond}/>'
        if kind == "ScriptCondition":
            return f'<ScriptCondition name="{name}" code="{self.expr(scope, 2, "num")}"{cond}/>'
        if kind == "SetBlackboard":
            target = self.var(scope)
            value = "{" + self.var(scope, scope[target]) + "}" if r.random() < 0.6 else r.choice(["7", "abc", "2.5"])
            return f'<SetBlackboard name="{name}" output_key="{target}" value="{value}"{cond}/>'
        if kind in ("C", "A", "R"):
            allowed = STATUSES if kind != "A" else ["SUCCESS", "FAILURE"]
            self.scripts[name] = [r.choice(allowed) for _ in range(r.randint(1, 5))]
        return f'<{kind} name="{name}"{cond}/>'

    def subtree(self, scope: dict[str, str], depth: int, name: str, cond: str) -> str:
        r = self.r
        sub_id = f"Sub{len(self.subtrees)}"
        self.subtrees[sub_id] = ""  # reserve the ID before drawing the body (nested subtrees)
        style = r.choice(["explicit", "explicit", "autoremap", "equals", "literal"])
        remap_sw = ""
        if style == "autoremap":
            inner = dict(scope)
            remap = ' _autoremap="true"'
        else:
            # the subtree sees two ports, p and q, and its own private entry k
            q_src = self.var(scope)
            inner = {"p": "str", "q": scope[q_src], "k": "num", "h": "h"}
            if "sw" in scope and r.random() < 0.3:  # a port the Switch nodes inside may read
                remap_sw = ' t="{sw}"'
                inner["t"] = "sw"
            if style == "equals" and "p" in scope:
                remap = f' p="{{=}}" q="{{{q_src}}}"'
                inner["p"] = scope["p"]
            elif style == "literal":
                remap = f' p="{r.choice(["abc", "x", "SUCCESS"])}" q="{{{q_src}}}"'
            else:
                p_src = self.var(scope)
                remap = f' p="{{{p_src}}}" q="{{{q_src}}}"'
                inner["p"] = scope[p_src]
        self.subtrees[sub_id] = self.node(inner, depth + 1)
        remap_h = ' h="{h}"' if style != "autoremap" else ""
        return f'<SubTree ID="{sub_id}" name="{name}"{remap}{remap_sw}{remap_h}{cond}/>'

    def node(self, scope: dict[str, str], depth: int) -> str:
        r = self.r
        kind = "leaf" if depth >= 4 else r.choice(["leaf"] * 4 + ["control"] * 3 + ["decorator"] * 2)
        if kind == "leaf":
            return self.leaf(scope, depth)
        cond = self.conditions(scope)

        def kids(lo: int, hi: int) -> str:
            return "".join(self.node(scope, depth + 1) for _ in range(r.randint(lo, hi)))

        if kind == "control":
            ctl = r.choice(["Sequence", "Fallback", "SequenceWithMemory", "ReactiveSequence", "ReactiveFallback",
                            "AsyncSequence", "Parallel", "ParallelAll", "IfThenElse", "WhileDoElse", "Switch3"])
            if ctl == "Parallel":
                count = r.randint(1, 3)
                s, f = r.randint(-count - 1, count), r.randint(-count - 1, count)
                body = "".join(self.node(scope, depth + 1) for _ in range(count))
                return f'<Parallel success_count="{s}" failure_count="{f}"{cond}>{body}</Parallel>'
            if ctl == "ParallelAll":
                count = r.randint(1, 3)
                body = "".join(self.node(scope, depth + 1) for _ in range(count))
                return f'<ParallelAll max_failures="{r.randint(-count, count)}"{cond}>{body}</ParallelAll>'
            if ctl in ("IfThenElse", "WhileDoElse"):
                return f"<{ctl}{cond}>{kids(2, 3)}</{ctl}>"
            if ctl == "Switch3":
                # only host-written entries: 4.8.2 matches "5abc" with case "5" (trailing junk)
                switched = [k for k, v in scope.items() if v == "sw"]
                var = "{" + r.choice(switched) + "}" if switched else r.choice(["abc", "5", "x"])
                cases = " ".join(f'case_{j}="{r.choice(["abc", "5", "1", "SUCCESS", "RUNNING", "", "x"])}"'
                                 for j in (1, 2, 3))
                return f'<Switch3 variable="{var}" {cases}{cond}>{kids(4, 4)}</Switch3>'
            return f"<{ctl}{cond}>{kids(1, 3)}</{ctl}>"

        dec = r.choice(["Inverter", "ForceSuccess", "ForceFailure", "KeepRunningUntilFailure", "Repeat",
                        "RetryUntilSuccessful", "RunOnce", "Precondition", "Loop", "SkipUnlessUpdated"])
        child = self.node(scope, depth + 1)
        if dec == "Loop":  # an output port written through whatever the scope remaps
            kind, items = r.choice([("Int", ["1", "2", "-3"]), ("Double", ["0.5", "2", "1e1"]),
                                    ("String", ["a", "5", "x y"])])
            queue = ";".join(r.sample(items, r.randint(0, 3)))
            return f'<Loop{kind} queue="{queue}" value="{{{self.var(scope)}}}"{cond}>{child}</Loop{kind}>'
        if dec == "SkipUnlessUpdated":
            # a synchronous child only: 4.8.2's halt() leaves a RUNNING child running (4.10 halts it)
            entry = self.var(scope)
            child = f'<Script name="{self.name()}" code="{self.script(scope)}"/>'
            return (f'<SkipUnlessUpdated entry="{r.choice([entry, "{" + entry + "}"])}"{cond}>{child}'
                    "</SkipUnlessUpdated>")
        if dec == "Repeat":
            cycles = r.choice(["-2", "0", "1", "2"])  # not {c}: a script can make it -1 (endless)
            return f'<Repeat num_cycles="{cycles}"{cond}>{child}</Repeat>'
        if dec == "RetryUntilSuccessful":
            return f'<RetryUntilSuccessful num_attempts="{r.randint(0, 3)}"{cond}>{child}</RetryUntilSuccessful>'
        if dec == "RunOnce":
            return f'<RunOnce then_skip="{r.choice(["true", "false"])}"{cond}>{child}</RunOnce>'
        if dec == "Precondition":
            els = r.choice(["SUCCESS", "FAILURE", "RUNNING", "SKIPPED"])
            return f'<Precondition if="{self.expr(scope, 2)}" else="{els}"{cond}>{child}</Precondition>'
        return f"<{dec}{cond}>{child}</{dec}>"


def make_case(seed: int) -> Case:
    """The random differential case of this seed (a pure function of it)."""
    g = _Gen(seed)
    r = g.r
    kinds = {k: "str" if isinstance(v, str) else "num" for k, v in SETUP.items()}
    kinds["sw"] = "sw"  # read by Switch only, written by the host only
    kinds["h"] = "h"  # which _onHalted ran last
    body = g.node(kinds, 0)
    extra = "".join(f'<BehaviorTree ID="{k}">{v}</BehaviorTree>' for k, v in g.subtrees.items())
    ticks = r.randint(1, 7)
    modes = [r.choice(["exactly_once", "once"]) for _ in range(ticks)]
    halts = sorted(r.sample(range(ticks), k=min(ticks, r.choice([0, 0, 1, 2]))))
    between = {}
    for step in r.sample(range(ticks), k=min(ticks, r.randint(0, 2))):
        between[step] = {"c": r.randint(0, 3), "sw": r.choice(["abc", "5", "x"])}
        if r.random() < 0.3:  # a host write of another kind: converted, or refused, by set()
            key, value = r.choice([("i", "7"), ("i", 2.0), ("i", 2.5), ("d", 3), ("d", "1.5"), ("s", 5),
                                   ("n", 2.5), ("b", 0), ("b", "1"), ("c", True)])
            between[step][key] = value
    return Case(f"scripted-{seed}", tree(body, extra), scripts=g.scripts, ticks=ticks, mode=modes,
                halt_after=halts, setup=dict(SETUP), between=between, keys=dict(KEYS))
