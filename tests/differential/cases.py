"""The differential scenarios: every built-in node kind, halting, subtrees, scripts and pre/post
conditions, each run in bt_runtime and in BT.CPP 4.8.2 (see ``harness.py``).

Leaf IDs: ``C`` condition, ``A`` sync action, ``R`` stateful action (start defaults to
RUNNING, then SUCCESS), ``Ok``/``Fail``. Scripts are keyed by instance name. Constructs where
4.8.2 and 4.10 legitimately differ are left out here (docs/btcpp_differences.md) and tested
against our 4.10 behaviour in the engine unit tests.
"""

from __future__ import annotations

from .harness import Case, tree

S, F, R_, K = "SUCCESS", "FAILURE", "RUNNING", "SKIPPED"

CASES: list[Case] = []


def case(name: str, xml: str, **kw) -> None:
    CASES.append(Case(name, xml, **kw))


# ---------------------------------------------------------------------------------------------
# Sequence / Fallback and their Async variants
# ---------------------------------------------------------------------------------------------
case("sequence_all_success", tree('<Sequence><A name="a1"/><A name="a2"/><A name="a3"/></Sequence>'), ticks=2)
case("sequence_failure_restarts", tree('<Sequence><A name="a1"/><A name="a2"/><A name="a3"/></Sequence>'),
     scripts={"a2": [F, S]}, ticks=3)
case("sequence_running_resumes_without_reticking",
     tree('<Sequence><C name="c"/><R name="r"/><A name="a"/></Sequence>'),
     scripts={"r": [R_, R_, S]}, ticks=4)
case("sequence_running_then_failure",
     tree('<Sequence><C name="c"/><R name="r"/><A name="a"/></Sequence>'),
     scripts={"r": [R_, R_, F, R_, S]}, ticks=5)
case("sequence_tick_once_runs_all", tree('<Sequence><A name="a1"/><A name="a2"/></Sequence>'),
     mode="once", ticks=2)
case("fallback_first_success", tree('<Fallback><A name="a1"/><A name="a2"/></Fallback>'), ticks=2)
case("fallback_all_fail", tree('<Fallback><Fail name="f1"/><Fail name="f2"/><A name="a"/></Fallback>'),
     scripts={"a": [F, S]}, ticks=3)
case("fallback_running_child",
     tree('<Fallback><C name="c"/><R name="r"/><A name="a"/></Fallback>'),
     scripts={"c": [F], "r": [R_, R_, F]}, ticks=4)
case("async_sequence_steps_exactly_once",
     tree('<AsyncSequence><A name="a1"/><A name="a2"/><A name="a3"/></AsyncSequence>'), ticks=4)
case("async_sequence_tick_once_completes",
     tree('<AsyncSequence><A name="a1"/><A name="a2"/><A name="a3"/></AsyncSequence>'), mode="once", ticks=2)
case("async_sequence_failure",
     tree('<AsyncSequence><A name="a1"/><A name="a2"/><A name="a3"/></AsyncSequence>'),
     scripts={"a2": [F, S]}, ticks=5)
case("async_fallback_steps",
     tree('<AsyncFallback><Fail name="f1"/><Fail name="f2"/><A name="a"/></AsyncFallback>'), ticks=4)
case("async_fallback_tick_once",
     tree('<AsyncFallback><Fail name="f1"/><Fail name="f2"/><A name="a"/></AsyncFallback>'),
     mode="once", ticks=2)
case("async_sequence_with_running_child",
     tree('<AsyncSequence><A name="a1"/><R name="r"/><A name="a2"/></AsyncSequence>'),
     scripts={"r": [R_, R_, S]}, mode=["exactly_once", "once", "exactly_once", "once", "once"])
case("sequence_skipped_children",
     tree('<Sequence><A name="a1" _skipIf="1"/><A name="a2"/><A name="a3" _skipIf="1"/></Sequence>'), ticks=2)
case("sequence_all_skipped_root_stays_running",
     tree('<Sequence><A name="a1" _skipIf="1"/><A name="a2" _skipIf="1"/></Sequence>'), ticks=2)
case("fallback_all_skipped",
     tree('<Fallback><A name="a1" _skipIf="1"/><A name="a2" _skipIf="1"/></Fallback>'), ticks=2)
case("fallback_skipped_then_failure",
     tree('<Fallback><A name="a1" _skipIf="1"/><Fail name="f"/></Fallback>'), ticks=2)

# ---------------------------------------------------------------------------------------------
# SequenceWithMemory
# ---------------------------------------------------------------------------------------------
case("seq_memory_yields_and_resumes_after_failure",
     tree('<SequenceWithMemory><A name="a1"/><A name="a2"/><A name="a3"/></SequenceWithMemory>'),
     scripts={"a2": [F, F, S]}, ticks=7)
case("seq_memory_tick_once",
     tree('<SequenceWithMemory><A name="a1"/><A name="a2"/><A name="a3"/></SequenceWithMemory>'),
     scripts={"a3": [F, S]}, mode="once", ticks=3)
case("seq_memory_halt_keeps_index",
     tree('<ReactiveSequence><C name="c"/><SequenceWithMemory><A name="a1"/><R name="r"/><A name="a2"/>'
          '</SequenceWithMemory></ReactiveSequence>'),
     scripts={"c": [S, S, S, F, S], "r": [R_, R_, R_, R_, S]}, ticks=7)
case("seq_memory_halt_tree_keeps_index",
     tree('<SequenceWithMemory><A name="a1"/><R name="r"/><A name="a2"/></SequenceWithMemory>'),
     scripts={"r": [R_, R_, S]}, halt_after=2, ticks=6)
case("seq_memory_skipped",
     tree('<SequenceWithMemory><A name="a1" _skipIf="1"/><A name="a2"/></SequenceWithMemory>'), ticks=2)

# ---------------------------------------------------------------------------------------------
# ReactiveSequence / ReactiveFallback
# ---------------------------------------------------------------------------------------------
case("reactive_sequence_condition_halts_action",
     tree('<ReactiveSequence><C name="c"/><R name="r"/></ReactiveSequence>'),
     scripts={"c": [S, S, F, S], "r": [R_]}, ticks=5)
case("reactive_sequence_restarts_earlier_stateful",
     tree('<ReactiveSequence><R name="r1"/><R name="r2"/></ReactiveSequence>'),
     scripts={"r1": [S], "r2": [R_, R_, S]}, ticks=4)
