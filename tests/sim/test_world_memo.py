"""World files parsed again in one process: the spec comes from memory only when it would be
parsed the same (same bytes, same path, robots' descriptors found at the same files, no URDF
bodies), and every caller gets its own copy."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from bt_manip.errors import InputError
from bt_manip.sim.world import World
from bt_manip.sim.world_reader import check_world, parse_world

ROOT = Path(__file__).resolve().parents[2]
TRIANGLE = "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nf 1 2 3\n"


def test_a_descriptor_added_beside_the_world_is_found_on_the_next_load(tmp_path: Path) -> None:
    world = tmp_path / "table.yaml"
    shutil.copy(ROOT / "worlds" / "sawyer_table.yaml", world)
    shipped = parse_world(world).robots[0].description_path
    assert shipped == (ROOT / "robots" / "sawyer.yaml").resolve()
    (tmp_path / "robots").mkdir()
    for name in ("sawyer.yaml", "sawyer.urdf"):
        shutil.copy(ROOT / "robots" / name, tmp_path / "robots" / name)
    assert parse_world(world).robots[0].description_path == (
        tmp_path / "robots" / "sawyer.yaml").resolve()
    (tmp_path / "robots" / "sawyer.yaml").unlink()
    assert parse_world(world).robots[0].description_path == shipped


def test_a_urdf_body_is_checked_on_every_load(tmp_path: Path) -> None:
    (tmp_path / "thing.obj").write_text(TRIANGLE)
    (tmp_path / "thing.urdf").write_text(
        '<robot name="thing"><link name="a"><collision><geometry>'
        '<mesh filename="thing.obj"/></geometry></collision></link></robot>\n')
    world = tmp_path / "w.yaml"
    world.write_text("name: w\nfurniture:\n  - {name: thing, urdf: thing.urdf, pose: [1, 0, 0]}\n")
    assert parse_world(world).furniture[0].urdf == (tmp_path / "thing.urdf").resolve()
    (tmp_path / "thing.obj").unlink()
    with pytest.raises(InputError) as err:
        parse_world(world)
    assert f"{world}:3:" in str(err.value) and "thing.obj" in str(err.value)


def test_every_load_gets_its_own_spec_equal_to_a_first_parse(tmp_path: Path) -> None:
    world = tmp_path / "house.yaml"
    shutil.copy(ROOT / "worlds" / "tb3_house.yaml", world)
    first = parse_world(world)
    again = parse_world(world)
    assert again == first and again is not first
    again.walls.pop()
    again.furniture[0].name = "renamed"
    again.poses.clear()
    assert parse_world(world) == first
    copied = tmp_path / "house_copy.yaml"
    shutil.copy(world, copied)
    assert parse_world(copied).path == copied  # the spec names the file it was read from
    with World(world, seed=3) as a:
        pose_a = a.body_pose("panel")
    with World(world, seed=3) as b:
        assert b.body_pose("panel") == pose_a


def test_checking_a_known_world_leaves_every_load_its_own_spec(tmp_path: Path) -> None:
    world = tmp_path / "house.yaml"
    shutil.copy(ROOT / "worlds" / "tb3_house.yaml", world)
    check_world(world)  # parsed and kept
    first = parse_world(world)
    check_world(world)  # known: nothing to copy
    first.walls.pop()
    again = parse_world(world)
    assert again != first and len(again.walls) == len(first.walls) + 1


def test_checking_a_world_raises_what_parsing_raises(tmp_path: Path) -> None:
    world = tmp_path / "bad.yaml"
    world.write_text("name: bad\nwalls: 3\n")
    with pytest.raises(InputError) as parsed:
        parse_world(world)
    with pytest.raises(InputError) as checked:
        check_world(world)
    assert str(checked.value) == str(parsed.value) and f"{world}:2" in str(checked.value)
