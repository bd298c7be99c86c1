"""bt-manip against the real BehaviorTree.CPP 4.8.2, tick by tick, on random trees.

The default run compares 1,000 seeded random trees. Environment: ``BTM_DIFF_TREES=20000`` for
more, ``BTM_DIFF_SEED`` moves the first seed, ``BTM_DIFF_DELAY=1`` also generates Delay (its
0 ms timer races in BT.CPP), ``BTM_DIFF_ALL_NODES=1`` every built-in (differential/rules.py).
Each tree is ticked on both engines with the same schedule; root status per tick, the test
leaf's start/run/halt trace and the root blackboard after each step must agree, apart from the
named rules of ``differential/rules.py``. A mismatch is shrunk and the failure message shows
the minimal XML and what each engine did. The harness itself is tested here too: the shrinker
on a seeded artificial bug, the oracle worker surviving an abort, the blackboard
normalisation, the rules' citations of the differences doc and the generator's coverage.
"""

from __future__ import annotations

import os
from collections import Counter

import pytest
from differential.btmanip_runner import make_registry, run_case
from differential.campaign import Differential, run_campaign
from differential.compare import first_divergence
from differential.generator import BUILTINS, POST_ATTRIBUTES, PRE_ATTRIBUTES, generate
from differential.oracle import Oracle, oracle_available
from differential.rules import (
    DOC,
    NOT_GENERATED,
    PENDING,
    RULES,
    active_rules,
    doc_sections,
    documented,
    enabled_builtins,
)
from differential.spec import HALT, TICK, Case, Node

from bt_manip.bt.decorators import ForceSuccess

needs_oracle = pytest.mark.skipif(not oracle_available(),
                                  reason="behaviortreepy (BehaviorTree.CPP) is not installed")

TREES = int(os.environ.get("BTM_DIFF_TREES", "1000"))
FIRST_SEED = int(os.environ.get("BTM_DIFF_SEED", "0"))
SHRUNK = 12  # mismatches shrunk for a failure message (one example per cause is shown)


@pytest.fixture(scope="module")
def oracle():
    with Oracle() as o:
        yield o


@needs_oracle
def test_random_trees_agree_with_btcpp(oracle: Oracle) -> None:
    report = run_campaign(FIRST_SEED, TREES, shrink_limit=SHRUNK, oracle=oracle)
    figures = report.figures()
    print("differential figures:", figures)
    assert report.total == TREES
    if report.mismatches:
        blocks = [f"--- cause: {cause} ({len(group)} of the {len(report.mismatches)} shrunk)\n"
                  + min(group, key=lambda m: m.shrunk.size()).report()
                  for cause, group in report.by_cause().items()]
        pytest.fail(f"{figures['mismatch']} of {TREES} trees disagree with BehaviorTree.CPP "
                    f"(figures {figures}); one shrunk example per cause:\n\n"
                    + "\n\n".join(blocks), pytrace=False)


class _BrokenInverter(ForceSuccess):
    """An artificial bug: an Inverter that passes a child's SUCCESS through (ForceSuccess)."""

    NODE_ID = "Inverter"


@needs_oracle
def test_shrinker_reduces_a_seeded_artificial_mismatch_to_the_minimal_tree(
        oracle: Oracle) -> None:
    broken = Differential(oracle, make_registry({"Inverter": _BrokenInverter}))
    enabled, _ = enabled_builtins()
    found = None
    for seed in range(500):
        case = generate(seed, enabled)
        if "Inverter" not in {n.tag for n in case.nodes()} or len(case.nodes()) < 6:
            continue
        div, o, b = broken.compare(case)
        if div is not None and div.kind == "status":
            found = case, div, o, b
            break
    assert found is not None, "no generated tree shows the artificial Inverter bug"
    case, div, o, b = found
    mismatch = broken.shrink(case, div, o, b)
    assert mismatch.shrunk.xml() == (
        '<root BTCPP_format="4" main_tree_to_execute="MainTree"><BehaviorTree ID="MainTree">'
        "<Inverter><AlwaysSuccess/></Inverter></BehaviorTree></root>")
    assert mismatch.shrunk.schedule == [TICK]
    assert mismatch.shrunk.init == []
    assert mismatch.shrunk_divergence.describe() == (
        "status differs at step 1: BT.CPP 'FAILURE', bt-manip 'SUCCESS'")
    assert "<Inverter>" in mismatch.report()


@needs_oracle
def test_a_counterfactual_rule_applies_only_when_btcpp_behaviour_explains_the_whole_run(
        oracle: Oracle) -> None:
    # BT.CPP's Precondition keeps "child running" over a halt: after the halt it ticks the
    # leaf again without counting c2 up in its `if` (bt-manip checks `if` again).
    body = Node("Precondition", {"if": "c2 += 1; c2 > 1"}, [Node("TestLeaf", {"name": "T1_RS"})])
    case = Case(body, init=[("c2", "int", 1)], schedule=[TICK, HALT, TICK, TICK])
    diff = Differential(oracle)
    div, o, b = diff.compare(case)
    assert div is not None and div.kind == "bb"
    assert diff.excluded_by(case, o, b, div).name == "precondition-flag-survives-halt"
    # The same tree under an Inverter, with an unrelated bug (the broken Inverter passes the
    # SUCCESS of tick 4 through): BT.CPP's Precondition alone does not explain the run.
    broken = Differential(oracle, make_registry({"Inverter": _BrokenInverter}))
    inverted = Case(Node("Inverter", {}, [body]), init=case.init, schedule=case.schedule)
    div, o, b = broken.compare(inverted)
    assert div is not None
    assert broken.excluded_by(inverted, o, b, div) is None