case("reactive_sequence_first_running_blocks_second",
     tree('<ReactiveSequence><R name="r1"/><R name="r2"/></ReactiveSequence>'),
     scripts={"r1": [R_, R_, S, R_], "r2": [R_, S]}, ticks=5)
case("reactive_sequence_all_success", tree('<ReactiveSequence><C name="c1"/><C name="c2"/></ReactiveSequence>'),
     ticks=2)
case("reactive_sequence_skipped_child",
     tree('<ReactiveSequence><C name="c" _skipIf="1"/><R name="r"/></ReactiveSequence>'),
     scripts={"r": [R_, R_, S]}, ticks=3)
case("reactive_sequence_all_skipped",
     tree('<ReactiveSequence><C name="c1" _skipIf="1"/><C name="c2" _skipIf="1"/></ReactiveSequence>'), ticks=2)
case("reactive_fallback_condition_halts_action",
     tree('<ReactiveFallback><C name="c"/><R name="r"/></ReactiveFallback>'),
     scripts={"c": [F, F, S, F], "r": [R_]}, ticks=5)
case("reactive_fallback_all_fail",
     tree('<ReactiveFallback><C name="c1"/><C name="c2"/></ReactiveFallback>'),
     scripts={"c1": [F], "c2": [F, S]}, ticks=3)
case("reactive_fallback_restarts_earlier_stateful",
     tree('<ReactiveFallback><R name="r1"/><R name="r2"/></ReactiveFallback>'),
     scripts={"r1": [F], "r2": [R_, R_, S]}, ticks=4)
case("reactive_sequence_nested_in_sequence",
     tree('<Sequence><A name="a0"/><ReactiveSequence><C name="c"/><R name="r"/></ReactiveSequence>'
          '<A name="a1"/></Sequence>'),
     scripts={"c": [S, S, F, S], "r": [R_, R_, R_, S]}, ticks=6)

# ---------------------------------------------------------------------------------------------
# Parallel / ParallelAll
# ---------------------------------------------------------------------------------------------
case("parallel_default_waits_for_all",
     tree('<Parallel><A name="a1"/><R name="r"/><A name="a2"/></Parallel>'),
     scripts={"r": [R_, R_, S]}, ticks=4)
case("parallel_failure_exits_early",
     tree('<Parallel><R name="r"/><Fail name="f"/><A name="a"/></Parallel>'), ticks=2)
case("parallel_success_count_one_halts_others",
     tree('<Parallel success_count="1"><R name="r"/><A name="a"/></Parallel>'), ticks=2)
case("parallel_negative_success_count",
     tree('<Parallel success_count="-2" failure_count="2"><A name="a1"/><R name="r"/><Fail name="f"/></Parallel>'),
     scripts={"r": [R_, R_, S]}, ticks=4)
case("parallel_failure_count_two",
     tree('<Parallel success_count="3" failure_count="2"><R name="r1"/><A name="a"/><R name="r2"/></Parallel>'),
     scripts={"a": [F], "r1": [R_, F], "r2": [R_, R_, S]}, ticks=4)
case("parallel_negative_failure_count",
     tree('<Parallel success_count="1" failure_count="-1"><A name="a1"/><A name="a2"/><R name="r"/></Parallel>'),
     scripts={"a1": [F], "a2": [F], "r": [R_, R_, F]}, ticks=4)
case("parallel_all_skipped_default_is_success",
     tree('<Parallel><A name="a1" _skipIf="1"/><A name="a2" _skipIf="1"/></Parallel>'), ticks=2)
case("parallel_all_skipped_positive_threshold",
     tree('<Parallel success_count="2"><A name="a1" _skipIf="1"/><A name="a2" _skipIf="1"/></Parallel>'),
     ticks=2)
case("parallel_threshold_too_large_errors",
     tree('<Parallel success_count="3"><A name="a1"/><A name="a2"/></Parallel>'), ticks=1, error="tick")
case("parallel_completed_not_reticked",
     tree('<Parallel><A name="a1"/><R name="r"/></Parallel>'), scripts={"r": [R_, R_, R_, S]}, ticks=5)
case("parallel_failure_unreachable_success",
     tree('<Parallel success_count="2" failure_count="3"><Fail name="f1"/><Fail name="f2"/><R name="r"/></Parallel>'),
     ticks=2)
case("parallel_all_max_failures_one",
     tree('<ParallelAll><Fail name="f"/><R name="r"/><A name="a"/></ParallelAll>'),
     scripts={"r": [R_, R_, S]}, ticks=4)
case("parallel_all_max_failures_two_one_failure",
     tree('<ParallelAll max_failures="2"><Fail name="f"/><R name="r"/></ParallelAll>'),
     scripts={"r": [R_, S]}, ticks=3)
case("parallel_all_max_failures_zero_always_fails",
     tree('<ParallelAll max_failures="0"><A name="a1"/><A name="a2"/></ParallelAll>'), ticks=2)
case("parallel_all_negative_max_failures",
     tree('<ParallelAll max_failures="-1"><Fail name="f"/><A name="a"/></ParallelAll>'),
     scripts={"a": [S, F]}, ticks=2)
case("parallel_all_all_skipped",
     tree('<ParallelAll><A name="a1" _skipIf="1"/><A name="a2" _skipIf="1"/></ParallelAll>'), ticks=2)
case("parallel_all_halted",
     tree('<ParallelAll><R name="r1"/><R name="r2"/></ParallelAll>'),
     scripts={"r1": [R_, S], "r2": [R_]}, halt_after=2, ticks=4)

# ---------------------------------------------------------------------------------------------
# IfThenElse / WhileDoElse
# ---------------------------------------------------------------------------------------------
case("if_then_else_true_branch_runs",
     tree('<IfThenElse><C name="c"/><R name="then"/><R name="else"/></IfThenElse>'),
     scripts={"then": [R_, R_, S]}, ticks=4)
case("if_then_else_false_branch",
     tree('<IfThenElse><C name="c"/><A name="then"/><A name="else"/></IfThenElse>'),
     scripts={"c": [F, S], "else": [F]}, ticks=2)
case("if_then_two_children_false",
     tree('<IfThenElse><C name="c"/><A name="then"/></IfThenElse>'), scripts={"c": [F, S]}, ticks=2)
