"""Differential cases modelled on the situations BT.CPP's own unit tests check
(``tests/gtest_*.cpp``, ``script_parser_test.cpp``), written for our harness: BT.CPP's test
nodes become the scripted leaves (``A``, ``R``, ``C``), and nodes that only print or copy a
port become ``SetBlackboard``/``Script`` writes that the trace reads back. Each case is named
``<gtest file>__<situation>``; the coverage map in ``docs/btcpp_differences.md`` points here.
The two engines are compared; no expected values are written down.
"""

from __future__ import annotations

from .harness import Case, tree

S, F, R_ = "SUCCESS", "FAILURE", "RUNNING"
CASES: list[Case] = []


def case(name: str, xml: str, **kw) -> None:
    CASES.append(Case(name, xml, **kw))


def sub(tree_id: str, body: str) -> str:
    return f'<BehaviorTree ID="{tree_id}">{body}</BehaviorTree>'


# -- gtest_preconditions ---------------------------------------------------------------------------
case("preconditions__decorator_on_ints_doubles_strings",
     tree('<Sequence><Script code="a:=1; b:=1; c:=3; x:=1.1; y:=(1.0+0.1); z:=\'hello\'; w:=\'world\'"/>'
          '<Precondition if="a==b" else="FAILURE"><A name="t1"/></Precondition>'
          '<Precondition if="a==c" else="SUCCESS"><A name="t2"/></Precondition>'
          '<Precondition if="x==y" else="FAILURE"><A name="t3"/></Precondition>'
          '<Precondition if=" z==w " else="SUCCESS"><A name="t4"/></Precondition>'
          '<Precondition if="a!=c" else="FAILURE"><A name="t5"/></Precondition></Sequence>'), ticks=2)
case("preconditions__decorator_checks_once_while_running",
     tree('<Sequence><Script code="a:=0"/><Precondition if=" a==0 " else="FAILURE">'
          '<R name="r" _while="b==0"/></Precondition></Sequence>'),
     scripts={"r": [R_, R_, R_, R_]}, setup={"b": 0}, between={2: {"a": 1}, 3: {"b": 1}},
     keys={"a": "int"}, ticks=5)
case("preconditions__decorator_in_repeat_runs_child_each_cycle",
     tree('<Sequence><Script code="a:=0; b:=0; c:=1"/><Repeat num_cycles="3"><Sequence>'
          '<Precondition if=" a==0 " else="SUCCESS"><A name="t"/></Precondition>'
          '<R name="k1" _while="c==0"/><R name="k2" _while="b==0"/></Sequence></Repeat></Sequence>'),
     scripts={"k2": [R_, R_, S]}, ticks=5)
case("preconditions__success_and_failure_if",
     tree('<Sequence><Script code="a:=1"/><A name="t1" _successIf="a==1"/><A name="t2" _successIf="a==2"/>'
          '<Fallback><A name="t3" _failureIf="a==1"/><A name="t4" _failureIf="a!=1"/></Fallback></Sequence>'),
     ticks=2)
case("preconditions__skip_chain_with_on_success_issue533",
     tree('<Sequence><A name="t1" _skipIf="v!=1"/><A name="t2" _skipIf="v!=2" _onSuccess="v=1"/>'
          '<A name="t3" _skipIf="v!=3" _onSuccess="v=2"/></Sequence>'),
     setup={"v": 3}, keys={"v": "int"}, ticks=4)
case("preconditions__skipped_async_action_is_never_started_issue585",
     tree('<Sequence><Script code="v:=1"/><R name="r" _skipIf="v==1"/></Sequence>'), ticks=2)
case("preconditions__no_skip_check_while_running_issue615",
     tree('<KeepRunningUntilFailure _skipIf="check == 1"><AlwaysSuccess/></KeepRunningUntilFailure>'),
     setup={"check": 0}, between={1: {"check": 1}}, ticks=3)