@needs_oracle
def test_oracle_worker_survives_an_abort_and_goes_on(oracle: Oracle) -> None:
    # _onHalted throws (arithmetic on a string) while the leaf runs: halting fails, and the
    # worker must keep that tree alive rather than let its destructor abort the process.
    throwing = Case(Node("Sequence", {}, [Node("TestLeaf", {"name": "T1_R",
                                                            "_onHalted": "s0 += 1"})]),
                    init=[("s0", "str", "a")], schedule=[TICK, TICK, HALT])
    result = oracle.run(throwing)
    assert [s["status"] for s in result["steps"]] == ["RUNNING", "RUNNING", None]
    assert result["steps"][2]["error"] is not None
    assert result["steps"][2]["events"] == ["T1_R:halt"]
    after = Case(Node("Sequence", {}, [Node("Script", {"code": "c0 += 1"})]),
                 init=[("c0", "int", 4)], schedule=[TICK])
    restarts = oracle.restarts
    assert oracle.run(after)["steps"][0]["bb"] == {"c0": ["n", 5.0]}
    assert oracle.restarts == restarts
    oracle.abort_worker()
    assert oracle.run(after)["steps"][0]["bb"] == {"c0": ["n", 5.0]}
    assert oracle.restarts == restarts + 1


@needs_oracle
def test_blackboard_normalisation_keeps_strings_apart_from_numbers(oracle: Oracle) -> None:
    case = Case(Node("Sequence", {}, [
        Node("Script", {"code": "i := 1; d := 2.5; s := 'x'; t := true; u := '1'"}),
        Node("SetBlackboard", {"value": "7", "output_key": "text"})]),
        init=[("c0", "int", 3), ("b0", "bool", False)], schedule=[TICK])
    expected = {"i": ["n", 1.0], "d": ["n", 2.5], "s": ["s", "x"], "t": ["n", 1.0],
                "u": ["s", "1"], "text": ["s", "7"], "c0": ["n", 3.0], "b0": ["n", 0.0]}
    btcpp = oracle.run(case)
    assert btcpp["steps"][0]["bb"] == expected
    assert first_divergence(btcpp, run_case(case)) is None


def test_comparison_reports_the_first_difference() -> None:
    base = {"load_error": None, "steps": [
        {"action": TICK, "status": "RUNNING", "error": None, "events": ["T1_R:start"],
         "bb": {"c0": ["n", 1.0]}}]}
    other = {"load_error": None, "steps": [
        {"action": TICK, "status": "RUNNING", "error": None, "events": ["T1_R:start"],
         "bb": {"c0": ["s", "1"]}}]}
    div = first_divergence(base, other)
    assert div is not None
    assert div.describe() == "bb differs at step 1: BT.CPP {'c0': 1}, bt-manip {'c0': '1'}"
    other["steps"][0]["bb"] = {"c0": ["n", 1.0]}
    other["steps"][0]["events"] = []
    assert first_divergence(base, other).kind == "trace"  # type: ignore[union-attr]


def test_generator_is_seeded_and_covers_every_builtin_and_attribute() -> None:
    assert generate(123).xml() == generate(123).xml()
    assert generate(123).xml() != generate(124).xml()
    tags: Counter[str] = Counter()
    attrs: set[str] = set()
    depths = set()
    autoremap = remapped = halted = 0
    for seed in range(1000):
        case = generate(seed)
        depths.add(case.main.depth())
        for node in case.nodes():
            tags[node.tag] += 1
            attrs.update(node.attrs)
            if node.tag == "SubTree":
                autoremap += "_autoremap" in node.attrs
                remapped += len(node.attrs) > 1 and "_autoremap" not in node.attrs
        halted += HALT in case.schedule
    assert set(BUILTINS) <= set(tags), set(BUILTINS) - set(tags)
    assert {"TestLeaf", "SubTree"} <= set(tags)
    assert set(PRE_ATTRIBUTES) | set(POST_ATTRIBUTES) <= attrs
    assert min(depths) == 2 and max(depths) >= 5
    assert autoremap > 20 and remapped > 20 and halted > 300


def test_every_exclusion_rule_cites_an_entry_of_the_differences_doc() -> None:
    sections = doc_sections()
    for rule in [*RULES, *NOT_GENERATED]:
        assert documented(rule, sections), (
            f"rule {rule.name}: '{rule.row}' is not under the heading '{rule.heading}' "
            f"in {DOC.name}")
    for rule in PENDING:
        assert (rule in active_rules()) == documented(rule, sections)


def test_a_pending_rule_counts_only_when_listed_under_not_yet_matched() -> None:
    rule = PENDING[0]
    wrapped = "- " + rule.row.replace(" ", "\n  ", 2) + ": what BT.CPP does, what bt-manip does\n"
    assert documented(rule, {"Not yet matched": wrapped})
    assert not documented(rule, {"Not yet matched": "- another difference\n"})
    assert not documented(rule, {"Time": wrapped})


def test_test_leaf_follows_its_pattern_on_bt_manip() -> None:
    case = Case(Node("Sequence", {}, [Node("TestLeaf", {"name": "T1_RRF"})]),
                schedule=[TICK, TICK, TICK, TICK, HALT])
    result = run_case(case)
    assert [s["status"] for s in result["steps"]] == ["RUNNING", "RUNNING", "FAILURE",
                                                      "RUNNING", None]
    assert [s["events"] for s in result["steps"]] == [
        ["T1_RRF:start"], ["T1_RRF:run"], ["T1_RRF:run"], ["T1_RRF:start"], ["T1_RRF:halt"]]
