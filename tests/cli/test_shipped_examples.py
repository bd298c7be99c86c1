"""The shipped examples: where they are found, `bt-manip examples [copy DIR]`, shipped paths
named from any folder, and `bt-manip demo`'s checks (the demo itself runs in test_wheel.py,
from an installed wheel)."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_manip import bundled
from bt_manip.cli import main
from bt_manip.sim import assets
from bt_manip.sim.robot_description import ROBOTS_DIR
from bt_manip.sim.world_reader import parse_world

ROOT = Path(__file__).resolve().parents[2]


def test_a_clone_reads_its_own_folders_and_a_wheel_its_package_data(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    assert assets.data_root() == ROOT  # no bt_manip/_data in a clone
    assert ROBOTS_DIR == ROOT / "robots"
    packaged = tmp_path / "_data"
    (packaged / "robots").mkdir(parents=True)
    monkeypatch.setattr(assets, "PACKAGED_DATA", packaged)
    assert assets.data_root() == packaged


def test_examples_lists_the_shipped_trees_worlds_and_robots(
        capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["examples"]) == 0
    out = capsys.readouterr().out
    listed = [line.strip() for line in out.splitlines() if line.startswith("  ")]
    assert "trees/husky_carry_wall.xml" in listed and "trees/nav2/through_poses.xml" in listed
    assert "worlds/tb3_house.yaml" in listed and "robots/panda.yaml" in listed
    assert not any(name.endswith((".urdf", ".md")) for name in listed)
    shipped = {p.relative_to(ROOT).as_posix() for folder in ("trees", "worlds", "robots")
               for p in (ROOT / folder).rglob("*") if p.suffix in (".xml", ".yaml")}
    assert set(listed) == shipped


def test_copied_examples_are_edited_and_still_find_their_robots(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    dest = tmp_path / "mine"
    assert main(["examples", "copy", str(dest)]) == 0
    assert "copied" in capsys.readouterr().out
    for folder in ("trees", "worlds", "robots"):
        for src in (ROOT / folder).rglob("*"):
            if src.is_file():
                assert (dest / src.relative_to(ROOT)).read_bytes() == src.read_bytes()
    # a copied robot, edited, is the one the copied world uses
    robot = dest / "robots" / "sawyer.yaml"
    robot.write_text(robot.read_text())
    spec = parse_world(dest / "worlds" / "sawyer_table.yaml")
    assert spec.robots[0].description_path == robot.resolve()
    # a world copied on its own finds the shipped robot
    alone = tmp_path / "alone.yaml"
    alone.write_text((ROOT / "worlds" / "sawyer_table.yaml").read_text())
    assert parse_world(alone).robots[0].description_path == (ROBOTS_DIR / "sawyer.yaml").resolve()


def test_copy_refuses_to_overwrite_unless_forced(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    dest = tmp_path / "mine"
    assert main(["examples", "copy", str(dest)]) == 0
    edited = dest / "trees" / "builtins_demo.xml"
    edited.write_text("<root/>")
    capsys.readouterr()
    assert main(["examples", "copy", str(dest)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"{dest}: ") and "would be overwritten" in err and "--force" in err
    assert edited.read_text() == "<root/>"
    assert main(["examples", "copy", str(dest), "--force"]) == 0
    assert edited.read_bytes() == (ROOT / "trees" / "builtins_demo.xml").read_bytes()
    assert main(["examples", "copy", str(tmp_path / "no" / "such")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_shipped_paths_are_found_from_any_folder_but_local_files_come_first(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.chdir(tmp_path)
    shipped = str(ROOT / "trees" / "builtins_demo.xml")
    assert bundled.shipped_or_given("trees/builtins_demo.xml") == shipped
    assert bundled.shipped_or_given("./trees/builtins_demo.xml") == shipped
    for untouched in ("trees/none.xml", "trees/../trees/builtins_demo.xml", "builtins_demo.xml",
                      "docs/bench.md", "trees"):
        assert bundled.shipped_or_given(untouched) == untouched
    local = tmp_path / "trees" / "builtins_demo.xml"
    local.parent.mkdir()
    local.write_text('<root BTCPP_format="4"><BehaviorTree ID="Main">'
                     '<AlwaysFailure name="mine"/></BehaviorTree></root>')
    assert bundled.shipped_or_given("trees/builtins_demo.xml") == "trees/builtins_demo.xml"
    assert main(["run", "trees/builtins_demo.xml"]) == 1  # the local file ran
    local.unlink()
    assert main(["run", "trees/builtins_demo.xml", "--quiet"]) == 0  # the shipped one ran
    assert "result: SUCCESS" in capsys.readouterr().out
    assert main(["world", "worlds/panda_table.yaml"]) == 0
    assert "world 'panda_table'" in capsys.readouterr().out
    assert main(["validate", "trees/nav2/through_poses.xml"]) == 0
    assert capsys.readouterr().out.strip() == f"{ROOT / 'trees/nav2/through_poses.xml'}: OK"
    assert main(["show", "trees/builtins_demo.xml"]) == 0
    assert "third_time_lucky" in capsys.readouterr().out


def test_demo_checks_its_output_folder_before_running(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["demo", "--out", str(tmp_path / "no" / "such")]) == 2
    out, err = capsys.readouterr()
    assert err.startswith("--out: the folder") and "does not exist" in err
    assert "result:" not in out
    taken = tmp_path / "file"
    taken.write_text("")
    assert main(["demo", "--out", str(taken)]) == 2
    assert "is a file, not a folder" in capsys.readouterr().err
