"""The Panda (added only through ``bt-manip robot init``) puts the three blocks into the tray,
each moved only by its fingers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pybullet as pb
import pytest

from bt_manip.behaviours.regions import region_of
from bt_manip.episode import Episode, EpisodeSpec
from bt_manip.run.runner import Runner

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("seed", [2, 9])
def test_blocks_end_in_the_tray_moved_only_by_the_fingers(seed: int) -> None:
    spec = EpisodeSpec(tree=str(ROOT / "trees" / "panda_pick_place.xml"),
                       world=str(ROOT / "worlds" / "panda_table.yaml"), seed=seed)
    with Episode(spec) as episode:
        world = episode.world
        robot = world.robots["panda"]
        c = world.client
        tray = region_of(world, "tray")
        start: dict[str, np.ndarray] = {}
        first_move: dict[str, bool] = {}
        resting: dict[str, bool] = {}

        def watch(_: Runner) -> None:
            for name, body in world.movable.items():
                pos = np.array(pb.getBasePositionAndOrientation(body, physicsClientId=c)[0])
                start.setdefault(name, pos)
                resting[name] = tray.contains(pos)
                if name not in first_move and np.linalg.norm(pos - start[name]) > 0.003:
                    first_move[name] = bool(robot.finger_contacts(body))

        report = episode.run([watch])
        assert report.status == "SUCCESS", report.reason
        blackboard = episode.tree.blackboard.as_dict()
        assert blackboard["in_tray"] == 3 and blackboard["resting_in_tray"] == 3
        names = {m.name for m in world.spec.models}
        assert resting == {name: True for name in names}
        assert first_move == {name: True for name in names}
        assert world.movable == {}
