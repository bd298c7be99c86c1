"""The deliberate differences from BehaviorTree.CPP 4.8.2 listed in docs/btcpp-differences.md:
where BT.CPP throws an internal error or breaks the halting contract, bt-manip's behaviour is
pinned here (and BT.CPP's is checked, so the list stays true)."""

from __future__ import annotations

from btcpp_reference import btcpp, document, run_btcpp, run_ours

from bt_manip.bt import NodeStatus


def test_if_then_else_with_a_skipped_condition_is_skipped() -> None:
    body = '<IfThenElse><AlwaysSuccess _skipIf="true"/><AlwaysSuccess/></IfThenElse>'
    assert run_btcpp(body, 1)[0] == ["ERROR"]  # "Something unexpected happened in IfThenElseNode"
    assert run_ours(body, 2).statuses == ["SKIPPED", "SKIPPED"]


def test_while_do_else_with_a_skipped_condition_is_skipped() -> None:
    body = '<WhileDoElse><AlwaysSuccess _skipIf="true"/><AlwaysSuccess/></WhileDoElse>'
    assert run_btcpp(body, 1)[0] == ["ERROR"]  # it returns IDLE to its parent
    assert run_ours(body, 2).statuses == ["SKIPPED", "SKIPPED"]


def precondition_after_halt(tick: object, set_bool: object) -> list[str]:
    statuses = []
    for go, ok in ((True, True), (False, True), (True, False)):
        set_bool("go", go)  # type: ignore[operator]
        set_bool("ok", ok)  # type: ignore[operator]
        statuses.append(tick().name)  # type: ignore[operator]
    return statuses


PRECONDITION = ('<ReactiveSequence><ScriptCondition code="go"/><Precondition if="ok">'
                '<Sleep msec="100000"/></Precondition></ReactiveSequence>')


def test_precondition_checks_its_condition_again_after_a_halt() -> None:
    b = btcpp()
    factory = b.BehaviorTreeFactory()
    factory.register_behavior_tree_from_text(document(PRECONDITION))
    bb = b.Blackboard.create()
    bb.set_bool("go", True)
    bb.set_bool("ok", True)
    tree = factory.create_tree("MainTree", bb)
    # BT.CPP keeps its "child running" flag over the halt and ticks the child without checking
    assert precondition_after_halt(tree.tick_once, bb.set_bool) == ["RUNNING", "FAILURE",
                                                                     "RUNNING"]
    tree.halt_tree()
    ours = run_ours(PRECONDITION, 0, {"go": True, "ok": True}).tree
    statuses = precondition_after_halt(ours.tick, ours.blackboard.set)
    assert statuses == ["RUNNING", "FAILURE", "FAILURE"]


def test_skip_unless_updated_halts_its_running_child() -> None:
    body = ('<ReactiveSequence><ScriptCondition code="go"/><SkipUnlessUpdated entry="e">'
            '<Sleep msec="100000" _onHalted="h := 1"/></SkipUnlessUpdated></ReactiveSequence>')
    ours = run_ours(body, 0, {"go": True, "e": 1}).tree
    assert ours.tick() is NodeStatus.RUNNING
    ours.blackboard.set("go", False)
    assert ours.tick() is NodeStatus.FAILURE
    assert ours.blackboard.get("h") == 1  # BT.CPP leaves the Sleep RUNNING and never halts it
    sleep = ours.nodes()[-1]
    assert sleep.bt_status is NodeStatus.IDLE


def test_set_blackboard_into_a_text_entry_stores_the_text() -> None:
    body = ('<Sequence><SetBlackboard value="b" output_key="s"/>'
            '<Script code="r := s .. &quot;x&quot;"/></Sequence>')
    assert run_btcpp(body, 1, {"s": "a"})[0] == ["ERROR"]  # "not initialized"
    ours = run_ours(body, 1, {"s": "a"})
    assert ours.statuses == ["SUCCESS"]
    assert ours.tree.blackboard.get("r") == "bx"
