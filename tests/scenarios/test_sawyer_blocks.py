"""Scenario B end to end: the Sawyer puts the ten blocks into the bin, touching nothing else,
on the scenario's world and on variants with the blocks turned +-45 deg and the bin moved."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pybullet as pb
import pytest

from bt_manip.behaviours.regions import region_of
from bt_manip.episode import Episode, EpisodeSpec
from bt_manip.run.runner import Runner

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize(
    ("world_file", "seed"),
    [("sawyer_table.yaml", 11), ("sawyer_table_yaw45.yaml", 5),
     ("sawyer_table_bin_moved.yaml", 3), ("sawyer_table_bin_moved.yaml", 14)],
)
def test_all_blocks_end_in_the_bin_moved_only_by_the_gripper(world_file: str, seed: int) -> None:
    spec = EpisodeSpec(tree=str(ROOT / "trees" / "sawyer_blocks_to_bin.xml"),
                       world=str(ROOT / "worlds" / world_file), seed=seed)
    with Episode(spec) as episode:
        world = episode.world
        robot = world.robots["sawyer"]
        c = world.client
        assert world.movable == {}  # the tree spawns the blocks
        start: dict[str, np.ndarray] = {}
        first_move: dict[str, bool] = {}
        resting: dict[str, bool] = {}
        moved_at: dict[str, float] = {}  # sim time of a block's first move
        lifted_at: dict[str, float] = {}  # and of its first 3 cm off the table

        # the bin's box in its own frame (turned with it in the moved-bin world)
        bin_box = region_of(world, "bin")

        def watch(_: Runner) -> None:
            for name, body in world.movable.items():
                pos = np.array(pb.getBasePositionAndOrientation(body, physicsClientId=c)[0])
                start.setdefault(name, pos)
                resting[name] = bin_box.contains(pos)
                if name not in first_move and np.linalg.norm(pos - start[name]) > 0.003:
                    first_move[name] = bool(robot.finger_contacts(body))
                    moved_at[name] = world.clock.now()
                if name not in lifted_at and pos[2] > start[name][2] + 0.03:
                    lifted_at[name] = world.clock.now()

        report = episode.run([watch])
        assert report.status == "SUCCESS", report.reason
        blackboard = episode.tree.blackboard.as_dict()
        assert blackboard["in_bin"] == 10 and blackboard["skipped"] == 0
        assert blackboard["resting_in_bin"] == 10
        # spawned where the world file says (within the +-1 cm jitter), then deleted at the end
        nominal = {m.name: np.array(m.pose.xyz) for m in world.spec.models}
        assert sorted(start) == sorted(nominal)
        for name, pos in start.items():
            assert np.all(np.abs(pos[:2] - nominal[name][:2]) <= 0.0101), name
        assert world.movable == {}
        # the last time each block was seen, it rested in the bin
        assert resting == {name: True for name in nominal}
        # every block started to move only when a finger touched it, and not before the block
        # picked before it was lifted (the fingers pass beside a neighbour, turned or not)
        assert first_move == {name: True for name in nominal}
        for k in range(1, 10):
            assert moved_at[f"block_{k}"] > lifted_at[f"block_{k - 1}"], k
