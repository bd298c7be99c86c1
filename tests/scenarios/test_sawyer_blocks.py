"""Scenario B end to end: the Sawyer puts the ten blocks into the bin, touching nothing else."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pybullet as pb

from bt_manip.episode import Episode, EpisodeSpec
from bt_manip.runner import Runner

ROOT = Path(__file__).resolve().parents[2]


def test_all_blocks_end_in_the_bin_moved_only_by_the_gripper() -> None:
    spec = EpisodeSpec(
        tree=str(ROOT / "trees" / "sawyer_blocks_to_bin.xml"),
        world=str(ROOT / "worlds" / "sawyer_table.yaml"),
        seed=11,
    )
    with Episode(spec) as episode:
        world = episode.world
        robot = world.robots["sawyer"]
        c = world.client
        start = {
            n: np.array(pb.getBasePositionAndOrientation(b, physicsClientId=c)[0])
            for n, b in world.movable.items()
        }
        first_move: dict[str, bool] = {}

        def watch(_: Runner) -> None:
            for name, body in world.movable.items():
                if name in first_move:
                    continue
                pos = np.array(pb.getBasePositionAndOrientation(body, physicsClientId=c)[0])
                if np.linalg.norm(pos - start[name]) > 0.003:
                    first_move[name] = bool(robot.finger_contacts(body))

        report = episode.run([watch])
        assert report.status == "SUCCESS", report.reason
        blackboard = episode.tree.blackboard.as_dict()
        assert blackboard["in_bin"] == 10 and blackboard["skipped"] == 0
        lo, hi = pb.getAABB(world.body_id("bin"), physicsClientId=c)
        for name, body in world.movable.items():
            pos, _ = pb.getBasePositionAndOrientation(body, physicsClientId=c)
            assert all(lo[i] <= pos[i] <= hi[i] for i in range(3)), f"{name} is not in the bin"
            lin, _ = pb.getBaseVelocity(body, physicsClientId=c)
            assert np.linalg.norm(lin) < 0.01, f"{name} is still moving"
        # every block started to move only when a finger touched it
        assert first_move == {name: True for name in world.movable}
