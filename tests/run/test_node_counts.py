"""The run report's per-node counts: how often each node was ticked in the run, what its ticks
returned, and how often it was halted while RUNNING (the counts a bench sums for coverage)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bt_manip.cli import main
from bt_manip.episode import run_tree

ROOT = Path(__file__).resolve().parents[2]


def _counts(report: object) -> dict[str, dict[str, int]]:
    return {n.path: n.counts for n in report.nodes if n.counts}  # type: ignore[attr-defined]


def test_each_node_counts_its_ticks_results_and_subtree_instances_apart() -> None:
    report = run_tree(ROOT / "trees" / "builtins_demo.xml", tick_hz=1000)
    counts = _counts(report)
    lucky = counts["demo/RetryUntilSuccessful/third_time_lucky"]
    assert lucky == {"ticks": 3, "success": 1, "failure": 2, "skipped": 0, "halted": 0}
    assert counts["demo/Repeat/Script"]["success"] == 4
    assert counts["demo/Fallback/plan_a"] == {"ticks": 1, "success": 0, "failure": 1,
                                               "skipped": 0, "halted": 0}
    # the SubTree and the node inside it, by their paths
    assert counts["demo/Fallback/Report/report"]["success"] == 1
    # the root runs at every tick, and again within a tick for a wake-up signal
    assert counts["demo"]["ticks"] >= report.ticks and counts["demo"]["success"] == 1


def test_halts_skips_and_nodes_never_ticked_are_counted(tmp_path: Path) -> None:
    tree = tmp_path / "halts.xml"
    tree.write_text("""<root BTCPP_format="4"><BehaviorTree ID="Main">
      <Sequence name="main">
        <Script name="init" code="go := false"/>
        <AlwaysSuccess name="skipped" _skipIf="!go"/>
        <Timeout name="limit" msec="50"><Sleep name="long" msec="5000"/></Timeout>
        <AlwaysSuccess name="never"/>
      </Sequence>
    </BehaviorTree></root>""")
    report = run_tree(tree, tick_hz=100)
    assert report.status == "FAILURE"
    counts = {n.path: n.counts for n in report.nodes}
    assert counts["main/skipped"] == {"ticks": 1, "success": 0, "failure": 0, "skipped": 1,
                                      "halted": 0}
    long = counts["main/limit/long"]
    assert long is not None and long["halted"] == 1 and long["success"] == 0
    assert long["ticks"] >= 2
    assert counts["main/limit"]["failure"] == 1
    assert counts["main/never"] == {"ticks": 0, "success": 0, "failure": 0, "skipped": 0,
                                    "halted": 0}


def test_a_run_ended_by_its_budget_counts_the_halt_of_what_was_running(tmp_path: Path) -> None:
    tree = tmp_path / "budget.xml"
    tree.write_text('<root BTCPP_format="4"><BehaviorTree ID="Main">'
                    '<Sleep name="wait" msec="100000"/></BehaviorTree></root>')
    out = tmp_path / "report.json"
    assert main(["run", str(tree), "--max-ticks", "3", "--quiet", "--report", str(out)]) == 1
    nodes = json.loads(out.read_text())["nodes"]
    assert nodes[0]["counts"] == {"ticks": 3, "success": 0, "failure": 0, "skipped": 0,
                                  "halted": 1}
    jsonschema = pytest.importorskip("jsonschema")
    schema = json.loads((ROOT / "docs" / "schemas" / "run-report.schema.json").read_text())
    jsonschema.Draft202012Validator(schema).validate(json.loads(out.read_text()))
