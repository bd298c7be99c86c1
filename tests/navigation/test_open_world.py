"""A world open round its obstacles (a lone wall, as a converted building of one wall or a row
of columns gives): a robot starting outside the obstacles' extent gets a map with room to
drive round them, while a robot inside a house keeps the map it had."""

from __future__ import annotations

import math
from pathlib import Path

from test_house import HUSKY_PIVOT, drive

from bt_manip.navigation.controller import FollowState
from bt_manip.navigation.grid import bodies_extent
from bt_manip.navigation.navigator import MAP_PAD, Navigator, NavigatorOptions
from bt_manip.sim.world import World

ROOT = Path(__file__).resolve().parents[2]


def _lone_wall(tmp_path: Path) -> Path:
    world = tmp_path / "lone_wall.yaml"
    world.write_text(
        "name: lone_wall\nwalls:\n"
        "  - {name: wall, from: [0, 0], to: [5, 0], thickness: 0.3, height: 1.5}\n"
        "robots:\n  - {name: husky, description: husky_ur3, pose: [2.5, -1.5, 1.5708]}\n"
    )
    return world


def test_the_husky_drives_round_a_lone_wall(tmp_path: Path) -> None:
    with World(str(_lone_wall(tmp_path)), seed=0) as world:
        robot = world.robots["husky"]
        nav = Navigator(robot, world.obstacle_body_ids(), world.movable,
                        NavigatorOptions(pivot=HUSKY_PIVOT))
        x0, y0, x1, y1 = nav.static.extent
        # the wall spans x 0..5, y -0.15..0.15: the map reaches round both its ends
        assert x0 < -1.2 and x1 > 6.2 and y0 < -1.5 - 1.2 and y1 > 1.4
        goal = (2.5, 1.5, math.pi / 2)
        plan = nav.start(robot.base_pose2d(), goal)
        assert plan.ok, plan.reason
        done = drive(world, nav, goal, 60.0, [robot.body])
        assert done.status is FollowState.SUCCEEDED, done.reason
        assert done.error_xy < 0.15
        assert not done.touched
        # it went round an end of the wall
        ends = (done.track[:, 0] < -0.3) | (done.track[:, 0] > 5.3)
        assert ends.any()


def test_a_robot_inside_a_house_keeps_the_map_round_its_walls() -> None:
    with World(str(ROOT / "worlds" / "tb3_house.yaml"), seed=0) as world:
        nav = Navigator(world.robots["husky"], world.obstacle_body_ids(), world.movable,
                        NavigatorOptions(pivot=HUSKY_PIVOT))
        x0, y0, _, _ = bodies_extent(world.client, world.obstacle_body_ids(), MAP_PAD)
        assert nav.static.origin == (x0, y0)