case("if_then_stale_failed_condition_keeps_status",
     tree('<IfThenElse><R name="cond"/><A name="then"/></IfThenElse>'), scripts={"cond": [F, S]}, ticks=3)
case("if_then_stale_condition_skips_preconditions",
     tree('<IfThenElse><C name="c" _skipIf="skip"/><A name="then"/></IfThenElse>'),
     scripts={"c": [F, S]}, setup={"skip": 0}, between={1: {"skip": 1}}, ticks=2)
case("if_then_else_running_condition",
     tree('<IfThenElse><R name="cond"/><A name="then"/><A name="else"/></IfThenElse>'),
     scripts={"cond": [R_, R_, S]}, ticks=3)
case("if_then_else_halted",
     tree('<IfThenElse><C name="c"/><R name="then"/><A name="else"/></IfThenElse>'),
     halt_after=1, ticks=4)
case("if_then_else_one_child_errors",
     tree('<IfThenElse><C name="c"/></IfThenElse>'), ticks=1, error="tick")
case("while_do_else_switches_branches",
     tree('<WhileDoElse><C name="c"/><R name="do"/><R name="else"/></WhileDoElse>'),
     scripts={"c": [S, S, F, F, S], "do": [R_], "else": [R_]}, ticks=6)
case("while_do_two_children_false",
     tree('<WhileDoElse><C name="c"/><R name="do"/></WhileDoElse>'),
     scripts={"c": [S, F, S]}, ticks=3)
case("while_do_else_branch_completes",
     tree('<WhileDoElse><C name="c"/><A name="do"/><A name="else"/></WhileDoElse>'),
     scripts={"c": [S, F], "do": [F]}, ticks=2)
case("while_do_stateful_condition_is_stale",
     tree('<WhileDoElse><R name="cond"/><R name="do"/><A name="else"/></WhileDoElse>'),
     scripts={"cond": [S, F], "do": [R_, R_, R_, S]}, ticks=5)
case("while_do_skipped_condition_errors",
     tree('<WhileDoElse><C name="c" _skipIf="1"/><A name="do"/><A name="else"/></WhileDoElse>'),
     ticks=1, error="tick")
case("if_then_skipped_condition_errors",
     tree('<IfThenElse><C name="c" _skipIf="1"/><A name="then"/><A name="else"/></IfThenElse>'),
     ticks=1, error="tick")

# ---------------------------------------------------------------------------------------------
# Switch2..6
# ---------------------------------------------------------------------------------------------
_SW3 = ('<Switch3 variable="{v}" case_1="{c1}" case_2="{c2}" case_3="{c3}">'
        '<A name="s1"/><A name="s2"/><A name="s3"/><A name="def"/></Switch3>')
case("switch_int_matches", tree('<Sequence><Script code="v := n"/><Switch2 variable="{v}" case_1="1" case_2="2">'
                                '<A name="s1"/><A name="s2"/><A name="def"/></Switch2></Sequence>'),
     setup={"n": 2}, between={1: {"n": 1}, 2: {"n": 3}}, ticks=3)
case("switch_string_variable_is_typed", tree('<Switch2 variable="{v}" case_1="1" case_2="2"><A name="s1"/>'
                                             '<A name="s2"/><A name="def"/></Switch2>'),
     setup={"v": 2}, ticks=1, error="setup")
case("switch_double_and_int_equality", tree('<Sequence><Script code="v := n"/>' + _SW3 + '</Sequence>'),
     setup={"n": 2.0, "c1": "1", "c2": "2", "c3": "3"}, between={1: {"n": "1.0"}, 2: {"n": "03"}}, ticks=3)
case("switch_numeric_strings", tree(_SW3),
     setup={"v": "1.0", "c1": "1", "c2": "2", "c3": "3"}, between={1: {"v": "03"}, 2: {"v": "2.0000000001"}},
     ticks=3)
case("switch_string_cases", tree('<Switch3 variable="{v}" case_1="red" case_2="green" case_3="blue">'
                                 '<A name="s1"/><A name="s2"/><A name="s3"/><A name="def"/></Switch3>'),
     setup={"v": "blue"}, between={1: {"v": "green"}, 2: {"v": "Green"}}, ticks=3)
case("switch_missing_variable_default", tree('<Switch2 variable="{nope}" case_1="1" case_2="2">'
                                             '<A name="s1"/><A name="s2"/><A name="def"/></Switch2>'), ticks=2)
case("switch_halts_running_child_on_change",
     tree('<Switch2 variable="{v}" case_1="1" case_2="2"><R name="s1"/><R name="s2"/><A name="def"/></Switch2>'),
     setup={"v": "1"}, between={2: {"v": "2"}, 4: {"v": "5"}}, scripts={"s1": [R_], "s2": [R_]}, ticks=5)
case("switch_wrong_child_count_errors",
     tree('<Switch2 variable="1" case_1="1" case_2="2"><A name="s1"/><A name="s2"/></Switch2>'),
     ticks=1, error="tick")
case("switch6_last_case", tree('<Switch6 variable="{v}" case_1="a" case_2="b" case_3="c" case_4="d" case_5="e"'
                               ' case_6="f"><A name="s1"/><A name="s2"/><A name="s3"/><A name="s4"/>'
                               '<A name="s5"/><A name="s6"/><A name="def"/></Switch6>'),
     setup={"v": "f"}, between={1: {"v": "c"}, 2: {"v": "g"}}, ticks=3)
case("switch_case_from_script", tree('<Sequence><Script code="v := 4; w := 4"/>'
                                     '<Switch4 variable="{v}" case_1="1" case_2="{w}" case_3="3" case_4="4">'
                                     '<A name="s1"/><A name="s2"/><A name="s3"/><A name="s4"/><A name="def"/>'
                                     '</Switch4></Sequence>'), ticks=2)
case("switch_reads_bool_as_number",
     tree('<Sequence><ForceSuccess><SetBlackboard output_key="copy" value="{flag}"/></ForceSuccess>'
          '<Switch2 variable="{flag}" case_1="1" case_2="true"><A name="s1"/><A name="s2"/><A name="def"/>'
          '</Switch2></Sequence>'),
     setup={"flag": True}, between={1: {"flag": False}}, keys={"flag": "string", "copy": "string"}, ticks=2)
case("switch_skipped_child", tree('<Switch2 variable="1" case_1="1" case_2="2"><A name="s1" _skipIf="1"/>'
                                  '<A name="s2"/><A name="def"/></Switch2>'), ticks=2)

