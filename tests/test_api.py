"""The Python entry points: ``bt_manip.load_tree``, ``bt_manip.run_tree``, and ``World``
finding the shipped worlds by their relative paths, as the command line does."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _python(code: str, cwd: Path) -> str:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, env=env, capture_output=True,
                          text=True, check=True).stdout


def test_import_bt_manip_stays_cheap(tmp_path: Path) -> None:
    """Importing the package loads neither the episode nor the robot nodes: the two entry
    points load them on first use."""
    out = _python(
        "import sys, bt_manip\n"
        "print(sorted(m for m in sys.modules if m.startswith('bt_manip')))\n"
        "bt_manip.load_tree\n"
        "print('bt_manip.behaviours' in sys.modules, 'bt_manip.nav2' in sys.modules)\n",
        tmp_path)
    first, second = out.splitlines()
    assert first == "['bt_manip']"
    assert second == "True True"


def test_load_tree_knows_every_shipped_node_from_any_folder(tmp_path: Path) -> None:
    """A tree of robot and Nav2 nodes loads without importing their packages first, and a
    shipped tree is found by its relative path from a folder that lacks it."""
    out = _python(
        "import bt_manip\n"
        "tree = bt_manip.load_tree('trees/sawyer_blocks_to_bin.xml')\n"
        "print(tree.tree_id)\n"
        "print(bt_manip.load_tree('trees/nav2/replan_on_goal_update.xml').tree_id)\n",
        tmp_path)
    assert out.splitlines() == ["BlocksToBin", "NavigateReplanOnGoalUpdate"]


def test_world_finds_a_shipped_world_by_its_relative_path(tmp_path: Path) -> None:
    out = _python(
        "from bt_manip.sim.world import World\n"
        "with World('worlds/sawyer_table.yaml') as w:\n"
        "    print(w.spec.name, w.path.is_absolute())\n",
        tmp_path)
    assert out.strip() == "sawyer_table True"


def test_a_file_of_that_path_here_comes_first(tmp_path: Path) -> None:
    (tmp_path / "trees").mkdir()
    (tmp_path / "trees" / "sawyer_blocks_to_bin.xml").write_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Mine"><AlwaysSuccess/></BehaviorTree>'
        "</root>", encoding="utf-8")
    out = _python("import bt_manip\n"
                  "print(bt_manip.load_tree('trees/sawyer_blocks_to_bin.xml').tree_id)\n",
                  tmp_path)
    assert out.strip() == "Mine"


def test_run_tree_returns_the_run_report() -> None:
    import bt_manip

    report = bt_manip.run_tree(ROOT / "trees" / "builtins_demo.xml", max_ticks=1000)
    assert report.status.value == "SUCCESS" and report.exit_code == 0
    assert report.ticks >= 2 and report.seed is None


def test_run_tree_takes_blackboard_entries_and_faults() -> None:
    import bt_manip

    tree = ROOT / "trees" / "builtins_demo.xml"
    report = bt_manip.run_tree(tree, blackboard={"unused": 1}, inject=["Sequence:failure:1.0"])
    assert report.status.value == "FAILURE"
    assert report.extra["inject"] == ["Sequence:failure:1"]


def test_run_tree_refuses_an_unknown_option() -> None:
    import bt_manip

    with pytest.raises(TypeError, match=r"unknown option.*max_tick.*options are"):
        bt_manip.run_tree(ROOT / "trees" / "builtins_demo.xml", max_tick=5)


def test_run_tree_raises_input_error_for_a_robot_tree_without_world() -> None:
    import bt_manip
    from bt_manip.errors import InputError

    with pytest.raises(InputError, match="SpawnModel acts on a simulated world"):
        bt_manip.run_tree("trees/sawyer_stack_two.xml")


def test_an_unknown_name_is_an_attribute_error() -> None:
    import bt_manip

    with pytest.raises(AttributeError):
        _ = bt_manip.no_such_thing  # type: ignore[attr-defined]
