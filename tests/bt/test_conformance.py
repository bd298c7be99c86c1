"""BT.CPP v4 conformance: trees of built-ins and scripts, statuses tick by tick, blackboards.

Each case follows BehaviorTree.CPP 4.x semantics (its node documentation and sources): what
each node returns on each child status, which children are re-ticked and which are halted.
Halting is observed through ``_onHalted`` scripts; time is driven by a manual clock.
"""

from __future__ import annotations

import pytest
from bt_harness import Case, Step, run_case

S = Step
SLEEP_H = '<Sleep msec="100" _onHalted="h := 1"/>'

CONTROLS = [
    Case("sequence_all_success",
         "<Sequence><Script code=\"s := 'a'\"/><Script code=\"s := s .. 'b'\"/></Sequence>",
         [S("SUCCESS", bb={"s": "ab"})]),
    Case("sequence_failure_restarts_from_first",
         '<Sequence><Script code="a += 1"/><ScriptCondition code="false"/></Sequence>',
         [S("FAILURE", bb={"a": 1}), S("FAILURE", bb={"a": 2})], init={"a": 0}),
    Case("sequence_running_child_resumed_not_earlier",
         '<Sequence><Script code="a += 1"/><Sleep msec="100"/><Script code="b := 1"/></Sequence>',
         [S("RUNNING", bb={"a": 1, "b": None}), S("SUCCESS", dt=0.1, bb={"a": 1, "b": 1})],
         init={"a": 0}),
    Case("sequence_all_children_skipped",
         '<Sequence><Script code="a := 1" _skipIf="true"/><AlwaysFailure _skipIf="true"/>'
         '</Sequence>', [S("SKIPPED", bb={"a": None})]),
    Case("sequence_skipped_child_is_passed",
         '<Sequence><AlwaysFailure _skipIf="true"/><Script code="a := 1"/></Sequence>',
         [S("SUCCESS", bb={"a": 1})]),
    Case("sequence_with_memory_resumes_at_failed_child",
         '<SequenceWithMemory><Script code="a += 1"/><ScriptCondition code="ok"/>'
         '<Script code="b += 1"/></SequenceWithMemory>',
         [S("FAILURE", bb={"a": 1, "b": 0}), S("SUCCESS", set={"ok": True}, bb={"a": 1, "b": 1}),
          S("SUCCESS", bb={"a": 2, "b": 2})], init={"a": 0, "b": 0, "ok": False}),
    Case("sequence_with_memory_running_resume",
         '<SequenceWithMemory><Script code="a += 1"/><Sleep msec="100"/></SequenceWithMemory>',
         [S("RUNNING", bb={"a": 1}), S("SUCCESS", dt=0.1, bb={"a": 1})], init={"a": 0}),
    Case("fallback_stops_at_first_success",
         '<Fallback><ScriptCondition code="false"/><Script code="x := 1"/>'
         '<Script code="y := 1"/></Fallback>', [S("SUCCESS", bb={"x": 1, "y": None})]),
    Case("fallback_all_fail",
         '<Fallback><AlwaysFailure/><ScriptCondition code="1 &gt; 2"/></Fallback>',
         [S("FAILURE")]),
    Case("fallback_running_child_resumed",
         '<Fallback><ScriptCondition code="c += 1; false"/><Sleep msec="100"/></Fallback>',
         [S("RUNNING", bb={"c": 1}), S("RUNNING", dt=0.05, bb={"c": 1}),
          S("SUCCESS", dt=0.05, bb={"c": 1}), S("RUNNING", bb={"c": 2})], init={"c": 0}),
    Case("fallback_all_skipped",
         '<Fallback><AlwaysFailure _skipIf="true"/><AlwaysSuccess _skipIf="true"/></Fallback>',
         [S("SKIPPED")]),
    Case("reactive_sequence_reticks_from_first",
         '<ReactiveSequence><Script code="c += 1"/><Sleep msec="100"/></ReactiveSequence>',
         [S("RUNNING", bb={"c": 1}), S("RUNNING", dt=0.05, bb={"c": 2}),
          S("SUCCESS", dt=0.05, bb={"c": 3})], init={"c": 0}),
    Case("reactive_sequence_failure_halts_running_child",
         f'<ReactiveSequence><ScriptCondition code="ok"/>{SLEEP_H}</ReactiveSequence>',
         [S("RUNNING", bb={"h": None}), S("FAILURE", set={"ok": False}, bb={"h": 1})],
         init={"ok": True}),
    Case("reactive_sequence_earlier_running_child_halts_later_one",
         '<ReactiveSequence><Sleep msec="50" _while="gate" _onHalted="h0 := 1"/>'
         '<Sleep msec="100" _onHalted="h1 := 1"/></ReactiveSequence>',
         [S("RUNNING", bb={"h0": None, "h1": None}),
          S("RUNNING", set={"gate": True}, bb={"h0": None, "h1": 1}),
          S("RUNNING", set={"gate": False}, bb={"h0": 1})], init={"gate": False}),
    Case("reactive_fallback_success_halts_running_child",
         f'<ReactiveFallback><ScriptCondition code="done"/>{SLEEP_H}</ReactiveFallback>',
         [S("RUNNING", bb={"h": None}), S("SUCCESS", set={"done": True}, bb={"h": 1})],
         init={"done": False}),
    Case("reactive_fallback_all_fail",
         '<ReactiveFallback><AlwaysFailure/><ScriptCondition code="false"/></ReactiveFallback>',
         [S("FAILURE")]),
    Case("parallel_default_needs_all_successes",
         '<Parallel><Sleep msec="100"/><Sleep msec="200"/></Parallel>',
         [S("RUNNING"), S("RUNNING", dt=0.1), S("SUCCESS", dt=0.1)]),
    Case("parallel_success_count_one_halts_the_others",
         '<Parallel success_count="1"><Sleep msec="100"/>'
         '<Sleep msec="200" _onHalted="h := 1"/></Parallel>',
         [S("RUNNING"), S("SUCCESS", dt=0.1, bb={"h": 1})]),
    Case("parallel_failure_halts_running_sibling",
         f'<Parallel>{SLEEP_H}<AlwaysFailure/></Parallel>', [S("FAILURE", bb={"h": 1})]),
    Case("parallel_negative_failure_count_means_all",
         '<Parallel success_count="1" failure_count="-1"><AlwaysFailure/><Sleep msec="100"/>'
         '</Parallel>', [S("RUNNING"), S("SUCCESS", dt=0.1)]),
    Case("parallel_default_failure_count_is_one",
         '<Parallel success_count="1"><AlwaysFailure/><Sleep msec="100"/></Parallel>',
         [S("FAILURE")]),
    Case("parallel_fails_when_success_becomes_impossible",
         '<Parallel success_count="2" failure_count="2"><AlwaysFailure/>'
         '<Sleep msec="100"/></Parallel>', [S("FAILURE")]),
    Case("parallel_finished_child_not_reticked",
         '<Parallel><Script code="c += 1"/><Sleep msec="100"/></Parallel>',
         [S("RUNNING", bb={"c": 1}), S("SUCCESS", dt=0.1, bb={"c": 1}),
          S("RUNNING", bb={"c": 2})], init={"c": 0}),
    Case("parallel_all_waits_for_every_child",
         '<ParallelAll><AlwaysFailure/><Sleep msec="100"/></ParallelAll>',
         [S("RUNNING"), S("FAILURE", dt=0.1)]),
    Case("parallel_all_max_failures_two",
         '<ParallelAll max_failures="2"><AlwaysFailure/><Sleep msec="100"/></ParallelAll>',
         [S("RUNNING"), S("SUCCESS", dt=0.1)]),
    Case("parallel_all_negative_max_failures_one_fails",
         '<ParallelAll max_failures="-1"><AlwaysFailure/><AlwaysSuccess/></ParallelAll>',
         [S("SUCCESS")]),
    Case("parallel_all_negative_max_failures_all_fail",
         '<ParallelAll max_failures="-1"><AlwaysFailure/><AlwaysFailure/></ParallelAll>',
         [S("FAILURE")]),
    Case("if_then_else_true_branch",
         "<IfThenElse><ScriptCondition code=\"true\"/><Script code=\"r := 'then'\"/>"
         "<Script code=\"r := 'else'\"/></IfThenElse>", [S("SUCCESS", bb={"r": "then"})]),
    Case("if_then_else_false_branch",
         "<IfThenElse><ScriptCondition code=\"false\"/><Script code=\"r := 'then'\"/>"
         "<Script code=\"r := 'else'\"/></IfThenElse>", [S("SUCCESS", bb={"r": "else"})]),
    Case("if_then_without_else_fails",
         '<IfThenElse><ScriptCondition code="false"/><Script code="r := 1"/></IfThenElse>',
         [S("FAILURE", bb={"r": None})]),
    Case("if_then_else_condition_not_rechecked_while_branch_runs",
         '<IfThenElse><ScriptCondition code="c += 1; c &gt; 0"/><Sleep msec="100"/>'
         '</IfThenElse>', [S("RUNNING", bb={"c": 1}), S("SUCCESS", dt=0.1, bb={"c": 1})],
         init={"c": 0}),
    Case("while_do_else_rechecks_and_halts_do_branch",
         f'<WhileDoElse><ScriptCondition code="ok"/>{SLEEP_H}<Script code="e := 1"/>'
         '</WhileDoElse>',
         [S("RUNNING", bb={"h": None}), S("SUCCESS", set={"ok": False}, bb={"h": 1, "e": 1})],
         init={"ok": True}),
    Case("while_do_else_two_children_false_fails",
         '<WhileDoElse><ScriptCondition code="false"/><Script code="r := 1"/></WhileDoElse>',
         [S("FAILURE", bb={"r": None})]),
    Case("switch2_selects_matching_case",
         '<Switch2 variable="{v}" case_1="a" case_2="b"><Script code="r := 1"/>'
         '<Script code="r := 2"/><Script code="r := 3"/></Switch2>',
         [S("SUCCESS", bb={"r": 2})], init={"v": "b"}),
    Case("switch2_default_child",
         '<Switch2 variable="{v}" case_1="a" case_2="b"><Script code="r := 1"/>'
         '<Script code="r := 2"/><Script code="r := 3"/></Switch2>',
         [S("SUCCESS", bb={"r": 3})], init={"v": "zzz"}),
    Case("switch3_compares_numbers",
         '<Sequence><Script code="x := 42"/><Switch3 variable="{x}" case_1="1" case_2="42.0" '
         'case_3="7"><Script code="r := 1"/><Script code="r := 2"/><Script code="r := 3"/>'
         '<Script code="r := 4"/></Switch3></Sequence>', [S("SUCCESS", bb={"r": 2})]),
    Case("switch_halts_previous_running_child",
         f'<Switch2 variable="{{v}}" case_1="a" case_2="b">{SLEEP_H}<Script code="r := 2"/>'
         '<Script code="r := 3"/></Switch2>',
         [S("RUNNING", bb={"h": None}), S("SUCCESS", set={"v": "b"}, bb={"h": 1, "r": 2})],
         init={"v": "a"}),
    Case("switch6_last_case",
         '<Switch6 variable="{v}" case_1="1" case_2="2" case_3="3" case_4="4" case_5="5" '
         'case_6="6">' + "".join(f'<Script code="r := {i}"/>' for i in range(1, 8))
         + "</Switch6>", [S("SUCCESS", bb={"r": 6})], init={"v": "6"}),
    Case("switch_compares_a_number_text_as_a_number",
         '<Switch2 variable="{v}" case_1="1" case_2="2.0"><Script code="r := 1"/>'
         '<Script code="r := 2"/><Script code="r := 3"/></Switch2>',
         [S("SUCCESS", bb={"r": 2})], init={"v": "2"}),
]