case("preconditions__skip_only_when_idle_issue615",
     tree('<R name="r" _skipIf="check==0"/>'), scripts={"r": [R_]},
     setup={"check": 0}, between={1: {"check": 1}, 2: {"check": 0}}, ticks=4)
case("preconditions__skip_if_through_nested_subtree_remapping",
     tree('<Sequence><Script code="param := 1; value := 1"/><SubTree ID="S1" param="{param}"/>'
          '<SubTree ID="S1" param="{value}"/><SubTree ID="S1" param="abc"/><A name="t"/></Sequence>',
          sub("S1", '<Sequence><SubTree ID="S2" _skipIf="param != 1"/></Sequence>') + sub("S2", '<A name="u"/>')),
     ticks=1, error="tick")
case("preconditions__while_false_halts_and_runs_on_halted",
     tree('<Sequence><R name="r" _while="a==1" _onHalted="b=69"/></Sequence>'),
     scripts={"r": [R_]}, setup={"a": 1, "b": 0}, between={1: {"a": 0}}, keys={"b": "int"}, ticks=3)
case("preconditions__skipped_single_child_sequence_toggles",
     tree('<Sequence><AlwaysSuccess _skipIf="skip"/></Sequence>'),
     setup={"skip": 1}, between={1: {"skip": 0}, 2: {"skip": 1}, 3: {"skip": 0}}, ticks=4)

# -- gtest_postconditions ----------------------------------------------------------------------------
case("postconditions__on_success_and_on_failure",
     tree('<Sequence><Script code="a:=1; b:=1; c:=1; d:=1"/><AlwaysSuccess _onSuccess="b=42"/>'
          '<ForceSuccess><AlwaysSuccess _failureIf="a!=0" _onFailure="c=42"/></ForceSuccess>'
          '<ForceSuccess><AlwaysFailure _onFailure="d=42"/></ForceSuccess></Sequence>'),
     keys={"b": "int", "c": "int", "d": "int"}, ticks=1)
case("postconditions__retry_runs_post_every_attempt_issue539",
     tree('<Sequence><Script code="x:=0; y:=0"/><RetryUntilSuccessful num_attempts="5">'
          '<AlwaysFailure _onFailure="x  += 1"  _post="y  += 1"/></RetryUntilSuccessful></Sequence>'),
     keys={"x": "int", "y": "int"}, mode="once", ticks=1)
case("postconditions__halted_by_parallel_runs_on_halted_not_post_issue601",
     tree('<Sequence><Script code="test := \'start\'"/><Parallel failure_count="1" success_count="-1">'
          '<R name="r" _onHalted="test = \'halted\'" _post="test = \'post\'"/><AlwaysFailure/></Parallel>'
          '</Sequence>'), keys={"test": "string"}, ticks=2)

# -- gtest_skipping ------------------------------------------------------------------------------
case("skipping__skip_beats_success_and_failure_if",
     tree('<Sequence><Script code="a:=1"/><A name="t1" _successIf="a==2" _failureIf="a!=1" _skipIf="a==1"/>'
          '<A name="t2"/></Sequence>'), ticks=1)
case("skipping__all_children_skipped",
     tree('<Sequence><A name="t1" _skipIf="a==1"/><A name="t2" _skipIf="a&lt;2"/><A name="t3" _skipIf="a&gt;0"/>'
          '</Sequence>'), setup={"a": 1}, ticks=2)
case("skipping__subtree_skipped_by_script_entry",
     tree('<Sequence><A name="t1"/><Script code=" data:=1 "/><SubTree ID="S" _skipIf="data"/></Sequence>',
          sub("S", '<A name="t2"/>')), ticks=1)
case("skipping__reactive_sequence_single_skipped_child",
     tree('<ReactiveSequence><AlwaysSuccess _skipIf="flag"/></ReactiveSequence>'),
     setup={"flag": True}, ticks=2)
case("skipping__reactive_sequence_with_async_child",
     tree('<ReactiveSequence><Script code=" value:=10 "/><A name="t" _skipIf="value &lt; 25"/>'
          '<R name="r"/></ReactiveSequence>'), scripts={"r": [R_, R_, S]}, ticks=6)