# ---------------------------------------------------------------------------------------------
# Decorators
# ---------------------------------------------------------------------------------------------
case("inverter", tree('<Inverter><R name="r"/></Inverter>'), scripts={"r": [R_, S, F]}, ticks=4)
case("inverter_skipped_child", tree('<Sequence><Inverter><A name="a" _skipIf="1"/></Inverter><A name="b"/></Sequence>'),
     ticks=1)
case("force_success_and_failure",
     tree('<Sequence><ForceSuccess><Fail name="f"/></ForceSuccess><ForceFailure><R name="r"/></ForceFailure>'
          '</Sequence>'), scripts={"r": [R_, S]}, ticks=3)
case("force_success_skipped_child",
     tree('<Sequence><ForceSuccess><A name="a" _skipIf="1"/></ForceSuccess><A name="b"/></Sequence>'), ticks=1)
case("keep_running_until_failure", tree('<KeepRunningUntilFailure><A name="a"/></KeepRunningUntilFailure>'),
     scripts={"a": [S, S, F, S]}, mode=["exactly_once", "once", "once", "once"], ticks=4)
case("repeat_steps_exactly_once", tree('<Repeat num_cycles="3"><A name="a"/></Repeat>'), ticks=4)
case("repeat_tick_once_loops", tree('<Repeat num_cycles="3"><A name="a"/></Repeat>'), mode="once", ticks=2)
case("repeat_child_failure", tree('<Repeat num_cycles="3"><A name="a"/></Repeat>'),
     scripts={"a": [S, F, S]}, mode="once", ticks=3)
case("repeat_zero_and_minus_two", tree('<Sequence><Repeat num_cycles="0"><A name="a"/></Repeat>'
                                       '<Repeat num_cycles="-2"><A name="b"/></Repeat></Sequence>'), ticks=1)
case("repeat_running_child", tree('<Repeat num_cycles="2"><R name="r"/></Repeat>'),
     scripts={"r": [R_, S, R_, R_, S]}, ticks=6)
case("repeat_infinite", tree('<Repeat num_cycles="-1"><A name="a"/></Repeat>'),
     scripts={"a": [S, S, S, S, F]}, ticks=6)
case("repeat_from_blackboard", tree('<Repeat num_cycles="{n}"><A name="a"/></Repeat>'),
     setup={"n": 2}, mode="once", ticks=2)
case("retry_steps_exactly_once", tree('<RetryUntilSuccessful num_attempts="3"><Fail name="f"/></RetryUntilSuccessful>'),
     ticks=4)
case("retry_tick_once", tree('<RetryUntilSuccessful num_attempts="3"><Fail name="f"/></RetryUntilSuccessful>'),
     mode="once", ticks=2)
case("retry_succeeds_second_attempt",
     tree('<RetryUntilSuccessful num_attempts="3"><A name="a"/></RetryUntilSuccessful>'),
     scripts={"a": [F, S, F, F, F]}, ticks=6)
case("retry_running_child", tree('<RetryUntilSuccessful num_attempts="2"><R name="r"/></RetryUntilSuccessful>'),
     scripts={"r": [R_, F, R_, R_, S]}, ticks=5)
case("retry_infinite", tree('<RetryUntilSuccessful num_attempts="-1"><A name="a"/></RetryUntilSuccessful>'),
     scripts={"a": [F, F, F, S]}, mode="once", ticks=2)
case("run_once_then_skip",
     tree('<Sequence><RunOnce><A name="a"/></RunOnce><A name="b"/></Sequence>'), ticks=3)
case("run_once_remembers_status",
     tree('<Sequence><RunOnce then_skip="false"><A name="a"/></RunOnce><A name="b"/></Sequence>'),
     scripts={"a": [F, S]}, ticks=3)
case("run_once_survives_halt",
     tree('<Sequence><RunOnce><R name="r"/></RunOnce><R name="b"/></Sequence>'),
     scripts={"r": [R_, S], "b": [R_]}, halt_after=[1, 3], ticks=6)
case("run_once_only_root_skipped", tree('<RunOnce><A name="a"/></RunOnce>'), ticks=3)
case("precondition_true_false",
     tree('<Sequence><Script code="x := x + 1"/><Precondition if="x &lt; 3" else="SUCCESS"><A name="a"/>'
          '</Precondition></Sequence>'), setup={"x": 0}, keys={"x": "int"}, ticks=4)
case("precondition_else_failure_and_running",
     tree('<Fallback><Precondition if="x == 1"><A name="a"/></Precondition>'
          '<Precondition if="x == 2" else="RUNNING"><A name="b"/></Precondition></Fallback>'),
     setup={"x": 0}, between={2: {"x": 2}, 3: {"x": 1}}, ticks=4)
case("precondition_not_rechecked_while_running",
     tree('<Precondition if="x == 1"><R name="r"/></Precondition>'),
     setup={"x": 1}, between={1: {"x": 0}}, scripts={"r": [R_, R_, S]}, ticks=4)
case("precondition_halt_quirk_skips_check",
     tree('<ReactiveSequence><C name="c"/><Precondition if="x == 1"><R name="r"/></Precondition></ReactiveSequence>'),
     setup={"x": 1}, between={2: {"x": 0}}, scripts={"c": [S, F, S], "r": [R_]}, ticks=4)
case("loop_int_static_queue",
     tree('<Sequence><Script code="s := 0"/><LoopInt queue="1;2;3" value="{v}"><Script code="s := s + v"/>'
          '</LoopInt></Sequence>'), keys={"s": "int", "v": "int"}, ticks=6)
case("loop_double_static_tick_once",
     tree('<LoopDouble queue="1.5;2.25" value="{v}"><A name="a"/></LoopDouble>'), keys={"v": "double"},
     mode="once", ticks=4)
case("loop_string_static", tree('<LoopString queue="a;b;;c" value="{v}"><A name="a"/></LoopString>'),
     keys={"v": "string"}, ticks=5)
case("loop_bool_static", tree('<LoopBool queue="true;0;TRUE" value="{v}"><A name="a"/></LoopBool>'),
     keys={"v": "bool"}, ticks=4)
