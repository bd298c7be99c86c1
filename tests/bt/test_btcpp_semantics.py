"""BehaviorTree.CPP 4.8.2 semantics of the BT core, each checked on a minimal tree against the
real engine (``behaviortreepy``) and pinned on bt-manip."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from btcpp_reference import btcpp, document, run_btcpp, run_ours

from bt_manip.bt import NodeStatus, validate_file
from bt_manip.errors import InputError
from bt_manip.run.runner import Runner, RunOptions


def same(body: str, ticks: int, init: dict[str, Any] | None = None,
         exactly_once: bool = False) -> tuple[list[str], dict[str, str], dict[str, Any]]:
    """Run on both engines; the statuses must agree. Returns them with both blackboards."""
    theirs, their_bb = run_btcpp(body, ticks, init, exactly_once)
    ours = run_ours(body, ticks, init, exactly_once)
    assert ours.statuses == theirs, (ours.statuses, theirs)
    return theirs, their_bb, ours.tree.blackboard.as_dict()


WAKE_UP = ('<ReactiveSequence><Script code="c += 1"/><SequenceWithMemory><AlwaysSuccess/>'
           "<AlwaysSuccess/></SequenceWithMemory></ReactiveSequence>")


def test_tick_re_ticks_the_root_while_a_wake_up_is_pending() -> None:
    statuses, theirs, ours = same(WAKE_UP, 1, {"c": 0})
    assert statuses == ["SUCCESS"]
    assert theirs["c"] == "2" and ours["c"] == 2


def test_tick_exactly_once_ignores_the_wake_up() -> None:
    statuses, theirs, ours = same(WAKE_UP, 2, {"c": 0}, exactly_once=True)
    assert statuses == ["RUNNING", "SUCCESS"]
    assert theirs["c"] == "2" and ours["c"] == 2


@pytest.mark.parametrize(("body", "counter"), [
    ('<Repeat num_cycles="3"><Script code="r += 1"/></Repeat>', 3),
    ('<RetryUntilSuccessful num_attempts="3"><ScriptCondition code="r += 1; false"/>'
     "</RetryUntilSuccessful>", 3),
    ('<AsyncSequence><Script code="r += 1"/><Script code="r += 1"/><Script code="r += 1"/>'
     "</AsyncSequence>", 3),
    ('<AsyncFallback><ScriptCondition code="r += 1; false"/><ScriptCondition code="r += 1; false"/>'
     '<Script code="r += 1"/></AsyncFallback>', 3),
])
def test_looping_nodes_yield_between_children(body: str, counter: int) -> None:
    tree = f'<ReactiveSequence><Script code="c += 1"/>{body}</ReactiveSequence>'
    _, theirs, ours = same(tree, 1, {"c": 0, "r": 0})
    assert theirs["r"] == str(counter) and ours["r"] == counter
    assert theirs["c"] == str(counter) and ours["c"] == counter  # re-ticked from the root


def test_condition_left_alone_by_while_do_else_keeps_its_status() -> None:
    # The condition (a stateful Sleep) succeeded; while the branch runs it is not reset, so the
    # next tick returns SUCCESS again without starting it (it would now wait 1000 ms).
    body = ('<Sequence><Script code="m = 0"/><WhileDoElse><Sleep msec="{m}" _onSuccess="c += 1"/>'
            '<Sequence><Script code="m = 1000"/><Sleep msec="100000"/></Sequence></WhileDoElse>'
            "</Sequence>")
    statuses, theirs, ours = same(body, 2, {"c": 0})
    assert statuses == ["RUNNING", "RUNNING"]
    assert theirs["c"] == "2" and ours["c"] == 2


def test_condition_of_if_then_else_is_not_reset_after_it_failed() -> None:
    body = ('<Sequence><Script code="n += 1"/><ForceSuccess><IfThenElse>'
            '<Sleep msec="0" _failureIf="n == 1" _onSuccess="s += 1" _onFailure="f += 1"/>'
            "<AlwaysSuccess/></IfThenElse></ForceSuccess></Sequence>")
    statuses, theirs, ours = same(body, 2, {"n": 0, "s": 0, "f": 0})
    assert statuses == ["SUCCESS", "SUCCESS"]
    assert (theirs["f"], theirs["s"]) == ("2", "0")
    assert (ours["f"], ours["s"]) == (2, 0)


def test_switch_whose_child_is_skipped_stays_idle_and_is_not_halted() -> None:
    body = ('<Sequence><Switch2 variable="1" case_1="1" case_2="2" _onHalted="h := 1">'
            '<AlwaysSuccess _skipIf="true"/><AlwaysSuccess/><AlwaysSuccess/></Switch2>'
            '<Script code="done := 1"/></Sequence>')
    statuses, theirs, ours = same(body, 2)
    assert statuses == ["SUCCESS", "SUCCESS"]
    assert "h" not in theirs and "h" not in ours


def test_arithmetic_on_a_string_entry_is_an_error() -> None:
    statuses, _, ours = same('<Script code="s += 1"/>', 1, {"s": "2"})
    assert statuses == ["ERROR"]
    assert ours["s"] == "2"


@pytest.mark.parametrize(("code", "init", "expected"), [
    ('s += "x"', {"s": "2"}, "2x"),
    ('i = "5"', {"i": 2}, 5),
    ("i := 3.0", {"i": 2}, 3),
    ("x := 1 + 2", {}, 3),
])
def test_assignments_keep_the_entry_type(code: str, init: dict[str, Any], expected: Any) -> None:
    _, _, ours = same(f'<Script code="{code.replace(chr(34), "&quot;")}"/>', 1, init)
    assert ours[next(iter(init), "x")] == expected


@pytest.mark.parametrize(("code", "init"), [
    ("s = 5", {"s": "2"}),
    ("i = 3.5", {"i": 2}),
    ('i = "abc"', {"i": 2}),
])
def test_assignments_that_change_an_entry_type_are_errors(code: str,
                                                          init: dict[str, Any]) -> None:
    statuses, _, _ = same(f'<Script code="{code.replace(chr(34), "&quot;")}"/>', 1, init)
    assert statuses == ["ERROR"]


def test_set_blackboard_text_over_an_int_entry_is_converted() -> None:
    _, theirs, ours = same('<SetBlackboard value="5" output_key="x"/>', 1, {"x": 3})
    assert theirs["x"] == "5"
    assert ours["x"] == 5 and type(ours["x"]) is int


def test_set_blackboard_text_that_cannot_be_converted_is_an_error() -> None:
    statuses, _, _ = same('<SetBlackboard value="abc" output_key="x"/>', 1, {"x": 3})
    assert statuses == ["ERROR"]


def test_port_creates_its_entry_with_the_port_type() -> None:
    # Sleep's msec port creates entry m as a number: text assigned to it must be a number.
    body = '<Sequence><Script code="m = &quot;abc&quot;"/><Sleep msec="{m}"/></Sequence>'
    statuses, _, _ = same(body, 1)
    assert statuses == ["ERROR"]
    ok = '<Sequence><Script code="m = &quot;0&quot;"/><Sleep msec="{m}"/></Sequence>'
    statuses, _, ours = same(ok, 1)
    assert statuses == ["SUCCESS"] and ours["m"] == 0


def test_set_blackboard_from_an_entry_without_value_fails() -> None:
    statuses, _, _ = same('<SetBlackboard value="{y}" output_key="x"/>', 1)
    assert statuses == ["FAILURE"]


def test_loop_int_runs_the_child_once_per_item() -> None:
    body = '<LoopInt queue="1;2;3" value="{v}"><Script code="s += v"/></LoopInt>'
    statuses, theirs, ours = same(body, 5, {"s": 0})
    assert statuses == ["RUNNING", "RUNNING", "RUNNING", "SUCCESS", "RUNNING"]
    assert theirs["s"] == "7" and ours["s"] == 7


def test_was_entry_updated_sees_each_write_once() -> None:
    check = ('<ForceSuccess><WasEntryUpdated entry="{e}" _onSuccess="a += 1" '
             '_onFailure="b += 1"/></ForceSuccess>')
    # each node sees the write of each tick once: the first time it looks, not the second
    body = (f'<Sequence><Script code="e := 1"/>{check}{check}'
            f'<Repeat num_cycles="2">{check}</Repeat></Sequence>')
    _, theirs, ours = same(body, 2, {"a": 0, "b": 0})
    assert (theirs["a"], theirs["b"]) == ("6", "2")
    assert (ours["a"], ours["b"]) == (6, 2)


@pytest.mark.parametrize(("decorator", "expected"), [
    ("SkipUnlessUpdated", ["SUCCESS", "SKIPPED"]), ("WaitValueUpdate", ["SUCCESS", "RUNNING"])])
def test_entry_updated_decorators(decorator: str, expected: list[str]) -> None:
    body = f'<{decorator} entry="e"><Script code="n += 1"/></{decorator}>'
    statuses, theirs, ours = same(body, 2, {"e": 1, "n": 0})
    assert statuses == expected
    assert theirs["n"] == "1" and ours["n"] == 1


def test_root_that_is_skipped_ends_the_run_with_status_skipped() -> None:
    statuses, _, _ = same('<Sequence><AlwaysSuccess _skipIf="true"/></Sequence>', 1)
    assert statuses == ["SKIPPED"]
    tree = run_ours('<Sequence><AlwaysSuccess _skipIf="true"/></Sequence>', 0).tree
    report = Runner(tree, options=RunOptions(max_ticks=50)).run()
    assert (report.status, report.ticks, report.exit_code) == ("SKIPPED", 1, 1)
    assert tree.bt_status is NodeStatus.SKIPPED


def test_a_timer_that_fired_between_ticks_wakes_the_tree_up() -> None:
    # BT.CPP's Sleep timer emits the wake-up signal when it fires; on the sim clock it fires
    # at the start of the tick at which its time is up, so that tick re-ticks the root once
    # the second Sleep has started.
    body = ('<ReactiveSequence><Script code="c += 1"/><Sequence><Sleep msec="100"/>'
            '<Sleep msec="100"/></Sequence></ReactiveSequence>')
    tree = run_ours(body, 0, {"c": 0}).tree
    clock = tree.context.clock
    assert tree.tick() is NodeStatus.RUNNING and tree.blackboard.get("c") == 1
    clock.advance(0.05)
    assert tree.tick() is NodeStatus.RUNNING and tree.blackboard.get("c") == 2
    clock.advance(0.05)
    assert tree.tick() is NodeStatus.RUNNING and tree.blackboard.get("c") == 4
    clock.advance(0.1)
    assert tree.tick() is NodeStatus.SUCCESS and tree.blackboard.get("c") == 5


def test_timeout_halts_its_child_when_its_timer_fires() -> None:
    body = '<Timeout msec="100"><Sleep msec="1000" _onHalted="h := 1"/></Timeout>'
    tree = run_ours(body, 0).tree
    assert tree.tick() is NodeStatus.RUNNING
    tree.context.clock.advance(0.1)
    assert tree.tick() is NodeStatus.FAILURE
    assert tree.blackboard.get("h") == 1
    assert not tree.context.timers


def test_a_port_of_another_scalar_type_on_a_typed_entry_is_refused_at_load() -> None:
    body = ('<Switch2 variable="{c}" case_1="1" case_2="2"><AlwaysSuccess/><AlwaysSuccess/>'
            "<AlwaysSuccess/></Switch2>")
    b = btcpp()
    factory = b.BehaviorTreeFactory()
    factory.register_behavior_tree_from_text(document(body))
    bb = b.Blackboard.create()
    bb.set_int("c", 1)
    with pytest.raises(Exception, match="was initially created with type"):
        factory.create_tree("MainTree", bb)
    with pytest.raises(InputError) as error:
        run_ours(body, 1, {"c": 1})
    assert str(error.value) == (
        "<string>:1: Switch2 port 'variable': entry [c] was created with type [int] and this "
        "port uses type [std::string]; BT.CPP refuses such a tree: use one type for the entry")
    assert run_ours(body, 1, {"c": "1"}).statuses == ["SUCCESS"]  # a text entry is fine


def test_set_blackboard_cannot_change_the_type_of_a_typed_entry() -> None:
    statuses, _, _ = same('<SetBlackboard value="{b}" output_key="c"/>', 1, {"b": True, "c": 1})
    assert statuses == ["ERROR"]
    statuses, theirs, ours = same('<SetBlackboard value="{b}" output_key="c"/>', 1,
                                  {"b": 7, "c": 1})
    assert statuses == ["SUCCESS"] and theirs["c"] == "7" and ours["c"] == 7


def test_reactive_sequence_with_two_async_sequences_is_refused_at_load() -> None:
    two = "<AsyncSequence><AlwaysSuccess/></AsyncSequence>" * 2
    body = f"<ReactiveSequence>{two}</ReactiveSequence>"
    b = btcpp()
    with pytest.raises(Exception, match="cannot have more than one async child"):
        b.BehaviorTreeFactory().register_behavior_tree_from_text(document(body))
    with pytest.raises(InputError) as error:
        run_ours(body, 1)
    assert str(error.value) == (
        "<string>:1: a ReactiveSequence cannot have more than one AsyncSequence child (found 2, "
        "as BehaviorTree.CPP requires); wrap them in one Sequence")
    assert run_ours(f"<ReactiveFallback>{two}</ReactiveFallback>", 1).statuses == ["SUCCESS"]


@pytest.mark.parametrize(("code", "text"), [
    ('x := 1 + 2; s := x .. ""', "3.000000"), ('s := 2.5 .. ""', "2.500000"),
    ('b := true; s := b .. ""', "1"), ('s := 3 .. ""', "3")])
def test_concatenation_writes_numbers_as_btcpp(code: str, text: str) -> None:
    _, theirs, ours = same(f'<Script code="{code.replace(chr(34), "&quot;")}"/>', 1)
    assert theirs["s"] == text and ours["s"] == text


def test_set_blackboard_copies_any_value_into_a_text_entry() -> None:
    body = ('<Sequence><SetBlackboard value="{b}" output_key="s"/>'
            '<Script code="r := s .. &quot;x&quot;"/></Sequence>')
    _, theirs, ours = same(body, 1, {"b": 5, "s": "t"})
    assert theirs["r"] == "5x" and ours["r"] == "5x"


@pytest.mark.parametrize(("variable", "expected"), [
    ("2abc", 1), (" +2.0e0", 1), ("0x2", 1), ("-0x2", 2), ("a2", 3), ("1.99999999", 1)])
def test_switch_compares_cases_as_btcpp(variable: str, expected: int) -> None:
    body = (f'<Switch2 variable="{variable}" case_1="2" case_2="-2"><Script code="r := 1"/>'
            '<Script code="r := 2"/><Script code="r := 3"/></Switch2>')
    _, theirs, ours = same(body, 1)
    assert theirs["r"] == str(expected) and ours["r"] == expected


def test_an_integer_assigned_to_a_double_entry_keeps_it_double() -> None:
    body = ('<Sequence><Script code="n := 0.5"/><Script code="n := 6"/>'
            '<Script code="n := 0.5"/></Sequence>')
    statuses, _, ours = same(body, 1)
    assert statuses == ["SUCCESS"] and ours["n"] == 0.5


def test_run_once_reads_then_skip_as_true_when_its_entry_has_no_value() -> None:
    statuses, _, _ = same('<RunOnce then_skip="{b}"><AlwaysSuccess/></RunOnce>', 2)
    assert statuses == ["SUCCESS", "SKIPPED"]
    statuses, _, _ = same('<RunOnce then_skip="{b}"><AlwaysSuccess/></RunOnce>', 2, {"b": "a"})
    assert statuses == ["SUCCESS", "SKIPPED"]  # nor when it holds text that is no bool
    statuses, _, _ = same('<Parallel success_count="{k}"><AlwaysSuccess/></Parallel>', 1)
    assert statuses == ["ERROR"]  # other ports without a value are errors


def test_validate_reports_ports_of_two_types_on_one_entry(tmp_path: Path) -> None:
    tree = tmp_path / "conflict.xml"
    tree.write_text(document('<Sequence><Sleep msec="{c}"/>\n<Switch2 variable="{c}" '
                             'case_1="1" case_2="2"><AlwaysSuccess/><AlwaysSuccess/>'
                             "<AlwaysSuccess/></Switch2></Sequence>"))
    assert [str(p) for p in validate_file(str(tree))] == [
        f"{tree}:2: Switch2 port 'variable': entry [c] was created with type [unsigned int] "
        "and this port uses type [std::string]; BT.CPP refuses such a tree: use one type for "
        "the entry"]


@pytest.mark.parametrize(("code", "status"), [("b = 0.5", "ERROR"), ("b = 1.0", "SUCCESS"),
                                              ("b += 1", "SUCCESS")])
def test_a_real_assigned_to_a_bool_entry_must_be_integral(code: str, status: str) -> None:
    statuses, _, ours = same(f'<Script code="{code}"/>', 1, {"b": False})
    assert statuses == [status]
    if status == "SUCCESS":
        assert ours["b"] == 1 and type(ours["b"]) is int
