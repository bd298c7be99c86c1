"""Scenario A end to end: the Husky fetches the panel and carries it to the goal."""

from __future__ import annotations

import math
from pathlib import Path

import pybullet as pb
import pytest

from bt_manip.episode import Episode, EpisodeSpec
from bt_manip.run.faults import FaultInjector, FaultSpec, parse_fault

ROOT = Path(__file__).resolve().parents[2]
TREE = str(ROOT / "trees" / "husky_carry_wall.xml")
HOUSE = str(ROOT / "worlds" / "tb3_house.yaml")


def test_panel_reaches_the_goal_held_and_untouched() -> None:
    with Episode(EpisodeSpec(tree=TREE, world=HOUSE, seed=4)) as episode:
        report = episode.run()
        world = episode.world
        assert report.status == "SUCCESS", report.reason
        x, y, yaw = world.robots["husky"].base_pose2d()
        goal = world.poses["goal"]
        assert math.hypot(x - goal.x, y - goal.y) <= 0.10
        assert abs(math.remainder(yaw - goal.yaw, math.tau)) <= 0.10
        assert world.attachments.is_attached("panel", "husky")
        lo, _ = pb.getAABB(world.movable["panel"], physicsClientId=world.client)
        assert lo[2] >= 0.1
        assert world.attachments.touched("panel") == []
        # it went through the doorway: the panel is in the living room now
        px = pb.getBasePositionAndOrientation(world.movable["panel"], physicsClientId=world.client)[
            0
        ][0]
        assert px > 1.8
        assert report.sim_time < 60


def test_a_grasp_that_never_holds_fails_with_the_reason() -> None:
    spec = EpisodeSpec(
        tree=TREE, world=HOUSE, seed=0, inject=[parse_fault("attach_panel:failure:1")]
    )
    with Episode(spec) as episode:
        report = episode.run()
        assert report.status == "FAILURE"
        assert [e["target"] for e in report.extra["injected"]] == ["attach_panel"] * 4
        assert report.reason.endswith("attach_panel: injected failure (--inject)")
        # every attempt backed off: the panel is still in its stand, not attached
        assert not episode.world.attachments.is_attached("panel")
        z = pb.getBasePositionAndOrientation(
            episode.world.movable["panel"], physicsClientId=episode.world.client
        )[0][2]
        assert z == pytest.approx(0.075, abs=0.01)


def test_an_injected_attach_failure_is_recovered() -> None:
    fault = parse_fault("Attach:failure:0.5")
    # the first seed whose draws fail the first attach and let the second one through
    seed = next(s for s in range(100) if _draws(fault, s) == [True, False])
    spec = EpisodeSpec(tree=TREE, world=HOUSE, seed=seed, inject=[fault])
    with Episode(spec) as episode:
        report = episode.run()
        assert len(report.extra["injected"]) == 1
        assert report.status == "SUCCESS", report.reason
        assert episode.world.attachments.is_attached("panel")


def _draws(fault: FaultSpec, seed: int) -> list[bool]:
    injector = FaultInjector([fault], seed=seed)
    return [injector.node_fails("attach_panel", "Attach") for _ in range(2)]


TURNED = str(ROOT / "worlds" / "tb3_house_panel_turned.yaml")
SOUTH = str(ROOT / "worlds" / "tb3_house_panel_south.yaml")


def test_a_panel_leaning_in_its_slot_is_lifted_out_without_counting_a_touch() -> None:
    # in this world and seed the closing gripper leaves the panel leaning on a rail of its
    # stand: sliding up along the rail it leans on is leaving the stand, not hitting it
    with Episode(EpisodeSpec(tree=TREE, world=SOUTH, seed=0)) as episode:
        report = episode.run()
        assert report.status == "SUCCESS", report.reason
        assert episode.world.attachments.touched("panel") == []


@pytest.mark.parametrize("seed", [0, 1])
def test_the_panel_set_moved_and_turned_is_fetched_and_delivered(seed: int) -> None:
    with Episode(EpisodeSpec(tree=TREE, world=TURNED, seed=seed)) as episode:
        report = episode.run()
        world = episode.world
        assert report.status == "SUCCESS", report.reason
        statuses = {n.path.split("/")[-1]: n.last_status for n in report.nodes}
        assert statuses["lift_out_of_stand"] == "SUCCESS"
        # the goal of this world, in the middle of the living room
        goal = world.poses["goal"]
        assert (goal.x, goal.y) == (4.6, -1.0)
        x, y, _ = world.robots["husky"].base_pose2d()
        assert math.hypot(x - goal.x, y - goal.y) <= 0.10
        assert world.attachments.is_attached("panel", "husky")
        assert world.attachments.touched("panel") == []
        lo, _ = pb.getAABB(world.movable["panel"], physicsClientId=world.client)
        assert lo[2] >= 0.1
        # the stand stayed where the group put it, in the workshop
        stand = world.body_pose("panel_stand").xyz
        assert stand[0] < 0.0 and stand[1] < -1.0


def test_the_pregrasp_pose_beside_the_panel_is_reached_without_swinging_into_it() -> None:
    """In the world with the panel set turned counter-clockwise, the drive to the pregrasp
    pose ends a few centimetres beside it: the base backs up and drives in instead of turning
    on the spot toward it, which swept the arm into the panel, tilted it in its stand, and
    the arm move into the grasp pose then stopped 10 deg short against it (seed 12)."""
    world_file = str(ROOT / "worlds" / "tb3_house_panel_turned_ccw.yaml")
    with Episode(EpisodeSpec(tree=TREE, world=world_file, seed=12)) as episode:
        report = episode.run()
        world = episode.world
        assert report.status == "SUCCESS", report.reason
        statuses = {n.path.split("/")[-1]: n.last_status for n in report.nodes}
        assert statuses["pregrasp_arm"] == "SUCCESS"
        assert world.attachments.touched("panel") == []
        goal = world.poses["goal"]
        x, y, _ = world.robots["husky"].base_pose2d()
        assert math.hypot(x - goal.x, y - goal.y) <= 0.10