case("loop_empty_if_empty",
     tree('<Sequence><LoopInt queue="" if_empty="SKIPPED" value="{v}"><A name="a"/></LoopInt>'
          '<LoopInt queue="" value="{w}"><A name="b"/></LoopInt>'
          '<LoopInt queue="" if_empty="FAILURE" value="{u}"><A name="c"/></LoopInt></Sequence>'), ticks=2)
case("loop_child_failure_restarts_fresh_copy",
     tree('<LoopInt queue="1;2;3" value="{v}"><A name="a"/></LoopInt>'),
     scripts={"a": [S, F, S]}, keys={"v": "int"}, ticks=6)
case("loop_running_child_does_not_pop",
     tree('<LoopInt queue="7;8" value="{v}"><R name="r"/></LoopInt>'),
     scripts={"r": [R_, S, R_, R_, S]}, keys={"v": "int"}, ticks=6)
case("loop_blackboard_string_queue_one_activation",
     tree('<LoopInt queue="{q}" value="{v}"><A name="a"/></LoopInt>'),
     setup={"q": "4;5"}, keys={"v": "int"}, ticks=3)
case("skip_unless_updated",
     tree('<Sequence><SkipUnlessUpdated entry="x"><A name="a"/></SkipUnlessUpdated><A name="b"/></Sequence>'),
     setup={"x": 1}, between={2: {"x": 2}, 3: {"x": 2}}, ticks=5)
case("skip_unless_updated_braces_and_running",
     tree('<Sequence><SkipUnlessUpdated entry="{x}"><R name="r"/></SkipUnlessUpdated><A name="b"/></Sequence>'),
     between={1: {"x": 1}, 3: {"x": 5}}, scripts={"r": [R_, R_, S]}, ticks=6)
case("wait_value_update",
     tree('<WaitValueUpdate entry="{x}"><A name="a"/></WaitValueUpdate>'),
     between={2: {"x": 3}, 4: {"x": 4}}, ticks=5)
case("was_entry_updated",
     tree('<Sequence><Fallback><WasEntryUpdated entry="x"/><ForceSuccess><A name="no"/></ForceSuccess></Fallback>'
          '<A name="after"/></Sequence>'),
     between={1: {"x": 1}, 3: {"x": 1}}, ticks=5)
case("timeout_not_reached_and_zero",
     tree('<Sequence><Timeout msec="5000"><R name="r"/></Timeout><Timeout msec="0"><A name="a"/></Timeout>'
          '</Sequence>'), scripts={"r": [R_, R_, S]}, ticks=4)
case("sleep_zero_is_immediate", tree('<Sequence><Sleep msec="0"/><A name="a"/></Sequence>'), ticks=2)

# Simple decorators (register_simple_decorator): the child is reset after the decorator's
# status is stored, whatever the decorator returns
case("simple_decorator_passes_and_overrides",
     tree('<Sequence><D name="d1"><A name="a"/></D><D name="d2"><Fail name="f"/></D><A name="b"/></Sequence>'),
     scripts={"d2": [S, F, S], "a": [S, F, S]}, ticks=3)
case("simple_decorator_running_over_finished_child_resets_it",
     tree('<D name="d"><R name="r"/></D>'), scripts={"d": [R_, R_, R_, S], "r": [R_, S, R_, S]}, ticks=5)
case("simple_decorator_halted_in_reactive_sequence",
     tree('<ReactiveSequence><C name="c"/><D name="d"><R name="r"/></D></ReactiveSequence>'),
     scripts={"c": [S, S, F, S], "r": [R_]}, ticks=4)
case("simple_decorator_with_conditions",
     tree('<Sequence><D name="d" _skipIf="skip" _onSuccess="n := n + 1"><A name="a"/></D><A name="b"/></Sequence>'),
     setup={"skip": 0, "n": 0}, between={2: {"skip": 1}}, keys={"n": "int"}, ticks=3)
case("simple_decorator_returning_idle_errors", tree('<D name="d"><A name="a"/></D>'), scripts={"d": ["IDLE"]},
     ticks=1, error="tick")
case("simple_decorator_over_sync_action_returning_running_errors", tree('<D name="d"><A name="a"/></D>'),
     scripts={"a": [R_]}, ticks=1, error="tick")

# ---------------------------------------------------------------------------------------------
# Ports taken from the blackboard are re-read on every tick (literal ones may be read once)
# ---------------------------------------------------------------------------------------------
case("repeat_count_changes_between_ticks", tree('<Repeat num_cycles="{k}"><A name="a"/></Repeat>'),
     setup={"k": 2}, between={2: {"k": 1}, 3: {"k": 3}}, keys={"k": "int"}, ticks=7)
case("retry_attempts_change_between_ticks",
     tree('<RetryUntilSuccessful num_attempts="{k}"><A name="a"/></RetryUntilSuccessful>'),
     scripts={"a": [F, F, F, F, F, S]}, setup={"k": 3}, between={1: {"k": 1}, 3: {"k": 2}}, keys={"k": "int"},
     ticks=6)
case("parallel_thresholds_change_between_ticks",
     tree('<Parallel success_count="{s}" failure_count="{f}"><A name="a"/><A name="b"/><C name="c"/></Parallel>'),
     scripts={"a": [S, F, F, S], "b": [F, F, S, F], "c": [S, S, F, F]}, setup={"s": 1, "f": 1},
     between={1: {"s": 3, "f": 3}, 2: {"s": -1, "f": 2}, 3: {"s": 2, "f": -1}}, keys={"s": "int", "f": "int"},
     ticks=4)
case("parallel_all_max_failures_changes_between_ticks",
     tree('<ParallelAll max_failures="{m}"><Fail name="f"/><A name="a"/></ParallelAll>'),
     scripts={"a": [S, F, S]}, setup={"m": 1}, between={1: {"m": 2}, 2: {"m": 3}}, keys={"m": "int"}, ticks=3,
     error="tick")  # 3 > 2 children: the changed value is seen
case("switch_case_changes_between_ticks",
     tree('<Switch2 variable="{v}" case_1="{c1}" case_2="2"><A name="s1"/><A name="s2"/><A name="def"/></Switch2>'),
     setup={"v": "1", "c1": "1"}, between={1: {"c1": "2"}, 2: {"v": "2"}, 3: {"c1": "x"}}, ticks=4)
