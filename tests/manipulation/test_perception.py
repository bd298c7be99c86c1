"""An object's pose as the robot perceives it: the ground truth plus the episode's pose noise."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from bt_manip.manipulation.perception import perceived_pose, true_pose
from bt_manip.run.faults import FaultInjector, FaultSpec
from bt_manip.sim.world import World

ROOM = Path(__file__).resolve().parent.parent / "behaviours" / "grasp_room.yaml"


@pytest.fixture
def grasp_room() -> Iterator[World]:
    with World(ROOM, seed=0) as world:
        yield world


def test_plans_read_the_perceived_pose_and_checks_the_true_one(grasp_room: World) -> None:
    world = grasp_room
    faults = FaultInjector([FaultSpec("pose_noise", 0.0, sigma_m=0.02, sigma_deg=3.0)], seed=5)
    offset = faults.pose_offset("panel")
    assert offset is not None
    seen = perceived_pose(world, faults, "panel")
    truth = true_pose(world, world.movable["panel"])
    np.testing.assert_allclose(seen[:2, 3] - truth[:2, 3], [offset.dx, offset.dy], atol=1e-12)
    assert seen[2, 3] == truth[2, 3]
    turn = math.atan2(seen[1, 0], seen[0, 0]) - math.atan2(truth[1, 0], truth[0, 0])
    assert math.remainder(turn - offset.dyaw, math.tau) == pytest.approx(0.0, abs=1e-9)
    assert perceived_pose(world, None, "panel").tolist() == truth.tolist()