DECORATORS = [
    Case("inverter_success_to_failure", "<Inverter><AlwaysSuccess/></Inverter>", [S("FAILURE")]),
    Case("inverter_failure_to_success", "<Inverter><AlwaysFailure/></Inverter>", [S("SUCCESS")]),
    Case("inverter_passes_running", '<Inverter><Sleep msec="100"/></Inverter>',
         [S("RUNNING"), S("FAILURE", dt=0.1)]),
    Case("force_success", "<ForceSuccess><AlwaysFailure/></ForceSuccess>", [S("SUCCESS")]),
    Case("force_failure", "<ForceFailure><AlwaysSuccess/></ForceFailure>", [S("FAILURE")]),
    Case("force_success_passes_running", '<ForceSuccess><Sleep msec="100"/></ForceSuccess>',
         [S("RUNNING"), S("SUCCESS", dt=0.1)]),
    Case("repeat_loops_within_one_tick",
         '<Repeat num_cycles="3"><Script code="c += 1"/></Repeat>',
         [S("SUCCESS", bb={"c": 3}), S("SUCCESS", bb={"c": 6})], init={"c": 0}),
    Case("repeat_stops_on_failure",
         '<Repeat num_cycles="5"><Sequence><Script code="c += 1"/>'
         '<ScriptCondition code="c &lt; 2"/></Sequence></Repeat>',
         [S("FAILURE", bb={"c": 2})], init={"c": 0}),
    Case("repeat_running_child_returns_running",
         '<Repeat num_cycles="2"><Sleep msec="100"/></Repeat>',
         [S("RUNNING"), S("RUNNING", dt=0.1), S("SUCCESS", dt=0.1)]),
    Case("repeat_num_cycles_from_blackboard",
         '<Repeat num_cycles="{n}"><Script code="c += 1"/></Repeat>',
         [S("SUCCESS", bb={"c": 4})], init={"n": "4", "c": 0}),
    Case("retry_succeeds_on_third_attempt_in_one_tick",
         '<RetryUntilSuccessful num_attempts="5"><Sequence><Script code="c += 1"/>'
         '<ScriptCondition code="c &gt;= 3"/></Sequence></RetryUntilSuccessful>',
         [S("SUCCESS", bb={"c": 3})], init={"c": 0}),
    Case("retry_exhausted_fails",
         '<RetryUntilSuccessful num_attempts="3"><ScriptCondition code="c += 1; false"/>'
         '</RetryUntilSuccessful>', [S("FAILURE", bb={"c": 3})], init={"c": 0}),
    Case("retry_running_child_returns_running",
         '<RetryUntilSuccessful num_attempts="2"><Sleep msec="100"/></RetryUntilSuccessful>',
         [S("RUNNING"), S("SUCCESS", dt=0.1)]),
    Case("keep_running_until_failure",
         '<KeepRunningUntilFailure><ScriptCondition code="c += 1; c &lt; 3"/>'
         '</KeepRunningUntilFailure>',
         [S("RUNNING", bb={"c": 1}), S("RUNNING", bb={"c": 2}), S("FAILURE", bb={"c": 3})],
         init={"c": 0}),
    Case("timeout_halts_child_and_fails",
         '<Timeout msec="200"><Sleep msec="500" _onHalted="h := 1"/></Timeout>',
         [S("RUNNING"), S("RUNNING", dt=0.1, bb={"h": None}), S("FAILURE", dt=0.1, bb={"h": 1})]),
    Case("timeout_child_finishes_in_time",
         '<Timeout msec="200"><Sleep msec="100"/></Timeout>',
         [S("RUNNING"), S("SUCCESS", dt=0.1)]),
    Case("timeout_restarts_after_firing",
         '<Timeout msec="200"><Sleep msec="500"/></Timeout>',
         [S("RUNNING"), S("FAILURE", dt=0.2), S("RUNNING"), S("RUNNING", dt=0.1),
          S("FAILURE", dt=0.1)]),
    Case("delay_waits_then_ticks_child",
         '<Delay delay_msec="100"><Script code="c += 1"/></Delay>',
         [S("RUNNING", bb={"c": 0}), S("RUNNING", dt=0.05, bb={"c": 0}),
          S("SUCCESS", dt=0.05, bb={"c": 1}), S("RUNNING", bb={"c": 1})], init={"c": 0}),
    Case("sleep_runs_for_msec", '<Sleep msec="100"/>',
         [S("RUNNING"), S("RUNNING", dt=0.099), S("SUCCESS", dt=0.001)]),
    Case("sleep_zero_succeeds_at_once", '<Sleep msec="0"/>', [S("SUCCESS")]),
    Case("run_once_then_skip",
         '<RunOnce><Script code="c += 1"/></RunOnce>',
         [S("SUCCESS", bb={"c": 1}), S("SKIPPED", bb={"c": 1})], init={"c": 0}),
    Case("run_once_in_sequence_is_skipped_after",
         '<Sequence><RunOnce><Script code="c += 1"/></RunOnce><Script code="d += 1"/>'
         '</Sequence>', [S("SUCCESS", bb={"c": 1, "d": 1}), S("SUCCESS", bb={"c": 1, "d": 2})],
         init={"c": 0, "d": 0}),
    Case("run_once_then_skip_false_repeats_status",
         '<RunOnce then_skip="false"><ScriptCondition code="c += 1; false"/></RunOnce>',
         [S("FAILURE", bb={"c": 1}), S("FAILURE", bb={"c": 1})], init={"c": 0}),
    Case("precondition_true_ticks_child",
         '<Precondition if="go"><Script code="r := 1"/></Precondition>',
         [S("SUCCESS", bb={"r": 1})], init={"go": True}),
    Case("precondition_false_returns_failure_by_default",
         '<Precondition if="go"><Script code="r := 1"/></Precondition>',
         [S("FAILURE", bb={"r": None})], init={"go": False}),
    Case("precondition_else_status",
         '<Precondition if="x &gt; 3" else="SUCCESS"><Script code="r := 1"/></Precondition>',
         [S("SUCCESS", bb={"r": None})], init={"x": 1}),
    Case("precondition_not_rechecked_while_child_runs",
         '<Precondition if="go"><Sleep msec="100"/></Precondition>',
         [S("RUNNING"), S("SUCCESS", dt=0.1, set={"go": False}), S("FAILURE")],
         init={"go": True}),
]