case("literal_ports_tick_alike_every_time",
     tree('<Sequence><Repeat num_cycles="2"><A name="a"/></Repeat><Parallel success_count="2">'
          '<A name="p1"/><A name="p2"/></Parallel><ParallelAll max_failures="2"><A name="q1"/><A name="q2"/></ParallelAll>'
          '<Switch2 variable="{v}" case_1="1" case_2="2"><A name="s1"/><A name="s2"/><A name="def"/></Switch2>'
          '<RetryUntilSuccessful num_attempts="2"><A name="r"/></RetryUntilSuccessful></Sequence>'),
     scripts={"a": [S, F, S], "p1": [F, S], "q1": [F], "q2": [S, F], "r": [F, S, F, F]}, setup={"v": "1"},
     between={2: {"v": "3"}}, ticks=6)

# ---------------------------------------------------------------------------------------------
# Halting
# ---------------------------------------------------------------------------------------------
case("halt_tree_running_sequence",
     tree('<Sequence><A name="a"/><R name="r"/><A name="b"/></Sequence>'),
     scripts={"r": [R_]}, halt_after=2, ticks=5)
case("halt_tree_on_halted_runs_everywhere",
     tree('<Sequence _onHalted="h := h + 1"><A name="a" _onHalted="h := h + 10"/>'
          '<R name="r" _onHalted="h := h + 100"/><A name="b" _onHalted="h := h + 1000"/></Sequence>'),
     setup={"h": 0}, keys={"h": "int"}, halt_after=[1, 3], ticks=5)
case("halt_tree_when_idle", tree('<Sequence><A name="a"/><R name="r"/></Sequence>'),
     scripts={"r": [S]}, halt_after=[0, 2], ticks=3)
case("halt_tree_parallel_all_running",
     tree('<Parallel><R name="r1"/><R name="r2"/><R name="r3"/></Parallel>'),
     scripts={"r2": [S]}, halt_after=2, ticks=4)
case("halt_tree_nested_decorators",
     tree('<Inverter><Repeat num_cycles="3"><Sequence><A name="a"/><R name="r"/></Sequence></Repeat></Inverter>'),
     halt_after=2, ticks=5)

# ---------------------------------------------------------------------------------------------
# Subtrees
# ---------------------------------------------------------------------------------------------
_SUB_INOUT = '<BehaviorTree ID="Sub"><Script code="out := in + 1"/></BehaviorTree>'
case("subtree_remap_in_out",
     tree('<Sequence><Script code="a := 41"/><SubTree ID="Sub" in="{a}" out="{b}"/></Sequence>', _SUB_INOUT),
     keys={"a": "int", "b": "int"}, ticks=1)
case("subtree_autoremap",
     tree('<Sequence><Script code="in := 1"/><SubTree ID="Sub" _autoremap="true"/></Sequence>', _SUB_INOUT),
     keys={"in": "int", "out": "int"}, ticks=1)
case("subtree_equals_remap",
     tree('<Sequence><Script code="in := 6"/><SubTree ID="Sub" in="{=}" out="{=}"/></Sequence>', _SUB_INOUT),
     keys={"out": "int"}, ticks=1)
case("subtree_string_literal",
     tree('<SubTree ID="Greet" who="world" out="{msg}"/>',
          '<BehaviorTree ID="Greet"><Script code="out := \'hello \' + who"/></BehaviorTree>'),
     keys={"msg": "string"}, ticks=1)
case("subtree_isolated_without_remap_errors",
     tree('<Sequence><Script code="zz := 1"/><SubTree ID="Sub2"/></Sequence>',
          '<BehaviorTree ID="Sub2"><Script code="q := zz"/></BehaviorTree>'), ticks=1, error="tick")
case("subtree_root_keys_with_at",
     tree('<Sequence><Script code="g := 5"/><SubTree ID="L1"/></Sequence>',
          '<BehaviorTree ID="L1"><SubTree ID="L2"/></BehaviorTree>'
          '<BehaviorTree ID="L2"><Script code="@r := @g * 2"/></BehaviorTree>'),
     keys={"r": "int"}, ticks=1)
case("subtree_nested_remap_chain",
     tree('<Sequence><Script code="x := 2"/><SubTree ID="L1" p="{x}" res="{y}"/></Sequence>',
          '<BehaviorTree ID="L1"><SubTree ID="L2" q="{p}" r="{res}"/></BehaviorTree>'
          '<BehaviorTree ID="L2"><Script code="r := q * 10"/></BehaviorTree>'),
     keys={"y": "int", "x": "int"}, ticks=1)
case("subtree_private_keys_with_autoremap",
     tree('<Sequence><SubTree ID="Sub3" _autoremap="true"/><ScriptCondition code="pub == 1"/></Sequence>',
          '<BehaviorTree ID="Sub3"><Script code="pub := 1; _priv := 2"/></BehaviorTree>'),
     keys={"pub": "int", "_priv": "int"}, ticks=1)
case("subtree_skipped_by_precondition",
     tree('<Sequence><SubTree ID="Sub4" _skipIf="1"/><A name="after"/></Sequence>',
          '<BehaviorTree ID="Sub4"><A name="inner"/></BehaviorTree>'), ticks=2)
case("subtree_running_and_halted",
     tree('<Sequence><SubTree ID="Sub5" name="first"/><SubTree ID="Sub5" name="second"/></Sequence>',
          '<BehaviorTree ID="Sub5"><Sequence><A name="x"/><R name="y"/></Sequence></BehaviorTree>'),
     scripts={"y": [R_, S, R_]}, halt_after=3, ticks=5)
case("subtree_model_default_port",
     tree('<Sequence><SubTree ID="Sub6" out="{res}"/><SubTree ID="Sub6" msg="given" out="{res2}"/></Sequence>',
          '<BehaviorTree ID="Sub6"><Script code="out := msg"/></BehaviorTree>'
          '<TreeNodesModel><SubTree ID="Sub6"><input_port name="msg" default="dflt"/>'
          '<output_port name="out"/></SubTree></TreeNodesModel>'),
     keys={"res": "string", "res2": "string"}, ticks=1)
case("subtree_model_default_blackboard_pointer",
     tree('<Sequence><Script code="src := 8"/><SubTree ID="Sub7" out="{res}"/></Sequence>',
          '<BehaviorTree ID="Sub7"><Script code="out := msg + 1"/></BehaviorTree>'
          '<TreeNodesModel><SubTree ID="Sub7"><input_port name="msg" default="{src}"/>'
          '<output_port name="out"/></SubTree></TreeNodesModel>'),
     keys={"res": "int"}, ticks=1)
