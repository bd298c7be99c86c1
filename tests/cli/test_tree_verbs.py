"""The validate, show and nodes verbs (bt_manip.cli.tree), through their parser and through
bt_manip.cli.main."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import ClassVar

import pytest
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.bt import ActionNode, ConditionNode, NodeStatus, TreeContext, load_tree, registry
from bt_manip.bt.display import render_status
from bt_manip.bt.documents import Document, read_model_file
from bt_manip.cli import build_parser
from bt_manip.clock import ManualClock

DEMO = Path(__file__).resolve().parents[2] / "trees" / "builtins_demo.xml"
SAMPLES = Path(__file__).resolve().parents[2].parent / "shared" / "samples"
"""The shared sample files, beside the project's root (``../shared/samples``)."""


Ports = dict[str, PortInformation]


class GraspCheck(ConditionNode):
    """Test condition: is the object held."""

    INPUT_PORTS: ClassVar[Ports] = {"object": PortInformation(str, description="object name"),
                   "force": PortInformation(float, required=False, default_value=2.5,
                                            description="minimum force [N]")}

    def update(self) -> Status:
        return Status.SUCCESS


class MoveTo(ActionNode):
    """Test action with an output port."""

    INPUT_PORTS: ClassVar[Ports] = {"goal": PortInformation(list[float], description="x;y;yaw")}
    OUTPUT_PORTS: ClassVar[Ports] = {
        "reached": PortInformation(bool, required=False, description="arrived")}

    def update(self) -> Status:
        self.set_output("reached", True)
        return Status.SUCCESS


@pytest.fixture
def custom_nodes() -> Iterator[None]:
    registry.register(GraspCheck)
    registry.register(MoveTo)
    yield
    registry.unregister("GraspCheck")
    registry.unregister("MoveTo")


def run_verb(argv: list[str]) -> int:
    args = build_parser(argv[:1]).parse_args(argv)
    return int(args.func(args))


def test_validate_ok_and_all_problems(capsys: pytest.CaptureFixture[str]) -> None:
    assert run_verb(["validate", str(DEMO)]) == 0
    assert capsys.readouterr().out.strip() == f"{DEMO}: OK"
    assert run_verb(["validate", str(SAMPLES / "btcpp/corpus3.xml"),
                     str(SAMPLES / "btcpp/corpus4.xml")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert [line.split(":")[1] for line in err] == ["4", "4", "5", "5", "6"]


def test_validate_nav2_with_models(capsys: pytest.CaptureFixture[str]) -> None:
    tree = SAMPLES / "nav2/navigate_to_pose_w_replanning_and_recovery.xml"
    # bt-manip's own Nav2 nodes (bt_manip.nav2) declare what Nav2's older model lacks
    code = run_verb(["validate", str(tree), "--models", str(SAMPLES / "nav2/nav2_tree_nodes.xml")])
    assert code == 0
    lines = capsys.readouterr().err.strip().splitlines()
    assert [line for line in lines if ": warning:" not in line] == []


def test_show_text_and_dot(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    dot = tmp_path / "tree.dot"
    assert run_verb(["show", str(DEMO), "--dot", str(dot)]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0] == "BehaviorTree Demo"
    assert "    RetryUntilSuccessful (num_attempts=5)" in out
    assert "SubTree Report (_autoremap=true)" in out
    text = dot.read_text()
    assert text.startswith('digraph "Demo" {') and text.count("->") == 11


def test_show_model_only_nodes(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    tree = tmp_path / "t.xml"
    tree.write_text('<root BTCPP_format="4"><BehaviorTree ID="T"><RecoveryNode '
                    'number_of_retries="2"><Spin spin_dist="1"/><Wait wait_duration="1"/>'
                    "</RecoveryNode></BehaviorTree></root>")
    assert run_verb(["show", str(tree), "--models", str(SAMPLES / "nav2/nav2_tree_nodes.xml")]) == 0
    assert "RecoveryNode (number_of_retries=2)" in capsys.readouterr().out


def test_nodes_groot_loads_back_as_model(custom_nodes: None,
                                         capsys: pytest.CaptureFixture[str],
                                         tmp_path: Path) -> None:
    assert run_verb(["nodes", "--groot"]) == 0
    out = capsys.readouterr().out
    path = tmp_path / "model.xml"
    path.write_text(out)
    doc = Document(str(path))
    read_model_file(str(path), doc)
    assert doc.problems == []
    assert "Sequence" not in doc.models
    grasp = doc.models["GraspCheck"]
    assert grasp.kind == "Condition"
    assert {p.name: (p.direction, p.type_name, p.default) for p in grasp.ports.values()} == {
        "object": ("input", "std::string", None), "force": ("input", "double", "2.5")}
    move = doc.models["MoveTo"]
    assert move.kind == "Action"
    assert move.ports["goal"].type_name == "std::vector<double>"
    assert move.ports["reached"].direction == "output"
    assert move.ports["reached"].description == "arrived"
    for node_id in registry.ids():
        assert (node_id in doc.models) == (not registry.is_builtin(node_id))


def test_nodes_listing(custom_nodes: None, capsys: pytest.CaptureFixture[str]) -> None:
    assert run_verb(["nodes"]) == 0
    rows = {line.split()[0]: line.split()[2] for line in capsys.readouterr().out.splitlines()}
    assert rows["Sequence"] == "built-in" and rows["MoveTo"] == "custom"


def test_custom_node_in_a_tree(custom_nodes: None) -> None:
    tree = load_tree(str(DEMO))
    assert tree.tree_id == "Demo"
    from bt_manip.bt import load_tree_string

    t = load_tree_string('<root BTCPP_format="4"><BehaviorTree ID="T"><Sequence>'
                         '<MoveTo goal="1;2;0.5" reached="{ok}"/><GraspCheck object="box"/>'
                         "</Sequence></BehaviorTree></root>")
    assert t.tick() is NodeStatus.SUCCESS
    assert t.blackboard.as_dict() == {"ok": True}
    assert t.root.children[0].get_input("goal") == [1.0, 2.0, 0.5]


def test_demo_tree_runs_and_renders() -> None:
    clock = ManualClock()
    tree = load_tree(str(DEMO), context=TreeContext(clock=clock))
    statuses = [tree.tick().name]
    view = render_status(tree)
    assert view.splitlines()[0] == "[*] Sequence 'demo'"
    assert "    [*] Sleep 'short_wait'" in view
    assert "  [ ] Fallback" in view
    clock.advance(0.05)
    for _ in range(10):
        statuses.append(tree.tick().name)
        if statuses[-1] != "RUNNING":
            break
        clock.advance(0.05)
    assert statuses == ["RUNNING"] * 4 + ["SUCCESS"]
    assert tree.blackboard.as_dict() == {"attempts": 3, "total": 12, "plan": "b",
                                         "summary": "plan b, total 12"}
    assert render_status(tree).splitlines()[0] == "[+] Sequence 'demo'"


def test_through_bt_manip_cli(capsys: pytest.CaptureFixture[str]) -> None:
    cli = pytest.importorskip("bt_manip.cli")
    assert cli.main(["validate", str(SAMPLES / "btcpp/corpus4.xml")]) == 2
    assert "ForceSuccess must have exactly 1 child" in capsys.readouterr().err
    assert cli.main(["validate", str(DEMO)]) == 0
