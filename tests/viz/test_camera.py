"""The views' camera: it frames the robot from behind and above with no wall in between."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from drive_tree import ROOM, DriveTree

from bt_manip.run.runner import Runner, RunOptions
from bt_manip.sim.world import World
from bt_manip.viz.camera import (
    DEFAULT_OFFSET,
    candidate_offsets,
    clear_offset,
    hidden_rays,
    live_camera,
    look_height,
)
from bt_manip.viz.recorder import Recorder
from bt_manip.viz.replay_page import read_replay, track_samples
from bt_manip.viz.scene import ROOT

REPO = Path(__file__).resolve().parents[2]
HOUSE = REPO / "worlds" / "tb3_house.yaml"


def test_the_house_views_at_start_and_goal_are_clear_where_a_fixed_one_is_not() -> None:
    with World(HOUSE, seed=0) as world:
        robot = world.robots["husky"]
        x, y, yaw = robot.base_pose2d()
        goal = world.poses["goal"]
        for spot in (np.array([x, y]), np.array([goal.x, goal.y])):
            # the old fixed camera looked through a wall at both places
            assert hidden_rays(world, robot.body, [spot], DEFAULT_OFFSET) > 0
            offset = clear_offset(world, robot.body, [spot], yaw)
            assert hidden_rays(world, robot.body, [spot], offset) == 0
            assert offset in candidate_offsets(yaw)
            assert offset[2] > 1.0  # above the robot


def test_an_open_room_keeps_the_first_choice_behind_the_robot(room: World) -> None:
    robot = room.robots["husky"]
    x, y, yaw = robot.base_pose2d()
    view = live_camera(room)
    assert view.follow == f"{ROOT}/husky"
    assert view.target[:2] == pytest.approx((x, y))
    assert view.target[2] == pytest.approx(look_height(room, robot.body)) and view.target[2] > 0.2
    assert view.offset == candidate_offsets(yaw)[0]
    heading = np.array([np.cos(yaw), np.sin(yaw)])
    assert np.dot(np.array(view.offset[:2]), heading) < 0  # behind it


def test_the_replay_camera_sees_the_robot_at_the_first_and_last_frames(tmp_path: Path) -> None:
    page = tmp_path / "run.html"
    world = World(ROOM, seed=3)
    try:
        tree = DriveTree(world)
        recorder = Recorder(page, world, tree)
        Runner(tree, world, RunOptions(), on_tick=[recorder]).run()
        recorder.close()
        header, blobs = read_replay(page)
        camera = header["scene"]["camera"]
        assert camera["follow"] == f"{ROOT}/husky"
        base = track_samples(header, blobs, f"{ROOT}/husky")
        assert camera["target"][:2] == pytest.approx(base[0, :2], abs=1e-4)
        robot = world.robots["husky"].body
        ends = [base[0, :2].astype(float), base[-1, :2].astype(float)]
        assert hidden_rays(world, robot, ends, camera["offset"]) == 0
    finally:
        world.close()
