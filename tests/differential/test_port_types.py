"""Build-time port type checks against BT.CPP 4.8.2: two built-in ports of different declared
types share one blackboard entry (directly, through a SubTree remapping, through _autoremap or
through ``@``); both engines must agree on whether the tree can be built."""

from __future__ import annotations

import itertools

import pytest

from .harness import Case, run_oracle, run_ours, tree

pytest.importorskip("behaviortreepy", exc_type=ImportError)
pytestmark = pytest.mark.oracle

# one port of each declared type, as an element using entry KEY
PORTS = {
    "int": '<Repeat num_cycles="{KEY}"><AlwaysSuccess/></Repeat>',
    "unsigned": '<Timeout msec="{KEY}"><AlwaysSuccess/></Timeout>',
    "string": '<Switch2 variable="{KEY}" case_1="1" case_2="2"><AlwaysSuccess/><AlwaysSuccess/>'
              '<AlwaysSuccess/></Switch2>',
    "status": '<Precondition if="1" else="{KEY}"><AlwaysSuccess/></Precondition>',
    "bool": '<RunOnce then_skip="{KEY}"><AlwaysSuccess/></RunOnce>',
    "double_out": '<LoopDouble queue="1.5" value="{KEY}"><AlwaysSuccess/></LoopDouble>',
    "any": '<SetBlackboard output_key="dummy" value="{KEY}"/>',
    "entry": '<WasEntryUpdated entry="{KEY}"/>',
}

LINKS = {
    "same_tree": lambda a, b: tree(f"<Sequence>{a.replace('KEY', 'k')}{b.replace('KEY', 'k')}</Sequence>"),
    "remapped": lambda a, b: tree(f'<Sequence>{a.replace("KEY", "k")}<SubTree ID="S" inner="{{k}}"/></Sequence>',
                                  f'<BehaviorTree ID="S">{b.replace("KEY", "inner")}</BehaviorTree>'),
    "autoremap": lambda a, b: tree(f'<Sequence>{a.replace("KEY", "k")}<SubTree ID="S" _autoremap="true"/></Sequence>',
                                   f'<BehaviorTree ID="S">{b.replace("KEY", "k")}</BehaviorTree>'),
    "root_key": lambda a, b: tree(f'<Sequence>{a.replace("KEY", "k")}<SubTree ID="S"/></Sequence>',
                                  f'<BehaviorTree ID="S">{b.replace("KEY", "@k")}</BehaviorTree>'),
    "isolated": lambda a, b: tree(f'<Sequence>{a.replace("KEY", "k")}<SubTree ID="S"/></Sequence>',
                                  f'<BehaviorTree ID="S">{b.replace("KEY", "k")}</BehaviorTree>'),
}

CASES = [Case(f"{link}:{a}->{b}", build(PORTS[a], PORTS[b]), ticks=0)
         for link, build in LINKS.items() for a, b in itertools.product(PORTS, PORTS)]


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_build_time_type_check_same_as_btcpp(case: Case):
    ours, oracle = run_ours(case), run_oracle(case)
    assert ours.error_at == oracle.error_at, (ours.error, oracle.error)
