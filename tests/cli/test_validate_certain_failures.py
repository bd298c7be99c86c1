"""``bt-manip validate`` reports, with file:line, what is certain to fail (required
alternatives missing, names the ``--world`` lacks) and warns of SubTree ports their tree never
uses; ``run`` refuses a tree that needs a world when none is given (exit 2, at load)."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_manip.cli import main

ROOT = Path(__file__).resolve().parents[2]
WORLD = str(ROOT / "worlds" / "sawyer_table.yaml")

TREE = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence>
      <MoveToPose/>
      <ObjectInRegion object="block_0"/>
      <ObjectInRegion object="block_0" min="0;0;0"/>
      <MoveToPose position="1;0;1" object="block_1"/>
      <MoveToPose position="{p}" object="{o}"/>
      <MoveJoints/>
      <Lift height="0.1"/>
      <SubTree ID="Sub" obj="block_1" blok="block_0"/>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Sub">
    <IsHolding object="{obj}"/>
  </BehaviorTree>
</root>
"""

NAMES = """<root BTCPP_format="4">
  <BehaviorTree ID="Names">
    <Sequence>
      <MoveToPose object="blok_1"/>
      <ObjectInRegion object="block_0" inside="bn"/>
      <Navigate goal="kitchen"/>
      <Navigate goal="1;2;0.5"/>
      <Navigate goal="bin_drop" robot="sawyer"/>
      <IsHolding object="{any}" robot="panda"/>
      <MoveToPose object="block_2" offset="0;0;0.1"/>
    </Sequence>
  </BehaviorTree>
</root>
"""


def _write(tmp_path: Path, name: str, text: str) -> str:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return str(path)


def test_missing_alternatives_are_problems_with_their_line(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    tree = _write(tmp_path, "t.xml", TREE)
    assert main(["validate", tree]) == 2
    err = capsys.readouterr().err.splitlines()
    problems = [line for line in err if "warning" not in line]
    assert problems == [
        f'{tree}:4: MoveToPose needs position="..." or object="..."; it would fail when ticked',
        f'{tree}:5: ObjectInRegion needs inside="..." or min="..." and max="..."; it would '
        "fail when ticked",
        f'{tree}:6: ObjectInRegion needs inside="..." or min="..." and max="..." (max '
        "missing); it would fail when ticked",
        f'{tree}:7: MoveToPose takes exactly one of position="..." or object="...", got '
        "position and object; it would fail when ticked",
        f'{tree}:9: MoveJoints needs targets="..." or state="..."; it would fail when ticked',
    ]  # line 8 gives both through the blackboard: one may be empty when it runs


def test_a_subtree_port_its_tree_never_uses_is_a_warning(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    tree = _write(tmp_path, "t.xml", TREE)
    main(["validate", tree])
    warnings = [line for line in capsys.readouterr().err.splitlines() if "warning" in line]
    assert warnings == [
        f"{tree}:11: warning: SubTree 'Sub' port 'blok' is never read or written by tree "
        "'Sub'; its value goes nowhere"
    ]


def test_shipped_trees_have_no_such_problem(capsys: pytest.CaptureFixture[str]) -> None:
    trees = sorted(str(p) for p in (ROOT / "trees").rglob("*.xml"))
    assert main(["validate", *trees]) == 0
    assert capsys.readouterr().err == ""


def test_names_the_world_lacks(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    tree = _write(tmp_path, "names.xml", NAMES)
    assert main(["validate", tree]) == 0  # without a world, names are not checked
    capsys.readouterr()
    assert main(["validate", tree, "--world", WORLD]) == 2
    err = capsys.readouterr().err.splitlines()
    assert [line.split(": ")[0] for line in err] == [f"{tree}:4", f"{tree}:5", f"{tree}:6",
                                                     f"{tree}:9"]
    assert "MoveToPose object=\"blok_1\": " in err[0] and "(did you mean 'block_1'" in err[0]
    assert "ObjectInRegion inside=\"bn\": " in err[1] and "(did you mean 'bin'" in err[1]
    assert "has no named pose of that name; its named poses: bin_drop" in err[2]
    assert "has no robot of that name; its robots: sawyer" in err[3]


def test_the_shipped_scenario_b_trees_name_what_their_world_has(
        capsys: pytest.CaptureFixture[str]) -> None:
    trees = [str(ROOT / "trees" / n) for n in ("sawyer_blocks_to_bin.xml", "sawyer_stack_two.xml")]
    assert main(["validate", *trees, "--world", "worlds/sawyer_table.yaml"]) == 0


def test_run_without_a_world_exits_2_at_load_naming_the_first_robot_node(
        capsys: pytest.CaptureFixture[str]) -> None:
    tree = str(ROOT / "trees" / "sawyer_stack_two.xml")
    assert main(["run", tree]) == 2
    captured = capsys.readouterr()
    assert captured.err.strip() == (
        f"{tree}:16: SpawnModel acts on a simulated world, and no world is given; run with "
        "--world W.yaml (`bt-manip examples` lists the shipped worlds)")
    assert "result" not in captured.out  # nothing ticked