case("skipping__reactive_sequence_not_skipped",
     tree('<ReactiveSequence><Script code=" value:=50 "/><A name="t" _skipIf="value &lt; 25"/>'
          '<R name="r"/></ReactiveSequence>'), scripts={"r": [R_, R_, S]}, ticks=6)
case("skipping__while_false_skips_inside_sequence",
     tree('<Sequence><Script code=" doit:=0 "/><Sequence><A name="t" _while="doit"/></Sequence></Sequence>'),
     ticks=1)

# -- gtest_subtree --------------------------------------------------------------------------------
case("subtree__script_writes_through_remapped_port",
     tree('<Sequence><Script code="value:=0"/><SubTree ID="S" value="{value}"/></Sequence>',
          sub("S", '<Script code="value:=1"/>')), keys={"value": "int"}, ticks=1)
case("subtree__private_keys_are_not_autoremapped",
     tree('<Sequence><SubTree ID="S" _autoremap="true"/><SetBlackboard output_key="seen1" value="{public_value}"/>'
          '<SetBlackboard output_key="seen2" value="{_private_value}"/></Sequence>',
          sub("S", '<Sequence><SetBlackboard output_key="public_value" value="hello"/>'
                   '<SetBlackboard output_key="_private_value" value="world"/></Sequence>')),
     keys={"seen1": "string", "seen2": "string"}, ticks=1)  # the private copy fails: FAILURE
case("subtree__literal_and_autoremap_in_nested_subtrees_issue696",
     tree('<SubTree ID="S2" msg2="bar" out="{log}"/>',
          sub("S1", '<Sequence><Script code="out := out .. msg1 .. \',\'"/>'
                    '<Script code="out := out .. msg2 .. \';\'"/></Sequence>')
          + sub("S2", '<Sequence><SubTree ID="S1" msg1="foo1" _autoremap="true"/>'
                      '<SubTree ID="S1" msg1="foo2" _autoremap="true"/></Sequence>')),
     setup={"log": ""}, keys={"log": "string"}, ticks=1)
case("subtree__explicit_and_autoremap_of_the_same_key_issue592",
     tree('<Sequence><Script code="variable := \'test\'"/><Script code="var := \'test\'"/>'
          '<SubTree ID="S" _autoremap="false" variable="{var}"/><SubTree ID="S" _autoremap="true"/></Sequence>',
          sub("S", '<Sequence><A name="t" _skipIf="variable != \'test\'"/></Sequence>')), ticks=1)
case("subtree__set_blackboard_true_through_remapped_port_issue653",
     tree('<Sequence><SubTree ID="S" test="{test}"/><ScriptCondition code="test"/></Sequence>',
          sub("S", '<SetBlackboard output_key="test" value="true"/>')), ticks=1, error="tick")
case("subtree__sibling_subtrees_read_the_current_value_issue72",
     tree('<Sequence><Script code=" myParam := \'hello\' "/><SubTree ID="S" name="s1" param="{myParam}" out="{o1}"/>'
          '<Script code=" myParam = \'world\' "/><SubTree ID="S" name="s2" param="{myParam}" out="{o2}"/></Sequence>',
          sub("S", '<SetBlackboard output_key="out" value="{param}"/>')),
     keys={"o1": "string", "o2": "string"}, ticks=1)
case("subtree__copy_between_remapped_ports",
     tree('<Sequence><Script code=" thoughts := \'hello\' "/>'
          '<SubTree ID="S" in_arg="{thoughts}" out_arg="{greetings}"/>'
          '<ScriptCondition code="greetings == \'hello\'"/></Sequence>',
          sub("S", '<SetBlackboard output_key="out_arg" value="{in_arg}"/>')),
     keys={"greetings": "string"}, ticks=1, error="tick")
