"""The shared sample files, handled as BehaviorTree.CPP 4 would."""

from __future__ import annotations

from pathlib import Path

from bt_manip.bt import load_tree, registry, validate, validate_file
from bt_manip.bt.registry import NodeRegistry

SAMPLES = Path(__file__).resolve().parents[2].parent / "shared" / "samples"
"""The shared sample files, beside the project's root (``../shared/samples``)."""
BTCPP = SAMPLES / "btcpp"
NAV2_TREE = SAMPLES / "nav2" / "navigate_to_pose_w_replanning_and_recovery.xml"
NAV2_MODEL = SAMPLES / "nav2" / "nav2_tree_nodes.xml"


def lines_and_messages(path: Path, models: list[str] | None = None) -> list[tuple[int, str]]:
    return [(p.line or 0, p.message) for p in validate_file(str(path), models)]


def test_corpus1_runs_to_success() -> None:
    tree = load_tree(str(BTCPP / "corpus1.xml"))
    assert tree.tick().name == "SUCCESS"


def test_corpus2_timeout_ms_is_not_a_v4_port() -> None:
    out = lines_and_messages(BTCPP / "corpus2.xml")
    assert [line for line, _ in out] == [5, 5]
    assert out[0][1].startswith("'timeout_ms' is not a port of Timeout")
    assert "msec" in out[0][1]
    assert out[1][1].startswith("Timeout is missing its required port 'msec'")


def test_corpus3_setblackboard_ports_and_undefined_subtree() -> None:
    out = lines_and_messages(BTCPP / "corpus3.xml")
    assert [line for line, _ in out] == [4, 4, 5]
    assert out[0][1].startswith("'key' is not a port of SetBlackboard")
    assert out[1][1].startswith("SetBlackboard is missing its required port 'output_key'")
    assert out[2][1].startswith("SubTree 'SubTree' is not defined")


def test_corpus4_decorators_without_child() -> None:
    out = lines_and_messages(BTCPP / "corpus4.xml")
    assert out == [(5, "ForceSuccess must have exactly 1 child, found 0"),
                   (6, "ForceFailure must have exactly 1 child, found 0")]


def builtins_only() -> NodeRegistry:
    """A registry of BT.CPP's built-in nodes only: Nav2's nodes known from a model alone
    (bt-manip's own Nav2 nodes, bt_manip.nav2, are tested in tests/nav2)."""
    reg = NodeRegistry()
    for cls in registry.classes(builtin=True):
        reg.register(cls, builtin=True)
    return reg


def test_nav2_reports_exactly_undeclared_ids_and_ports() -> None:
    # Checked by hand against nav2_tree_nodes.xml: the model does not declare the nodes
    # WouldAPlannerRecoveryHelp (lines 14, 30), WouldAControllerRecoveryHelp (22, 29) and
    # GoalUpdated (33), nor the port error_code_id of ComputePathToPose (12) and FollowPath (20).
    # Everything else is declared or built in (Sequence, Fallback, ReactiveFallback).
    problems, warnings = validate(str(NAV2_TREE), [str(NAV2_MODEL)], reg=builtins_only())
    found = set()
    for p in problems:
        assert p.file == str(NAV2_TREE)
        if p.message.startswith("unknown node"):
            found.add((p.line, "node", p.message.split("'")[1]))
        else:
            assert p.message.startswith("'error_code_id' is not a port of"), p.message
            found.add((p.line, "port", p.message.split(" of ")[1].split(" ")[0] + ".error_code_id"))
    assert len(problems) == 7
    assert found == {
        (12, "port", "ComputePathToPose.error_code_id"),
        (14, "node", "WouldAPlannerRecoveryHelp"),
        (20, "port", "FollowPath.error_code_id"),
        (22, "node", "WouldAControllerRecoveryHelp"),
        (29, "node", "WouldAControllerRecoveryHelp"),
        (30, "node", "WouldAPlannerRecoveryHelp"),
        (33, "node", "GoalUpdated"),
    }
    assert [w.line for w in warnings] == [6]
    assert "BTCPP_format" in warnings[0].message


def test_nav2_without_model_reports_every_nav2_node() -> None:
    problems, _ = validate(str(NAV2_TREE), reg=builtins_only())
    unknown = {p.message.split("'")[1] for p in problems}
    assert {"RecoveryNode", "PipelineSequence", "RateController", "ComputePathToPose",
            "ClearEntireCostmap", "FollowPath", "RoundRobin", "Spin", "Wait", "BackUp",
            "GoalUpdated"} <= unknown
