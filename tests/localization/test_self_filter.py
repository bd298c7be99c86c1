"""The localiser's self filter: returns from the robot itself and from what it holds across
the laser's plane are left out of what the filter reads; returns from the world are kept."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from bt_manip.localization.runtime import SELF_FILTER_PADDING, Localizer
from bt_manip.sim.world import World
from tests.sensing.worlds import ROOM, spawn_held, write


@pytest.fixture()
def holding(tmp_path: Path) -> World:
    world = World(write(tmp_path, ROOM.replace("arm_state: tuck", "arm_state: home")))
    yield world
    world.close()


def test_a_held_load_across_the_laser_is_left_out_and_the_walls_kept(holding: World) -> None:
    loc = Localizer(holding, holding.robots["husky"], "husky", seed=0)
    before = loc.lidar.scan()
    own_before = loc._own_returns(before)
    spawn_held(holding, "bar", (0.03, 0.6, 0.5))  # held level, across the scan plane
    scan = loc.lidar.scan()
    own = loc._own_returns(scan)
    bar = holding.body_id("bar")
    to_bar = loc.lidar.model_ranges([bar])
    on_bar = np.isfinite(to_bar) & (np.abs(scan.ranges - to_bar) < 0.03)
    assert on_bar.sum() >= 20, "the bar should hide a good part of the scan"
    assert own[on_bar].all()
    # the beams the bar does not stop read what they read before, and are judged as before
    clear = ~np.isfinite(to_bar)
    assert clear.sum() > 100
    assert np.array_equal(own[clear], own_before[clear])
    # what is kept lies beyond the robot's own model: walls and furniture
    kept = ~own & ~scan.no_return
    model = loc.lidar.model_ranges([holding.robots["husky"].body, bar])
    assert kept.sum() > 100
    assert np.all(scan.ranges[kept] < model[kept] - SELF_FILTER_PADDING)
    assert np.all(scan.ranges[kept] > 0.4)


def test_model_ranges_are_the_scan_where_only_the_robot_is_met(holding: World) -> None:
    loc = Localizer(holding, holding.robots["husky"], "husky", seed=0)
    robot = holding.robots["husky"]
    exact = loc.lidar
    scan = exact.scan()
    model = exact.model_ranges([robot.body])
    met = np.isfinite(model) & (model < scan.range_max)
    # a beam meets the robot first or the world first: never beyond the robot
    assert np.all(scan.ranges[met] <= model[met] + 4 * exact.spec.noise_m + 1e-6)
    # the wheels behind the laser are the robot (the Husky's 270 deg laser sees them)
    behind = np.abs(np.abs(scan.angles) - math.radians(120)) < math.radians(15)
    assert np.isfinite(model[behind]).any()