case("subtree__unremapped_input_port_fails",
     tree('<Sequence><Script code=" thoughts := \'hello\' "/><SubTree ID="S" out_arg="{greetings}"/>'
          '<ScriptCondition code="greetings == \'hello\'"/></Sequence>',
          sub("S", '<SetBlackboard output_key="out_arg" value="{in_arg}"/>')), ticks=1)  # FAILURE
case("subtree__autoremap_with_explicit_and_literal_ports",
     tree('<Sequence><Script code="myParam := \'Hello World\'; param3 := \'Auto remapped\'"/>'
          '<SubTree ID="S" _autoremap="1" param1="{myParam}" param2="Straight Talking"/></Sequence>',
          sub("S", '<Script code="out := param1 .. \'|\' .. param2 .. \'|\' .. param3"/>')),
     keys={"out": "string"}, ticks=1)
case("subtree__literal_then_remapped_then_autoremapped",
     tree('<Sequence><Script code="myParam := \'Hello\'"/><SubTree ID="S" name="a" param="{myParam}"/>'
          '<SubTree ID="S" name="b" param="World"/><Script code="param := \'Auto\'"/>'
          '<SubTree ID="S" name="c" _autoremap="1"/></Sequence>',
          sub("S", '<Script code="log := \'x\'"/>')), ticks=1)

# -- gtest_blackboard -------------------------------------------------------------------------------
case("blackboard__set_blackboard_then_script_compare_issue725",
     tree('<Sequence><SetBlackboard value="hello" output_key="my_port"/>'
          '<ScriptCondition code="my_port == \'hello\'"/><SetBlackboard value="42" output_key="num"/>'
          '<ScriptCondition code="num == 42"/></Sequence>'), keys={"my_port": "string", "num": "string"}, ticks=1)
case("blackboard__set_blackboard_into_remapped_port",
     tree('<Sequence><Script code="value := 0"/><SubTree ID="S" value="{value}"/>'
          '<ScriptCondition code="value == 42"/></Sequence>',
          sub("S", '<SetBlackboard output_key="value" value="42"/>')), keys={"value": "int"}, ticks=1, error="tick")
case("blackboard__set_blackboard_copies_into_typed_entry",
     tree('<Sequence><Script code="a := 1; b := 2.5"/><SetBlackboard output_key="a" value="{b}"/></Sequence>'),
     keys={"a": "double"}, ticks=1)
case("blackboard__whitespace_around_script_values_issue605",
     tree('<Sequence><Script code="  x := 5 ;  y := \'  text  \' "/><ScriptCondition code=" x == 5 "/></Sequence>'),
     keys={"x": "int", "y": "string"}, ticks=1)
case("blackboard__at_prefix_reaches_the_root_from_a_subtree",
     tree('<Sequence><Script code="@g := 1"/><SubTree ID="S"/><ScriptCondition code="g == 3"/></Sequence>',
          sub("S", '<Sequence><Script code="@g += 2"/><SetBlackboard output_key="@h" value="{@g}"/></Sequence>')),
     keys={"g": "int", "h": "int"}, ticks=1)

# -- gtest_updates ---------------------------------------------------------------------------------
case("updates__skip_unless_updated_sees_each_write",
     tree('<Sequence><SkipUnlessUpdated entry="v"><A name="t"/></SkipUnlessUpdated>'
          '<WasEntryUpdated entry="v"/></Sequence>'),
     between={1: {"v": 1}, 3: {"v": 2}, 4: {"v": 2}}, ticks=6)

# -- script_parser_test ---------------------------------------------------------------------------
case("script__compare_with_negative_number_issue832",
     tree('<Sequence><Script code="v := -1"/><ScriptCondition code="v &lt; -0.5"/>'
          '<ScriptCondition code="v == -1"/><ScriptCondition code="-1 &lt; v + 1"/></Sequence>'), ticks=1)
case("script__new_lines_separate_statements",
     tree('<Sequence><Script code="a := 1;&#10;b := 2;&#10;&#10;c := a + b"/></Sequence>'),
     keys={"c": "double"}, ticks=1)
