"""PipelineSequence, RecoveryNode and RoundRobin with scripted children."""

from __future__ import annotations

from collections import defaultdict

import pytest

from bt_runtime.factory import BehaviorTreeFactory
from bt_runtime.node import ActionNodeBase
from bt_runtime.status import FAILURE, IDLE, RUNNING, SKIPPED, SUCCESS, NodeStatus
from nodes.nav2 import register_nav2_nodes


class Script:
    """What each scripted leaf returns, tick after tick (the last status repeats)."""

    def __init__(self):
        self.plans: dict[str, list[NodeStatus]] = {}
        self.ticks: dict[str, int] = defaultdict(int)
        self.halts: dict[str, int] = defaultdict(int)

    def set(self, **plans: str) -> None:
        table = {"S": SUCCESS, "F": FAILURE, "R": RUNNING, "K": SKIPPED}
        for name, plan in plans.items():
            self.plans[name] = [table[c] for c in plan]

    def next(self, name: str) -> NodeStatus:
        plan = self.plans[name]
        self.ticks[name] += 1
        return plan.pop(0) if len(plan) > 1 else plan[0]


class Scripted(ActionNodeBase):
    """A leaf ticked every time (like BT.CPP's ActionNodeBase): its script decides."""

    def __init__(self, name, config, script: Script):
        self.script = script
        super().__init__(name, config)

    def tick(self):
        return self.script.next(self.name)

    def halt(self):
        if self._status is RUNNING:
            self.script.halts[self.name] += 1
        self.reset_status()


def make(body: str, script: Script):
    factory = BehaviorTreeFactory()
    register_nav2_nodes(factory)
    factory.register_node_type(Scripted, "Scripted", script)
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="T">{body}</BehaviorTree></root>'
    return factory.create_tree_from_text(xml)


def node(tree, name):
    return next(n for n in tree.nodes() if n.name == name)


# -- PipelineSequence ----------------------------------------------------------------------------

def test_pipeline_reticks_earlier_children_while_a_later_one_runs():
    s = Script()
    s.set(a="S", b="SRRRS", c="RRRRRRS")
    tree = make('<PipelineSequence><Scripted name="a"/><Scripted name="b"/><Scripted name="c"/>'
                '</PipelineSequence>', s)
    assert tree.tick_exactly_once() is RUNNING  # a S, b S, c R
    assert s.ticks["a"] == 1 and s.ticks["b"] == 1 and s.ticks["c"] == 1
    for _ in range(3):  # b RUNNING is passed over: c keeps running, a and b keep being ticked
        assert tree.tick_exactly_once() is RUNNING
    assert s.ticks["a"] == 4 and s.ticks["b"] == 4 and s.ticks["c"] == 4
    statuses = []
    while (st := tree.tick_exactly_once()) is RUNNING:
        statuses.append(st)
    assert st is SUCCESS and s.ticks["c"] == 7
    assert all(n.status is IDLE for n in tree.nodes())


def test_pipeline_running_child_stops_the_sweep_until_reached():
    s = Script()
    s.set(a="RRS", b="S")
    tree = make('<PipelineSequence><Scripted name="a"/><Scripted name="b"/></PipelineSequence>', s)
    assert tree.tick_exactly_once() is RUNNING and s.ticks["b"] == 0
    assert tree.tick_exactly_once() is RUNNING and s.ticks["b"] == 0
    assert tree.tick_exactly_once() is SUCCESS and s.ticks["b"] == 1


def test_pipeline_failure_halts_the_running_children():
    s = Script()
    s.set(a="SSF", b="R")
    tree = make('<PipelineSequence><Scripted name="a"/><Scripted name="b"/></PipelineSequence>', s)
    assert tree.tick_exactly_once() is RUNNING
    assert tree.tick_exactly_once() is RUNNING
    assert tree.tick_exactly_once() is FAILURE
    assert s.halts["b"] == 1 and node(tree, "b").status is IDLE
    # the pipeline starts over: b's running index was reset
    s.set(a="S", b="S")
    assert tree.tick_exactly_once() is SUCCESS


def test_pipeline_all_skipped_is_skipped():
    s = Script()
    s.set(a="K", b="K")
    tree = make('<Sequence><PipelineSequence name="p"><Scripted name="a"/><Scripted name="b"/>'
                '</PipelineSequence><Scripted name="c"/></Sequence>', s)
    s.set(c="S")
    assert tree.tick_exactly_once() is SUCCESS
    assert s.ticks["c"] == 1  # the skipped pipeline did not stop the sequence


# -- RecoveryNode ----------------------------------------------------------------------------------

