"""The localisation map is the house's walls and furniture as its file lists them: not the
movable objects, not what is added while the world runs."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

from bt_manip.localization import LikelihoodField, map_from_world
from bt_manip.localization.map_from_world import static_bodies, static_outlines
from bt_manip.navigation.grid import OccupancyGrid
from bt_manip.sim.world import World
from bt_manip.sim.world_spec import COLOURS, BodySpec, Part, Pose3D, Range2D

WORLD = "worlds/tb3_house.yaml"


@pytest.fixture(scope="module")
def house() -> Iterator[World]:
    world = World(WORLD, seed=0)
    yield world
    world.close()


def occupied_at(grid: OccupancyGrid, x: float, y: float) -> bool:
    return bool(grid.occupied[grid.world_to_cell(x, y)])


def test_the_map_holds_walls_and_furniture_but_not_the_movable_panel(house: World) -> None:
    grid = map_from_world(house)
    assert grid.resolution == 0.05
    assert occupied_at(grid, 0.0, -5.0)  # the south wall
    assert occupied_at(grid, -2.6, 0.4)  # the tool cabinet
    assert occupied_at(grid, 3.6, 3.0)  # the kitchen table (a cylinder)
    assert not occupied_at(grid, 4.5, -1.5)  # the living room's floor
    # the panel (a movable object) stands here; its stand's rails are under the scan band
    assert not occupied_at(grid, 1.2171, -1.3476)
    panel = house.body_id("panel")
    assert panel not in static_bodies(house)
    assert len(static_bodies(house)) == len(house.spec.walls) + len(house.spec.furniture)


def test_what_is_added_at_run_time_is_not_in_the_map(house: World) -> None:
    before = map_from_world(house)
    crate = house.spawn(BodySpec(
        name="crate_added", movable=False,
        parts=[Part("box", (0.4, 0.4, 0.4), colour=COLOURS["brown"])], urdf=None,
        pose=Pose3D((4.5, -1.5, 0.2)), planar=False, mass=0.0, friction=0.9,
        colour=COLOURS["brown"], randomize=Range2D(), line=0,
    ))
    try:
        assert crate in house.obstacle_body_ids()  # navigation keeps clear of it ...
        after = map_from_world(house)  # ... but a mapping run never saw it
        assert np.array_equal(before.occupied, after.occupied)
    finally:
        house.remove("crate_added")


def test_the_outlines_and_the_field_agree(house: World) -> None:
    grid = map_from_world(house)
    field = LikelihoodField.from_grid(grid)
    outlines = static_outlines(house)
    assert len(outlines) >= len(house.spec.furniture)
    # every polygon corner lies in or beside an occupied cell (diagonally at worst)
    corners = np.concatenate([o.points() for o in outlines if hasattr(o, "vertices")])
    d = field.distance_at(corners[:, 0], corners[:, 1])
    assert float(d.max()) <= 0.05 * 2**0.5 + 1e-6