LEAVES = [
    Case("script_arithmetic_precedence",
         '<Script code="a := 1 + 2 * 3; b := (1 + 2) * 3; c := 10 / 4; d := -a + 1"/>',
         [S("SUCCESS", bb={"a": 7, "b": 9, "c": 2.5, "d": -6})]),
    Case("script_strings",
         "<Script code=\"s := 'ab' .. 'cd'; t := 'x' + 'y'; n := 'n=' .. 3\"/>",
         [S("SUCCESS", bb={"s": "abcd", "t": "xy", "n": "n=3"})]),
    Case("script_ternary_logic_and_chained_comparison",
         "<Script code=\"x := 5; y := x &gt; 3 ? 'big' : 'small'; "
         "z := (x == 5) &amp;&amp; !(x != 5); w := 1 &lt; x &lt; 10; v := x &lt; 2 || false\"/>",
         [S("SUCCESS", bb={"y": "big", "z": True, "w": True, "v": False})]),
    Case("script_compound_assignment",
         "<Script code=\"n := 10; n += 5; n -= 3; n *= 2; n /= 4; s := 'a'; s += 'b'\"/>",
         [S("SUCCESS", bb={"n": 6.0, "s": "ab"})]),
    Case("script_hex_booleans_bitwise",
         '<Script code="a := 0x0F &amp; 6; b := true; c := 5 | 2; d := 6 ^ 3"/>',
         [S("SUCCESS", bb={"a": 6, "b": True, "c": 7, "d": 5})]),
    Case("script_condition_false_then_fallback",
         "<Fallback><ScriptCondition code=\"1 == 2\"/><Script code=\"r := 'fell'\"/></Fallback>",
         [S("SUCCESS", bb={"r": "fell"})]),
    Case("script_string_number_comparison",
         '<ScriptCondition code="s &gt; 2 &amp;&amp; s == 3"/>', [S("SUCCESS")], init={"s": "3"}),
    Case("set_blackboard_literal",
         '<Sequence><SetBlackboard output_key="k" value="42"/>'
         '<ScriptCondition code="k == 42"/></Sequence>', [S("SUCCESS", bb={"k": "42"})]),
    Case("set_blackboard_copies_reference",
         '<SetBlackboard output_key="dst" value="{src}"/>',
         [S("SUCCESS", bb={"dst": [1, 2]})], init={"src": [1, 2]}),
    Case("unset_blackboard_removes_entry",
         '<UnsetBlackboard key="k"/>', [S("SUCCESS", bb={"k": None})], init={"k": 1}),
    Case("always_success", "<AlwaysSuccess/>", [S("SUCCESS")]),
    Case("always_failure", "<AlwaysFailure/>", [S("FAILURE")]),
]