case("subtree_model_mandatory_port_missing",
     tree('<SubTree ID="Sub8"/>',
          '<BehaviorTree ID="Sub8"><A name="a"/></BehaviorTree>'
          '<TreeNodesModel><SubTree ID="Sub8"><input_port name="needed"/></SubTree></TreeNodesModel>'),
     ticks=1, error="build")
case("subtree_pre_post_conditions_on_node",
     tree('<Sequence><SubTree ID="Sub9" _onSuccess="done := 1" _post="p := 2"/></Sequence>',
          '<BehaviorTree ID="Sub9"><A name="inner"/></BehaviorTree>'),
     setup={"done": 0, "p": 0}, keys={"done": "int", "p": "int"}, ticks=1)

# ---------------------------------------------------------------------------------------------
# Script, ScriptCondition, SetBlackboard, UnsetBlackboard
# ---------------------------------------------------------------------------------------------
case("script_counter", tree('<Sequence><Script code="n := n + 1"/><ScriptCondition code="n &lt; 3"/></Sequence>'),
     setup={"n": 0}, keys={"n": "int"}, ticks=4)
case("script_condition_strings",
     tree('<Fallback><ScriptCondition code="s == \'go\'"/><A name="other"/></Fallback>'),
     setup={"s": "stop"}, between={1: {"s": "go"}}, ticks=2)
case("script_condition_non_bool_errors", tree('<ScriptCondition code="5"/>'), ticks=1, error="tick")
case("script_condition_negative_double_errors", tree('<ScriptCondition code="0 - 1.5"/>'), ticks=1, error="tick")
case("precondition_negative_value_errors",
     tree('<Sequence><Script code="d := 0 - 2.0"/><Precondition if="d"><A name="a"/></Precondition></Sequence>'),
     ticks=1, error="tick")
case("pre_condition_negative_and_zero",
     tree('<Sequence><A name="a" _skipIf="-0.0"/><A name="b" _successIf="0.5"/></Sequence>'), ticks=1)
case("set_blackboard_literal_and_copy",
     tree('<Sequence><SetBlackboard output_key="a" value="hello"/><SetBlackboard output_key="b" value="{a}"/>'
          '</Sequence>'), keys={"a": "string", "b": "string"}, ticks=1)
case("set_blackboard_into_typed_entry",
     tree('<Sequence><SetBlackboard output_key="n" value="42"/><ScriptCondition code="n == 42"/></Sequence>'),
     setup={"n": 1}, keys={"n": "int"}, ticks=1)
case("set_blackboard_untyped_destination_quirk",
     tree('<Sequence><Script code="x := 1"/><SetBlackboard output_key="x" value="5"/></Sequence>'),
     keys={"x": "int"}, ticks=1)
case("set_blackboard_repeated_string_writes",  # set<BT::Any>: the entry is std::string, not untyped
     tree('<Repeat num_cycles="3"><Sequence><SetBlackboard output_key="x" value="1"/>'
          '<SetBlackboard output_key="x" value="abc"/><A name="a"/></Sequence></Repeat>'),
     keys={"x": "string"}, ticks=1)
case("set_blackboard_copy_of_untyped_becomes_any",
     tree('<Sequence><Script code="y := 7"/><SetBlackboard output_key="x" value="{y}"/>'
          '<SetBlackboard output_key="x" value="2"/></Sequence>'), ticks=1, error="tick")
case("set_blackboard_twice_into_untyped_destination",
     tree('<Sequence><Script code="x := 1"/><SetBlackboard output_key="x" value="2"/>'
          '<SetBlackboard output_key="x" value="3"/></Sequence>'), ticks=1, error="tick")
# Found by the scripted random trees (test_random_scripted_trees.py):
case("set_blackboard_through_remap_keeps_the_entry_untyped",  # set() on a remapped key: create branch
     tree('<SubTree ID="S" p="lit" q="{s}"/>',
          '<BehaviorTree ID="S"><SetBlackboard output_key="q" value="{p}"/></BehaviorTree>'),
     setup={"s": "abc"}, keys={"s": "string"}, ticks=3)
case("subtree_string_literal_entry_is_untyped",  # set<std::string> on a new entry: AnyTypeAllowed
     tree('<SubTree ID="S" p="x"/>',
          '<BehaviorTree ID="S"><Sequence><SetBlackboard output_key="p" value="{p}"/>'
          '<SetBlackboard output_key="p" value="7"/></Sequence></BehaviorTree>'),
     ticks=1, error="tick")
case("subtree_string_literal_retyped_by_script",
     tree('<SubTree ID="S" p="x"/>',
          '<BehaviorTree ID="S"><Sequence><Script code="p := 5"/><Script code="p = 2.5"/>'
          '<ScriptCondition code="p == 2"/></Sequence></BehaviorTree>'), ticks=1, error="tick")
case("set_blackboard_empty_source_fails",
     tree('<SetBlackboard output_key="a" value="{nope}"/>'), ticks=1)
case("unset_blackboard",
     tree('<Sequence><Script code="k := 1"/><UnsetBlackboard key="k"/><ScriptCondition code="k == 1"/></Sequence>'),
     ticks=1, error="tick")
case("unset_missing_key_is_success", tree('<Sequence><UnsetBlackboard key="absent"/><A name="a"/></Sequence>'),
     ticks=1)
case("script_error_propagates", tree('<Sequence><A name="a"/><Script code="y = 3"/></Sequence>'),
     ticks=1, error="tick")
case("output_port_chain_through_script",
     tree('<Sequence><Script code="msg := \'a\'"/><Script code="msg += \'b\'"/><Script code="len := 2"/>'
          '</Sequence>'), keys={"msg": "string", "len": "int"}, ticks=2)

# ---------------------------------------------------------------------------------------------
# Pre- and post-conditions
# ---------------------------------------------------------------------------------------------
case("pre_failure_beats_success",
     tree('<Sequence><A name="a" _successIf="1" _failureIf="1"/><A name="b"/></Sequence>'), ticks=1)
case("pre_success_beats_skip",
     tree('<Sequence><A name="a" _skipIf="1" _successIf="1"/><A name="b"/></Sequence>'), ticks=1)
case("pre_skip_if_from_blackboard",
     tree('<Sequence><A name="a" _skipIf="flag == 1"/><A name="b"/></Sequence>'),
     setup={"flag": 1}, between={1: {"flag": 0}}, ticks=2)
