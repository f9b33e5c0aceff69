"""Generated trees for bench/tick.py: the shapes real trees have, at any size.

Every shape is one unit repeated under a root Sequence until the tree has about ``n`` nodes
(SubTree instances count their own nodes, as BT.CPP counts them). Leaves that are not
built-ins are the Python callbacks ``Ok`` (SUCCESS), ``No`` (FAILURE) and ``Run``
(stateful, RUNNING), registered alike in every engine. Blackboard values that scripts read
are preset (doubles) so the first tick already runs the scripts in full.

  leaves     Python-callback leaves only: Fallback(No, Sequence(Ok, Ok))
  builtin    the same with AlwaysFailure / AlwaysSuccess
  scripts    Script increments and ScriptCondition tests on the blackboard
  precond    leaves carrying _skipIf/_successIf/_failureIf/_while/_post/_onSuccess
  bbheavy    SubTrees three levels deep with remapped ports, a script on every level
  mixed      every control kind that completes in one tick (SequenceWithMemory does not: it
             yields RUNNING between children), decorators, scripts, pre/post conditions,
             3-level SubTrees

Each shape also comes ``-named`` (``mixed-named``): every element gets a unique
``name="..."`` as Groot2 writes it, so no two elements have the same text (the generated
shapes repeat identical elements, which a per-distinct-element cache would favour).
"""

from __future__ import annotations

import itertools
import re
from dataclasses import dataclass, field

ROOT = '<root BTCPP_format="4" main_tree_to_execute="Main">{trees}</root>'


@dataclass(slots=True)
class GeneratedTree:
    shape: str
    xml: str
    nodes: int
    preset: dict[str, float | str] = field(default_factory=dict)


def _main(body: str, extra: str = "") -> str:
    return ROOT.format(trees=f'<BehaviorTree ID="Main"><Sequence>{body}</Sequence></BehaviorTree>{extra}')


def _units(n: int, per_unit: int) -> int:
    return max(1, round((n - 1) / per_unit))


def leaves(n: int) -> GeneratedTree:
    k = _units(n, 5)
    unit = '<Fallback><No/><Sequence><Ok/><Ok/></Sequence></Fallback>'
    return GeneratedTree("leaves", _main(unit * k), 1 + 5 * k)


def builtin(n: int) -> GeneratedTree:
    k = _units(n, 5)
    unit = '<Fallback><AlwaysFailure/><Sequence><AlwaysSuccess/><AlwaysSuccess/></Sequence></Fallback>'
    return GeneratedTree("builtin", _main(unit * k), 1 + 5 * k)


def scripts(n: int) -> GeneratedTree:
    k = _units(n, 4)
    body = "".join(f'<Sequence><Script code="x{i} := x{i} + 1"/><ScriptCondition code="x{i} &gt; 0"/>'
                   f'<Script code="y := x{i} * 2"/></Sequence>' for i in range(k))
    preset = {f"x{i}": 0.0 for i in range(k)} | {"y": 0.0}
    return GeneratedTree("scripts", _main(body), 1 + 4 * k, preset)


def precond(n: int) -> GeneratedTree:
    k = _units(n, 5)
    unit = ('<Sequence><Ok _skipIf="skip" _post="count += 1"/><Ok _successIf="done"/>'
            '<Ok _failureIf="skip" _onSuccess="last := 1"/><Ok _while="!skip"/></Sequence>')
    return GeneratedTree("precond", _main(unit * k), 1 + 5 * k,
                         {"skip": 0.0, "done": 0.0, "count": 0.0, "last": 0.0})


_LEVELS = (
    '<BehaviorTree ID="L3"><Sequence><Script code="c := c + 1"/><ScriptCondition code="c &gt; 0"/>'
    '</Sequence></BehaviorTree>'
    '<BehaviorTree ID="L2"><Sequence><Script code="b := b + 1"/><SubTree ID="L3" c="{b}"/>'
    '</Sequence></BehaviorTree>'
    '<BehaviorTree ID="L1"><Sequence><Script code="a := a + 1"/><SubTree ID="L2" b="{a}"/>'
    '</Sequence></BehaviorTree>'
)
_PER_L1 = 10  # SubTree(L1) + 3 x (Sequence, Script) + SubTree(L2) + SubTree(L3) + ScriptCondition


def bbheavy(n: int) -> GeneratedTree:
    k = _units(n, _PER_L1)
    body = "".join(f'<SubTree ID="L1" a="{{v{i}}}"/>' for i in range(k))
    return GeneratedTree("bbheavy", _main(body, _LEVELS), 1 + _PER_L1 * k, {f"v{i}": 0.0 for i in range(k)})


def _mixed_unit(i: int) -> tuple[str, int]:
    """One unit touching every control kind and decorator that finishes within a tick."""
    parts = [
        ('<ReactiveSequence><Ok/><Inverter><No/></Inverter></ReactiveSequence>', 4),
        ('<ReactiveFallback><No/><ForceSuccess><No/></ForceSuccess></ReactiveFallback>', 4),
        ('<Parallel success_count="2" failure_count="1"><Ok/><Ok/></Parallel>', 3),
        ('<ParallelAll max_failures="1"><Ok/><AlwaysSuccess/></ParallelAll>', 3),
        ('<IfThenElse><ScriptCondition code="m &gt;= 0"/><Ok/><No/></IfThenElse>', 4),
        ('<WhileDoElse><No/><Ok/><Ok/></WhileDoElse>', 4),
        ('<Switch2 variable="{mode}" case_1="1" case_2="2"><Ok/><Ok/><Ok/></Switch2>', 4),
        ('<Fallback><ForceFailure><Ok/></ForceFailure><Repeat num_cycles="1"><Ok/></Repeat></Fallback>', 5),
        ('<RetryUntilSuccessful num_attempts="1"><Ok/></RetryUntilSuccessful>', 2),
        (f'<Script code="m := m + 1; w{i} := m"/>', 1),
        ('<Ok _skipIf="skip" _post="count += 1"/>', 1),
        (f'<SubTree ID="L1" a="{{v{i}}}"/>', _PER_L1),
    ]
    return "<Sequence>" + "".join(p for p, _ in parts) + "</Sequence>", 1 + sum(c for _, c in parts)


def mixed(n: int) -> GeneratedTree:
    per = _mixed_unit(0)[1]
    k = _units(n, per)
    body = "".join(_mixed_unit(i)[0] for i in range(k))
    preset = {"m": 0.0, "mode": "1", "skip": 0.0, "count": 0.0} | {f"v{i}": 0.0 for i in range(k)}
    return GeneratedTree("mixed", _main(body, _LEVELS), 1 + per * k, preset)


_NODE_TAG = re.compile(r"<(?![/!?]|root\b|BehaviorTree\b)(\w+)")


def named(g: GeneratedTree) -> GeneratedTree:
    """The same tree with a unique ``name`` on every node element (SubTree definitions are
    named once: their instances repeat them, as in a real document)."""
    count = itertools.count()
    xml = _NODE_TAG.sub(lambda m: f'<{m[1]} name="{m[1]}_{next(count)}"', g.xml)
    return GeneratedTree(f"{g.shape}-named", xml, g.nodes, g.preset)


_PLAIN = {"leaves": leaves, "builtin": builtin, "scripts": scripts, "precond": precond,
          "bbheavy": bbheavy, "mixed": mixed}
SHAPES = _PLAIN | {f"{k}-named": (lambda n, make=make: named(make(n))) for k, make in _PLAIN.items()}