ATTRIBUTES = [
    Case("skip_if_true_skips_node",
         '<Sequence><Script code="c += 1" _skipIf="c == 0"/><Script code="d := 1"/></Sequence>',
         [S("SUCCESS", bb={"c": 0, "d": 1})], init={"c": 0}),
    Case("skip_if_false_runs_node",
         '<Sequence><Script code="c += 1" _skipIf="c == 5"/></Sequence>',
         [S("SUCCESS", bb={"c": 1})], init={"c": 0}),
    Case("success_if_overrides_without_ticking",
         '<Script code="r := 1" _successIf="true"/>', [S("SUCCESS", bb={"r": None})]),
    Case("failure_if_overrides_without_ticking",
         '<Script code="r := 1" _failureIf="true"/>', [S("FAILURE", bb={"r": None})]),
    Case("failure_if_checked_before_success_if",
         '<AlwaysSuccess _successIf="true" _failureIf="true"/>', [S("FAILURE")]),
    Case("while_false_on_idle_node_skips_it",
         '<Sequence><Script code="r := 1" _while="false"/><Script code="q := 1"/></Sequence>',
         [S("SUCCESS", bb={"r": None, "q": 1})]),
    Case("while_turning_false_halts_running_node",
         '<Sleep msec="100" _while="go" _onHalted="h := 1"/>',
         [S("RUNNING", bb={"h": None}), S("SKIPPED", set={"go": False}, bb={"h": 1})],
         init={"go": True}),
    Case("on_success_on_failure_and_post",
         '<Sequence><AlwaysSuccess _onSuccess="s := 1" _onFailure="f := 1" _post="p := 1"/>'
         '<AlwaysFailure _onFailure="f2 := 1" _onSuccess="s2 := 1" _post="p2 := 1"/></Sequence>',
         [S("FAILURE", bb={"s": 1, "f": None, "p": 1, "f2": 1, "s2": None, "p2": 1})]),
    Case("post_not_run_while_running",
         '<Sleep msec="100" _post="p := 1"/>',
         [S("RUNNING", bb={"p": None}), S("SUCCESS", dt=0.1, bb={"p": 1})]),
    Case("success_if_ignored_once_running",
         '<Sleep msec="100" _successIf="done"/>',
         [S("RUNNING"), S("RUNNING", set={"done": True}), S("SUCCESS", dt=0.1)],
         init={"done": False}),
    Case("skip_if_on_control_skips_subtree",
         '<Sequence _skipIf="true"><Script code="r := 1"/></Sequence>',
         [S("SKIPPED", bb={"r": None})]),
    Case("on_halted_not_run_for_idle_node",
         '<ReactiveSequence><ScriptCondition code="ok"/>'
         '<AlwaysSuccess _onHalted="h := 1"/></ReactiveSequence>',
         [S("SUCCESS", bb={"h": None})], init={"ok": True}),
]