case("script__ternary_on_strings_issue595",
     tree('<Sequence><Script code="v := 5; s := (v &gt; 3) ? \'big\' : \'small\'"/></Sequence>'),
     keys={"s": "string"}, ticks=1)
case("script__uninitialized_entry_comparison",
     tree('<Sequence><SetBlackboard output_key="x" value="{nope}"/><ScriptCondition code="x == 1"/></Sequence>'),
     ticks=1)

# -- gtest_parallel ---------------------------------------------------------------------------------
case("parallel__skipped_child_counts_neither_way_issue593",
     tree('<Sequence><Script code="test := 1"/><Parallel failure_count="1" success_count="-1">'
          '<A name="t" _skipIf="test == 1"/><R name="r"/></Parallel></Sequence>'), scripts={"r": [R_, R_, S]}, ticks=4)
case("parallel__retry_paused_by_while_is_halted_and_runs_on_halted",
     tree('<Parallel><Sequence><R name="r1"/><Script code="paused := 0"/><R name="r2"/></Sequence>'
          '<Sequence><Script code="paused := 1; done := 0"/>'
          '<RetryUntilSuccessful _while="paused" num_attempts="-1" _onHalted="done = 1"><R name="f"/>'
          '</RetryUntilSuccessful></Sequence></Parallel>'),
     scripts={"r1": [R_, R_, S], "r2": [R_, R_, S], "f": [R_, F]}, keys={"done": "int", "paused": "int"}, ticks=7)
case("parallel__sequences_are_not_reticked_issue819",
     tree('<Parallel success_count="2" failure_count="1"><Sequence><C name="c1"/><R name="r1"/></Sequence>'
          '<Sequence><C name="c2"/><R name="r2"/></Sequence></Parallel>'),
     scripts={"r1": [R_, R_, R_, S], "r2": [R_, R_, S]}, ticks=5)
case("parallel__reactive_sequences_are_reticked_issue819",
     tree('<Parallel success_count="2" failure_count="1"><ReactiveSequence><C name="c1"/><R name="r1"/>'
          '</ReactiveSequence><ReactiveSequence><C name="c2"/><R name="r2"/></ReactiveSequence></Parallel>'),
     scripts={"r1": [R_, R_, R_, S], "r2": [R_, R_, S], "c2": [S, S, F, S]}, ticks=5)

# -- gtest_reactive ---------------------------------------------------------------------------------
case("reactive__sequence_then_async_sequence_children",
     tree('<ReactiveSequence><Sequence name="first"><A name="a"/><A name="b"/><A name="c"/></Sequence>'
          '<AsyncSequence name="second"><A name="d"/><A name="e"/><A name="f"/></AsyncSequence></ReactiveSequence>'),
     ticks=5)
case("reactive__skip_if_set_by_on_success_issue587",
     tree('<Sequence><Script code="test := 0"/><ReactiveSequence>'
          '<RetryUntilSuccessful name="retry1" num_attempts="-1" _skipIf="test "><A name="a" _onSuccess="test = 1"/>'
          '</RetryUntilSuccessful><RetryUntilSuccessful name="retry2" num_attempts="5"><AlwaysFailure/>'
          '</RetryUntilSuccessful></ReactiveSequence></Sequence>'), keys={"test": "int"}, mode="once", ticks=2)
case("reactive__fallback_second_child_succeeds_after_running",
     tree('<ReactiveFallback><C name="c"/><R name="r"/></ReactiveFallback>'),
     scripts={"c": [F, F, S, F], "r": [R_, R_, R_, S]}, ticks=5)

# -- gtest_decorator -----------------------------------------------------------------------------
case("decorator__run_once_with_post_conditions",
     tree('<Sequence><RunOnce then_skip="false"><A name="a" _onSuccess="n += 1"/></RunOnce>'
          '<RunOnce><Fail name="f" _onFailure="m := 1"/></RunOnce></Sequence>'),
     setup={"n": 0}, keys={"n": "int", "m": "int"}, ticks=3)
