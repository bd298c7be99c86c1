"""GetClear: the base gets clear of what it is up against, or fails saying what blocked it."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from bhelpers import reasons, run_xml

from bt_manip.sim import pybullet_queries as pbq
from bt_manip.sim.world import World

MakeWorld = Callable[[str], World]

TOUCHING_CRATE = """\
name: touching_crate
walls:
  - {from: [-3, -3], to: [3, -3]}
  - {from: [-3, 3], to: [3, 3]}
objects:
  # 5 mm in front of the bumper
  - {name: crate, shape: box, size: [0.3, 0.3, 0.3], mass: 2.0, pose: [0.655, 0.1, 0.0]}
robots:
  - {name: husky, description: husky_ur3, pose: [0.0, 0.0, 0.0], arm_state: tuck}
"""

WALL_BEHIND = """\
name: wall_behind
furniture:
  # 5 mm behind the robot: backing away is blocked
  - {name: back_wall, shape: box, size: [0.2, 3.0, 1.0], pose: [-0.61, 0.0, 0.0]}
objects:
  # against the front half of the robot's left side
  - {name: crate, shape: box, size: [0.3, 0.3, 0.3], mass: 2.0, pose: [0.2, 0.5, 0.0]}
robots:
  - {name: husky, description: husky_ur3, pose: [0.0, 0.0, 0.0], arm_state: tuck}
"""

BOXED_IN = """\
name: boxed_in
furniture:
  - {name: front, shape: box, size: [0.2, 1.6, 0.5], pose: [0.62, 0.0, 0.0]}
  - {name: back, shape: box, size: [0.2, 1.6, 0.5], pose: [-0.62, 0.0, 0.0]}
  - {name: left, shape: box, size: [1.0, 0.2, 0.5], pose: [0.0, 0.46, 0.0]}
  - {name: right, shape: box, size: [1.0, 0.2, 0.5], pose: [0.0, -0.46, 0.0]}
robots:
  - {name: husky, description: husky_ur3, pose: [0.0, 0.0, 0.0], arm_state: tuck}
"""


@pytest.fixture
def world_of(tmp_path: Path) -> Iterator[MakeWorld]:
    opened: list[World] = []

    def make(text: str) -> World:
        path = tmp_path / "w.yaml"
        path.write_text(text)
        world = World(path, seed=0)
        opened.append(world)
        return world

    yield make
    for world in opened:
        world.close()


def clearance(world: World, name: str) -> float:
    robot = world.robots["husky"]
    points = pbq.closest_points(world.client, robot.body, world.body_id(name), 5.0)
    return min(p.distance for p in points)


def test_a_robot_touching_a_crate_backs_away_until_clear(world_of: MakeWorld) -> None:
    world = world_of(TOUCHING_CRATE)
    crate_before = world.body_pose("crate").xyz
    report, _ = run_xml(world, '<GetClear distance="0.5"/>')
    assert report.status == "SUCCESS", report.reason
    assert reasons(report)["GetClear"] == "clear of 'crate' by 0.5 m"
    assert clearance(world, "crate") >= 0.5 - 0.02
    x, _, _ = world.robots["husky"].base_pose2d()
    assert x < -0.3  # it went backwards, away from the crate
    # the crate was left where it was
    assert world.body_pose("crate").xyz == pytest.approx(crate_before, abs=0.01)


def test_with_a_wall_behind_it_turns_and_drives_out_forwards(world_of: MakeWorld) -> None:
    world = world_of(WALL_BEHIND)
    report, _ = run_xml(world, '<GetClear distance="0.5"/>')
    assert report.status == "SUCCESS", report.reason
    assert clearance(world, "crate") >= 0.5 - 0.02
    assert clearance(world, "back_wall") >= 0.5 - 0.02
    x, _, yaw = world.robots["husky"].base_pose2d()
    assert x > 0.5  # forwards, not through the wall
    assert yaw < -0.1  # turned away from the crate on its left


def test_boxed_in_all_round_it_fails_saying_why(world_of: MakeWorld) -> None:
    world = world_of(BOXED_IN)
    report, _ = run_xml(world, '<GetClear distance="0.5"/>')
    assert report.status == "FAILURE"
    why = reasons(report)["GetClear"]
    assert why.startswith("no motion frees it: still within 0.5 m of 'front', 'back', 'left', "
                          "'right'"), why
    assert "backing away" in why and "turning on the spot" in why
    x, y, _ = world.robots["husky"].base_pose2d()
    assert abs(x) < 0.05 and abs(y) < 0.05


def test_with_nothing_near_it_succeeds_without_moving(world_of: MakeWorld) -> None:
    world = world_of(TOUCHING_CRATE.replace("[0.655, 0.1, 0.0]", "[1.5, 0.1, 0.0]"))
    before = world.robots["husky"].base_pose2d()
    report, _ = run_xml(world, '<GetClear distance="0.5"/>')
    assert report.status == "SUCCESS"
    assert reasons(report)["GetClear"] == "nothing to get clear of"
    assert world.robots["husky"].base_pose2d() == pytest.approx(before, abs=1e-3)
