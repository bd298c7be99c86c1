"""The TreeNodesModel of the Nav2 nodes names port types as Nav2 does, and Nav2 trees still
validate against it."""

from __future__ import annotations

import html
import re
from pathlib import Path

import pytest

import bt_manip.nav2  # noqa: F401  (registers the Nav2 nodes)
from bt_manip import cli
from bt_manip.bt.models import spec_of
from bt_manip.bt.registry import registry

ROOT = Path(__file__).resolve().parents[2]
SAMPLES = ROOT.parent / "shared" / "samples" / "nav2"


def model_text(capsys: pytest.CaptureFixture[str]) -> str:
    assert cli.main(["nodes", "--groot"]) == 0
    return capsys.readouterr().out


def port_type(model: str, node_id: str, port: str) -> str:
    block = re.search(rf'<(\w+) ID="{node_id}">(.*?)</\1>', model, re.S)
    assert block is not None, node_id
    found = re.search(rf'name="{port}" type="([^"]*)"', block.group(2))
    assert found is not None, (node_id, port)
    return html.unescape(found.group(1))


def test_ports_carry_nav2s_type_names(capsys: pytest.CaptureFixture[str]) -> None:
    model = model_text(capsys)
    expected = {
        ("ComputePathToPose", "goal"): "geometry_msgs::msg::PoseStamped",
        ("ComputePathToPose", "path"): "nav_msgs::msg::Path",
        ("ComputePathToPose", "error_code_id"): "uint16_t",
        ("FollowPath", "path"): "nav_msgs::msg::Path",
        ("ComputePathThroughPoses", "goals"): "std::vector<geometry_msgs::msg::PoseStamped>",
        ("RemovePassedGoals", "output_goals"): "std::vector<geometry_msgs::msg::PoseStamped>",
        ("SmoothPath", "smoothed_path"): "nav_msgs::msg::Path",
        ("TruncatePathLocal", "pose"): "geometry_msgs::msg::PoseStamped",
        ("GoalUpdater", "input_goal"): "geometry_msgs::msg::PoseStamped",
        ("AreErrorCodesPresent", "error_codes_to_check"): "std::vector<int>",
        ("WouldAPlannerRecoveryHelp", "error_code"): "uint16_t",
        ("IsPathValid", "max_cost"): "unsigned int",
        ("CancelControl", "server_timeout"): "std::chrono::milliseconds",
        ("Spin", "spin_dist"): "double",
        ("IsBatteryLow", "battery_topic"): "std::string",
    }
    for (node_id, port), type_name in expected.items():
        assert port_type(model, node_id, port) == type_name, (node_id, port)
    assert 'type="Nav2Path"' not in model


def test_the_model_names_do_not_change_how_the_blackboard_types_entries() -> None:
    cls = registry.get("ComputePathToPose")
    assert cls is not None
    assert cls.PORT_TYPE_NAMES.get("path") is None  # the blackboard still sees a Nav2Path
    assert spec_of(cls).ports["path"].type_name == "nav_msgs::msg::Path"


@pytest.mark.skipif(not SAMPLES.is_dir(), reason="Nav2's samples are not in ../shared")
def test_nav2s_sample_tree_validates_against_both_models(
        capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    tree = str(SAMPLES / "navigate_to_pose_w_replanning_and_recovery.xml")
    assert cli.main(["validate", tree, "--models", str(SAMPLES / "nav2_tree_nodes.xml")]) == 0
    assert ": OK" in capsys.readouterr().out
    own = tmp_path / "bt_manip_nodes.xml"
    own.write_text(model_text(capsys))
    assert cli.main(["validate", tree, "--models", str(own)]) == 0
    assert ": OK" in capsys.readouterr().out


def test_a_models_nav2_integer_types_check_literals(
        capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    # a node known only from a model (no implementation needed to validate)
    path = tmp_path / "tree.xml"
    path.write_text(
        '<root BTCPP_format="4">\n'
        '  <BehaviorTree ID="M">\n'
        '    <Sequence>\n'
        '      <CheckCode code="7" timeout="15"/>\n'
        '      <CheckCode code="-1" timeout="soon"/>\n'
        '    </Sequence>\n'
        '  </BehaviorTree>\n'
        '  <TreeNodesModel>\n'
        '    <Condition ID="CheckCode">\n'
        '      <input_port name="code" type="uint16_t"/>\n'
        '      <input_port name="timeout" type="std::chrono::milliseconds"/>\n'
        '    </Condition>\n'
        '  </TreeNodesModel>\n'
        '</root>\n')
    assert cli.main(["validate", str(path)]) == 2
    out = capsys.readouterr()
    text = out.out + out.err
    assert f"{path}:5:" in text
    assert "expected a non-negative integer, got '-1'" in text
    assert "'timeout'" in text and "soon" in text
    assert f"{path}:4:" not in text
