"""One lookup of robot descriptors, for worlds and for code."""

from __future__ import annotations

from pathlib import Path

from bt_manip.sim.robot_description import ROBOTS_DIR, find_descriptor, known_robots


def _descriptor(folder: Path, name: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.yaml"
    path.write_text(f"name: {name}\n")
    return path


def test_a_world_finds_its_own_robots_first(tmp_path: Path) -> None:
    worlds = tmp_path / "worlds"
    beside = _descriptor(tmp_path / "robots", "husky_ur3")
    assert find_descriptor("husky_ur3", worlds) == beside.resolve()
    inside = _descriptor(worlds / "robots", "husky_ur3")
    assert find_descriptor("husky_ur3", worlds) == inside.resolve()
    assert find_descriptor("sawyer", worlds) == (ROBOTS_DIR / "sawyer.yaml").resolve()
    assert find_descriptor("r2d2", worlds) is None
    assert "husky_ur3" in known_robots(worlds) and "sawyer" in known_robots(worlds)


def test_paths_are_relative_to_the_world_and_names_to_the_shipped_robots(tmp_path: Path) -> None:
    own = _descriptor(tmp_path / "mine", "rover")
    assert find_descriptor("mine/rover.yaml", tmp_path) == own.resolve()
    assert find_descriptor("mine/missing.yaml", tmp_path) is None
    assert find_descriptor(own) == own
    assert find_descriptor("sawyer") == ROBOTS_DIR / "sawyer.yaml"
    assert find_descriptor("rover") is None
    assert "rover" not in known_robots()