def test_recovery_node_retries_after_each_successful_recovery():
    s = Script()
    s.set(act="F", rec="S")
    tree = make('<RecoveryNode number_of_retries="3"><Scripted name="act"/><Scripted name="rec"/>'
                '</RecoveryNode>', s)
    assert tree.tick_exactly_once() is FAILURE  # all within one tick: act F, rec S x3, act F
    assert s.ticks["act"] == 4 and s.ticks["rec"] == 3


def test_recovery_node_running_children_and_success_resets_the_counter():
    s = Script()
    s.set(act="FRS", rec="RS")
    tree = make('<RecoveryNode number_of_retries="1"><Scripted name="act"/><Scripted name="rec"/>'
                '</RecoveryNode>', s)
    assert tree.tick_exactly_once() is RUNNING  # act F, rec R
    assert tree.tick_exactly_once() is RUNNING  # rec S (retry 1), act R
    assert tree.tick_exactly_once() is SUCCESS
    rn = node(tree, "RecoveryNode")
    assert rn.retry_count == 0 and rn.current_child_idx == 0
    s.set(act="FF", rec="S")  # a new activation gets all its retries again
    assert tree.tick_exactly_once() is FAILURE and s.ticks["rec"] == 3


def test_recovery_node_fails_when_the_recovery_fails_or_is_skipped():
    s = Script()
    s.set(act="F", rec="F")
    tree = make('<RecoveryNode number_of_retries="5"><Scripted name="act"/><Scripted name="rec"/>'
                '</RecoveryNode>', s)
    assert tree.tick_exactly_once() is FAILURE and s.ticks["act"] == 1
    s.set(rec="K")
    assert tree.tick_exactly_once() is FAILURE and s.ticks["act"] == 2


def test_recovery_node_halt_resets_retries_and_needs_two_children():
    s = Script()
    s.set(act="FR", rec="S")
    tree = make('<RecoveryNode number_of_retries="1"><Scripted name="act"/><Scripted name="rec"/>'
                '</RecoveryNode>', s)
    assert tree.tick_exactly_once() is RUNNING
    assert node(tree, "RecoveryNode").retry_count == 1
    tree.halt_tree()
    assert node(tree, "RecoveryNode").retry_count == 0 and s.halts["act"] == 1
    bad = make('<RecoveryNode><Scripted name="act"/></RecoveryNode>', s)
    with pytest.raises(Exception, match="must only have 2 children"):
        bad.tick_exactly_once()


# -- RoundRobin ----------------------------------------------------------------------------------

RR = ('<RoundRobin{attr}><Scripted name="a"/><Scripted name="b"/><Scripted name="c"/></RoundRobin>')


def test_round_robin_one_child_per_activation_and_wraps_around():
    s = Script()
    s.set(a="S", b="RS", c="S")
    tree = make(RR.format(attr=""), s)
    assert tree.tick_exactly_once() is SUCCESS and s.ticks["a"] == 1
    assert tree.tick_exactly_once() is RUNNING and s.ticks["b"] == 1
    assert tree.tick_exactly_once() is SUCCESS and s.ticks["b"] == 2
    assert tree.tick_exactly_once() is SUCCESS and s.ticks["c"] == 1
    assert tree.tick_exactly_once() is SUCCESS and s.ticks["a"] == 2  # Jazzy: wraps around


def test_round_robin_failed_child_gives_way_in_the_same_tick():
    s = Script()
    s.set(a="F", b="F", c="S")
    tree = make(RR.format(attr=""), s)
    assert tree.tick_exactly_once() is SUCCESS and s.ticks["c"] == 1
    s.set(c="F")
    assert tree.tick_exactly_once() is FAILURE  # a, b, c all failed in a row
    assert s.ticks["a"] == 2 and s.ticks["b"] == 2 and s.ticks["c"] == 2
    assert node(tree, "RoundRobin").current_child_idx == 0


def test_round_robin_wrap_around_false_is_nav2_main():
    s = Script()
    s.set(a="S", b="F", c="S")
    tree = make(RR.format(attr=' wrap_around="false"'), s)
    assert tree.tick_exactly_once() is SUCCESS  # a
    assert tree.tick_exactly_once() is FAILURE  # b fails, c is the last child: FAILURE even on success
    assert s.ticks["c"] == 1
    assert tree.tick_exactly_once() is SUCCESS and s.ticks["a"] == 2  # halted: starts over


def test_round_robin_index_survives_completion_but_not_halt():
    s = Script()
    s.set(a="S", b="R", c="S")
    tree = make(RR.format(attr=""), s)
    assert tree.tick_exactly_once() is SUCCESS
    assert tree.tick_exactly_once() is RUNNING  # b
    tree.halt_tree()
    assert s.halts["b"] == 1 and node(tree, "RoundRobin").current_child_idx == 0
    assert tree.tick_exactly_once() is SUCCESS and s.ticks["a"] == 2
