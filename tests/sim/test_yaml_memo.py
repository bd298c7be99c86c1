"""YAML files read again in one process: the values come from memory only when the bytes are
the same, every caller gets its own copy, and the memory is bounded."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from bt_manip.errors import InputError
from bt_manip.sim import yaml_lines
from bt_manip.sim.world import World
from bt_manip.sim.yaml_lines import LineDict, LineList, load_yaml

ROOT = Path(__file__).resolve().parents[2]


def test_a_world_file_edited_between_two_loads_is_read_as_edited(tmp_path: Path) -> None:
    path = tmp_path / "table.yaml"
    shutil.copy(ROOT / "worlds" / "sawyer_table.yaml", path)
    with World(path) as world:
        x_before = world.body_pose("cafe_table").xyz[0]
    path.write_text(path.read_text().replace("pose: [1.0, 0.0, 0.0]", "pose: [1.1, 0.0, 0.0]"))
    with World(path) as world:
        x_after = world.body_pose("cafe_table").xyz[0]
    assert x_before == pytest.approx(1.0, abs=1e-9)
    assert x_after == pytest.approx(1.1, abs=1e-9)
    path.write_text(path.read_text().replace("name: cafe_table", "name: [broken"))
    with pytest.raises(InputError) as err:
        World(path)
    assert str(path) in str(err.value)


def test_every_load_gets_its_own_copy_with_lines_and_shared_aliases(tmp_path: Path) -> None:
    path = tmp_path / "values.yaml"
    path.write_text("base: &b {x: [1, 2.5, {y: true}]}\nother: *b\nname: n\nlist:\n  - a\n  - 3\n")
    first = load_yaml(path)
    first["base"]["x"][2]["y"] = False  # a caller changing what it got
    first["list"].append("z")
    again = load_yaml(path)
    assert again == {"base": {"x": [1, 2.5, {"y": True}]}, "other": {"x": [1, 2.5, {"y": True}]},
                     "name": "n", "list": ["a", 3]}
    assert isinstance(again, LineDict) and isinstance(again["list"], LineList)
    assert again.line_of("name") == 3 and again["list"].line_of(1) == 6
    assert again["base"] is again["other"]  # the alias names one value, as when parsed
    third = load_yaml(path)
    assert third is not again and third["base"] is not again["base"]


def test_the_memory_of_files_is_bounded(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    memo = yaml_lines.Memo(3)
    monkeypatch.setattr(yaml_lines, "_YAML_MEMO", memo)
    for i in range(10):
        path = tmp_path / f"f{i}.yaml"
        path.write_text(f"value: {i}\n")
        assert load_yaml(path) == {"value": i}
        assert len(memo) <= 3
    big = tmp_path / "big.yaml"
    big.write_text("k: '" + "x" * (yaml_lines.YAML_MEMO_BYTES // yaml_lines.YAML_MEMO_ENTRIES)
                   + "'\n")
    held = dict(memo._items)
    assert len(load_yaml(big)["k"]) > 1000
    assert dict(memo._items) == held  # a file past the size kept is not held