case("pre_while_false_skips", tree('<Sequence><A name="a" _while="ok"/><A name="b"/></Sequence>'),
     setup={"ok": 0}, between={1: {"ok": 1}}, ticks=2)
case("pre_while_turns_false_mid_run",
     tree('<Sequence><R name="r" _while="ok" _onHalted="h := 1"/><A name="b"/></Sequence>'),
     setup={"ok": 1, "h": 0}, between={2: {"ok": 0}}, scripts={"r": [R_]}, keys={"h": "int"}, ticks=4)
case("pre_while_on_control_node",
     tree('<Sequence _while="ok"><A name="a"/><R name="r"/></Sequence>'),
     setup={"ok": 1}, between={2: {"ok": 0}}, scripts={"r": [R_]}, ticks=4)
case("pre_not_rechecked_while_running",
     tree('<Sequence><R name="r" _failureIf="x == 1" _successIf="x == 2" _skipIf="x == 3"/></Sequence>'),
     setup={"x": 0}, between={1: {"x": 1}, 2: {"x": 2}, 3: {"x": 3}}, scripts={"r": [R_, R_, R_, S, R_]}, ticks=5)
case("post_on_success_failure_post",
     tree('<Sequence><A name="a" _onSuccess="s := s + 1" _onFailure="f := f + 1" _post="p := p + 1"/></Sequence>'),
     setup={"s": 0, "f": 0, "p": 0}, scripts={"a": [S, F, S]}, keys={"s": "int", "f": "int", "p": "int"}, ticks=3)
case("post_runs_after_precondition_result",
     tree('<Sequence><A name="a" _successIf="1" _onSuccess="s := 1" _post="p := 1"/>'
          '<A name="b" _failureIf="1" _onFailure="f := 1"/></Sequence>'),
     setup={"s": 0, "f": 0, "p": 0}, keys={"s": "int", "f": "int", "p": "int"}, ticks=1)
case("post_not_run_when_skipped_or_running",
     tree('<Sequence><A name="a" _skipIf="1" _post="p := p + 1"/><R name="r" _post="p := p + 10"/></Sequence>'),
     setup={"p": 0}, scripts={"r": [R_, R_, S]}, keys={"p": "int"}, ticks=3)
case("post_not_run_on_halt",
     tree('<Sequence><R name="r" _post="p := 1" _onHalted="h := 1"/></Sequence>'),
     setup={"p": 0, "h": 0}, keys={"p": "int", "h": "int"}, halt_after=1, ticks=2)
case("on_halted_on_reactive_halt",
     tree('<ReactiveSequence><C name="c"/><R name="r" _onHalted="h := h + 1"/></ReactiveSequence>'),
     setup={"h": 0}, scripts={"c": [S, F, S, F]}, keys={"h": "int"}, ticks=4)
case("post_on_decorator_resets_its_completed_child",
     tree('<Sequence><Inverter _post="p := p + 1"><A name="a"/></Inverter>'
          '<Repeat num_cycles="2" _onSuccess="s := s + 1"><A name="b"/></Repeat></Sequence>'),
     setup={"p": 0, "s": 0}, scripts={"a": [F, F, S, F]}, keys={"p": "int", "s": "int"}, ticks=4)
case("post_on_decorator_restarts_a_stateful_child",
     tree('<Inverter _post="p := p + 1"><R name="r"/></Inverter>'),
     setup={"p": 0}, scripts={"r": [R_, S, R_, S]}, keys={"p": "int"}, ticks=4)
case("pre_on_decorator_with_running_child",
     tree('<Sequence><ForceSuccess _while="ok" _post="p := p + 1"><R name="r"/></ForceSuccess></Sequence>'),
     setup={"ok": 1, "p": 0}, between={2: {"ok": 0}}, scripts={"r": [R_, R_, R_, S]}, keys={"p": "int"}, ticks=4)
case("post_script_error_at_tick",
     tree('<Sequence><A name="a" _post="p := missing + 1"/></Sequence>'), ticks=1, error="tick")
case("pre_skip_if_on_control_node",
     tree('<Sequence><Fallback _skipIf="1"><A name="a"/></Fallback><A name="b"/></Sequence>'), ticks=1)
case("pre_condition_script_error_at_tick",
     tree('<A name="a" _skipIf="missing_var == 1"/>'), ticks=1, error="tick")
case("pre_condition_bad_script_at_build",
     tree('<A name="a" _skipIf="1 +"/>'), ticks=1, error="build")
case("post_conditions_in_retry_loop",
     tree('<RetryUntilSuccessful num_attempts="3"><A name="a" _onFailure="f := f + 1"/></RetryUntilSuccessful>'),
     setup={"f": 0}, scripts={"a": [F, F, S]}, keys={"f": "int"}, mode="once", ticks=1)

# ---------------------------------------------------------------------------------------------
# Loading errors both engines must raise
# ---------------------------------------------------------------------------------------------
case("load_unknown_node", tree('<Sequence><Nope/></Sequence>'), ticks=1, error="build")
case("load_decorator_two_children", tree('<Inverter><A name="a"/><A name="b"/></Inverter>'), ticks=1,
     error="build")
case("load_action_with_child", tree('<A name="a"><A name="b"/></A>'), ticks=1, error="build")
case("load_unknown_port", tree('<Repeat num_cycle="2"><A name="a"/></Repeat>'), ticks=1, error="build")
case("load_bad_literal", tree('<Repeat num_cycles="abc"><A name="a"/></Repeat>'), ticks=1, error="build")
case("load_bad_bool_literal", tree('<RunOnce then_skip="yes"><A name="a"/></RunOnce>'), ticks=1, error="build")
case("load_unknown_subtree", tree('<SubTree ID="Missing"/>'), ticks=1, error="build")
case("load_reactive_explicit_child_quirk",
     tree('<ReactiveSequence><Action ID="A" name="a"/></ReactiveSequence>'), ticks=1, error="build")
case("explicit_category_not_checked", tree('<Sequence><Condition ID="A" name="a"/><Action ID="C" name="c"/></Sequence>'),
     ticks=1)
case("load_type_mismatch_between_ports",
     tree('<Sequence><Repeat num_cycles="{n}"><A name="a"/></Repeat>'
          '<Sleep msec="{n}"/></Sequence>'), ticks=1, error="build")