case("decorator__repeat_async_child_with_post",
     tree('<Repeat num_cycles="3"><R name="r" _onSuccess="n += 1"/></Repeat>'),
     setup={"n": 0}, keys={"n": "int"}, ticks=7)
case("decorator__keep_running_until_failure_counts",
     tree('<KeepRunningUntilFailure><A name="a" _post="n += 1"/></KeepRunningUntilFailure>'),
     scripts={"a": [S, S, F]}, setup={"n": 0}, keys={"n": "int"}, ticks=4)

# -- gtest_switch / gtest_enums ---------------------------------------------------------------------
case("switch__to_default_and_back_halts_running_child",
     tree('<Switch2 variable="{v}" case_1="1" case_2="42"><R name="r1"/><R name="r2"/><R name="rd"/></Switch2>'),
     setup={"v": "1"}, between={1: {"v": "x"}, 2: {"v": "42"}, 4: {"v": "42"}}, ticks=5)
case("switch__variable_written_by_a_subtree_on_failure",
     tree('<Sequence><Script code="fault := \'none\'; h := 0"/><SubTree ID="S" health="{h}" trigger="low" fault="{=}"/>'
          '<Switch2 variable="{fault}" case_1="none" case_2="low"><A name="n"/><A name="l"/><A name="d"/></Switch2>'
          '</Sequence>',
          sub("S", '<ForceSuccess><ScriptCondition code="health" _onFailure="fault = trigger"/></ForceSuccess>')),
     keys={"fault": "string"}, ticks=1)

# -- gtest_while_do_else / gtest_if_then_else --------------------------------------------------------
case("while_do_else__condition_flips_halt_running_branches",
     tree('<WhileDoElse><C name="c"/><R name="do"/><R name="else"/></WhileDoElse>'),
     scripts={"c": [S, S, F, F, S]}, ticks=6)
case("if_then_else__running_condition_then_branch",
     tree('<IfThenElse><R name="c"/><A name="then"/><A name="else"/></IfThenElse>'),
     scripts={"c": [R_, F]}, ticks=3)

# -- gtest_loop / gtest_ports -----------------------------------------------------------------------
# (Issue 1065, a SubTree literal queue read by LoopDouble, fails in 4.8.2: tests/engine/test_btcpp410.py)
case("loop__if_empty_failure_and_child_failure",
     tree('<Sequence><LoopInt queue="" if_empty="FAILURE"><A name="never"/></LoopInt></Sequence>'), ticks=1)

# -- gtest_reactive_backchaining --------------------------------------------------------------------
case("reactive_backchaining__ensure_warm",
     tree('<ReactiveFallback><ScriptCondition name="warm" code="is_warm"/><ReactiveSequence>'
          '<ScriptCondition name="jacket" code="holding"/><Sequence><R name="wear"/>'
          '<Script code="is_warm = 1"/></Sequence></ReactiveSequence></ReactiveFallback>'),
     scripts={"wear": [R_, R_, S]}, setup={"is_warm": 0, "holding": 1}, keys={"is_warm": "int"}, ticks=5)
case("reactive_backchaining__ensure_warm_with_nested_subtree",
     tree('<ReactiveFallback><ScriptCondition code="is_warm"/><ReactiveSequence><SubTree ID="Hold" _autoremap="true"/>'
          '<Sequence><R name="wear"/><Script code="is_warm = 1"/></Sequence></ReactiveSequence></ReactiveFallback>',
          sub("Hold", '<ReactiveFallback><ScriptCondition code="holding"/><ReactiveSequence>'
                      '<ScriptCondition code="near"/><Sequence><R name="grab"/><Script code="holding = 1"/>'
                      '</Sequence></ReactiveSequence></ReactiveFallback>')),
     scripts={"wear": [R_, R_, S], "grab": [R_, R_, S]}, setup={"is_warm": 0, "holding": 0, "near": 1},
     keys={"is_warm": "int", "holding": "int"}, ticks=7)