SUB = '<BehaviorTree ID="Sub">{}</BehaviorTree>'
SUBTREES = [
    Case("subtree_remaps_output_to_parent_key",
         '<SubTree ID="Sub" out="{result}"/>', [S("SUCCESS", bb={"result": "done", "out": None})],
         extra=SUB.format("<Script code=\"out := 'done'\"/>")),
    Case("subtree_blackboard_is_isolated",
         '<Sequence><SubTree ID="Sub"/><Script code="seen := 1"/></Sequence>',
         [S("SUCCESS", bb={"out": None, "seen": 1})],
         extra=SUB.format("<Script code=\"out := 'done'\"/>")),
    Case("subtree_literal_remap",
         '<SubTree ID="Sub" msg="hello" r="{res}"/>', [S("SUCCESS", bb={"res": "hello!"})],
         extra=SUB.format("<Script code=\"r := msg .. '!'\"/>")),
    Case("subtree_autoremap_shares_keys",
         '<Sequence><Script code="a := 2"/><SubTree ID="Sub" _autoremap="true"/></Sequence>',
         [S("SUCCESS", bb={"b": 6})], extra=SUB.format('<Script code="b := a * 3"/>')),
    Case("subtree_equal_sign_remap",
         '<SubTree ID="Sub" out="{=}"/>', [S("SUCCESS", bb={"out": "done"})],
         extra=SUB.format("<Script code=\"out := 'done'\"/>")),
    Case("subtree_at_key_reaches_root_blackboard",
         '<SubTree ID="A"/>', [S("SUCCESS", bb={"g": 7})],
         extra='<BehaviorTree ID="A"><SubTree ID="B"/></BehaviorTree>'
               '<BehaviorTree ID="B"><Script code="@g := 7"/></BehaviorTree>'),
    Case("subtree_instances_have_their_own_state",
         '<Sequence><SubTree ID="Sub" out="{x}"/><SubTree ID="Sub" out="{y}"/></Sequence>',
         [S("SUCCESS", bb={"x": "ran", "y": "ran"})],
         extra=SUB.format("<RunOnce><Script code=\"out := 'ran'\"/></RunOnce>")),
    Case("running_subtree_is_halted_by_parent",
         '<ReactiveSequence><ScriptCondition code="ok"/><SubTree ID="Slow"/></ReactiveSequence>',
         [S("RUNNING", bb={"h": None}), S("FAILURE", set={"ok": False}, bb={"h": 1})],
         init={"ok": True},
         extra='<BehaviorTree ID="Slow"><Sleep msec="100" _onHalted="@h := 1"/></BehaviorTree>'),
]

ALL = CONTROLS + DECORATORS + LEAVES + ATTRIBUTES + SUBTREES


def test_case_names_unique_and_enough() -> None:
    names = [c.name for c in ALL]
    assert len(names) == len(set(names))
    assert len(names) >= 60


@pytest.mark.parametrize("case", ALL, ids=[c.name for c in ALL])
def test_conformance(case: Case) -> None:
    run_case(case)
