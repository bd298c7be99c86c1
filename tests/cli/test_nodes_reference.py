"""``bt-manip nodes NAME`` and ``nodes --markdown``: the node reference, and docs/nodes.md kept
current."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

import bt_manip.behaviours  # registers the robot nodes
import bt_manip.nav2  # noqa: F401  (and Nav2's)
from bt_manip.bt.reference import NO_UNIT, carries_number, node_reference, unit_of
from bt_manip.bt.registry import registry
from bt_manip.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]


def run_verb(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    code: int = args.func(args)
    return code


def test_nodes_name_prints_the_contract_and_ports(capsys: pytest.CaptureFixture[str]) -> None:
    assert run_verb(["nodes", "MoveToPose"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("MoveToPose: Action, bt-manip (bt_manip.behaviours.arm)")
    for status in ("RUNNING", "SUCCESS", "FAILURE", "Halted"):
        assert status in out
    assert "  position: input, std::vector<double>, default \"\", unit m" in out
    assert "  approach: input, double, default 0.0, unit m" in out
    assert "accepts: >= 0" in out
    assert "accepts: one of joint, line" in out
    assert 'Give exactly one of position | object (checked when the tree is loaded).' in out


def test_nodes_name_states_units_that_were_missing(capsys: pytest.CaptureFixture[str]) -> None:
    assert run_verb(["nodes", "Navigate"]) == 0
    assert "  goal: input, std::string, required, unit m, rad" in capsys.readouterr().out
    assert run_verb(["nodes", "MoveJoints"]) == 0
    out = capsys.readouterr().out
    assert "  targets: input, std::vector<double>, default \"\", unit deg or rad" in out
    assert "  units: input, std::string, default deg" in out


@pytest.mark.parametrize(("name", "origin"), [
    ("Sequence", "BT.CPP built-in"), ("RecoveryNode", "Nav2"), ("Lift", "bt-manip"),
    ("PyTreesTimer", "py_trees"),
])
def test_nodes_name_says_where_a_node_comes_from(
        name: str, origin: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert run_verb(["nodes", name]) == 0
    assert capsys.readouterr().out.split("\n")[0].split(", ")[1].startswith(origin)


def test_unknown_node_exits_2_with_the_closest_names(capsys: pytest.CaptureFixture[str]) -> None:
    assert run_verb(["nodes", "MoveToPos"]) == 2
    err = capsys.readouterr().err
    assert "unknown node 'MoveToPos' (did you mean 'MoveToPose'" in err


def test_a_name_in_another_case_is_found(capsys: pytest.CaptureFixture[str]) -> None:
    assert run_verb(["nodes", "movetopose"]) == 0
    assert capsys.readouterr().out.startswith("MoveToPose:")


def test_every_number_of_the_shipped_robot_and_nav2_nodes_has_a_unit() -> None:
    missing = []
    for cls in registry.classes():
        ref = node_reference(cls, registry)
        if ref.origin not in ("bt-manip", "Nav2"):
            continue
        missing += [f"{ref.node_id}.{p.name}" for p in ref.ports
                    if carries_number(p.type_name) and not p.unit]
    assert missing == []


def test_units_are_read_from_the_descriptions() -> None:
    assert unit_of("how far to reverse (m)") == "m"
    assert unit_of("target pose of the object's centre x;y;z;yaw (m, rad; world)") == "m, rad"
    assert unit_of("sim seconds allowed") == "s"
    assert unit_of("longest wait (sim s) for a tilted object to come to rest") == "s"
    assert unit_of("fraction of each joint's velocity limit, 0..1") == NO_UNIT
    assert unit_of("robot name in the world", is_number=False) == ""


def test_docs_nodes_md_is_current() -> None:
    """docs/nodes.md is what `bt-manip nodes --markdown` prints (regenerate it with that
    command when a node changes)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    out = subprocess.run([sys.executable, "-m", "bt_manip", "nodes", "--markdown"], cwd=ROOT,
                         env=env, capture_output=True, text=True, check=True).stdout
    assert out == (ROOT / "docs" / "nodes.md").read_text(encoding="utf-8")


def test_markdown_holds_every_node(capsys: pytest.CaptureFixture[str]) -> None:
    assert run_verb(["nodes", "--markdown"]) == 0
    out = capsys.readouterr().out
    for node_id in ("MoveToPose", "Navigate", "Sequence", "RecoveryNode"):
        assert f"\n### {node_id}\n" in out
    assert "| `approach` | input | `double` | m | `0.0` | >= 0 |" in out
