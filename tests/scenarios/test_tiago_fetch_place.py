"""TIAGo (a descriptor written by ``bt-manip robot init``, only its states set by hand) fetches
the block from table_a and puts it on table_b: data files only, no robot-specific code."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pybullet as pb

from bt_manip.episode import Episode, EpisodeSpec
from bt_manip.run.runner import Runner

ROOT = Path(__file__).resolve().parents[2]
TREE = str(ROOT / "trees" / "tiago_fetch_place.xml")
WORLD = str(ROOT / "worlds" / "tiago_tables.yaml")
PLACE = (-2.03, -1.2, 0.725)
"""Where the tree puts the block's centre on table_b."""


def test_the_block_is_carried_in_the_hand_from_table_a_to_table_b() -> None:
    with Episode(EpisodeSpec(tree=TREE, world=WORLD, seed=3)) as episode:
        world = episode.world
        robot = world.robots["tiago"]
        block = world.movable["block"]
        c = world.client
        start = np.array(pb.getBasePositionAndOrientation(block, physicsClientId=c)[0])
        path = {"held": 0.0, "free": 0.0}
        first_move_by_fingers: list[bool] = []
        last = start.copy()

        def watch(_: Runner) -> None:
            nonlocal last
            pos = np.array(pb.getBasePositionAndOrientation(block, physicsClientId=c)[0])
            step = float(np.linalg.norm(pos - last))
            held = world.attachments.is_attached("block", "tiago")
            path["held" if held else "free"] += step
            if not first_move_by_fingers and np.linalg.norm(pos - start) > 0.003:
                first_move_by_fingers.append(bool(robot.finger_contacts(block)))
            last = pos

        report = episode.run([watch])
        assert report.status == "SUCCESS", report.reason
        pos, quat = pb.getBasePositionAndOrientation(block, physicsClientId=c)
        # on table_b, where Place put it, upright and let go
        assert math.dist(pos[:2], PLACE[:2]) <= 0.02
        assert abs(pos[2] - PLACE[2]) <= 0.005
        up = np.array(pb.getMatrixFromQuaternion(quat)).reshape(3, 3)[:, 2]
        assert up[2] > math.cos(math.radians(5))
        assert not world.attachments.is_attached("block")
        # the fingers moved it first, and it crossed the room held by the hand
        assert first_move_by_fingers == [True]
        assert math.dist(start[:2], pos[:2]) > 4.0
        assert path["held"] > 4.0
        assert path["free"] < 0.15
        # while held it touched nothing but the table it was set down on
        assert set(world.attachments.touched("block")) <= {"table_b"}
        # the robot backed away from table_b with the arm tucked
        x, y, _ = robot.base_pose2d()
        near = world.poses["near_table_b"]
        assert math.hypot(x - near.x, y - near.y) <= 0.05
        assert report.sim_time < 120
