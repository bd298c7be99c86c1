"""IsBatteryLow, SmoothPath and the Cancel* nodes on the Husky in the small room."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pybullet as pb
import pytest

import bt_manip.nav2  # noqa: F401  (registers the Nav2 nodes)
from bt_manip.bt import Tree, load_tree_string
from bt_manip.errors import InputError
from bt_manip.nav2.path import Nav2Path
from bt_manip.run.context import RunContext
from bt_manip.run.report import RunReport
from bt_manip.run.runner import Runner, RunOptions
from bt_manip.sim.world import World
from bt_manip.sim.world_reader import parse_world

ROOM = Path(__file__).resolve().parent / "room.yaml"


@pytest.fixture
def room() -> Iterator[World]:
    with World(ROOM, seed=0) as world:
        yield world


def load(world: World, body: str, bb: dict[str, Any] | None = None,
         context: RunContext | None = None) -> Tree:
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="Main">{body}</BehaviorTree></root>'
    return load_tree_string(xml, context=context or RunContext.for_world(world),
                            blackboard=dict(bb or {}))


def run(world: World, body: str, bb: dict[str, Any] | None = None,
        max_sim_time: float = 60.0) -> tuple[RunReport, Tree]:
    tree = load(world, body, bb)
    return Runner(tree, world, RunOptions(max_sim_time=max_sim_time)).run(), tree


def battery_world(tmp_path: Path, battery: str) -> Path:
    text = ROOM.read_text().replace("    arm_state: tuck\n",
                                    f"    arm_state: tuck\n    battery: {battery}\n")
    path = tmp_path / "room_battery.yaml"
    path.write_text(text)
    return path


# -- IsBatteryLow --------------------------------------------------------------------------

def test_is_battery_low_reads_the_world_files_battery_as_it_drains(tmp_path: Path) -> None:
    path = battery_world(tmp_path, "{percentage: 0.5, voltage: 11.5, drain: 0.01}")
    with World(path, seed=0) as world:
        tree = load(world, '<IsBatteryLow min_battery="0.3"/>')
        volts = load(world, '<IsBatteryLow min_battery="11.6" is_voltage="true"/>')
        assert tree.tick().value == "FAILURE"  # 0.5 > 0.3
        assert tree.root.feedback_message == "battery at 0.500 > 0.3"
        assert volts.tick().value == "SUCCESS"  # 11.5 V <= 11.6 V
        world.step(int(25 * world.rate_hz))  # 25 s: 0.5 - 0.25 = 0.25 <= 0.3
        assert tree.tick().value == "SUCCESS"
        assert tree.root.feedback_message == "battery at 0.250 <= 0.3"


def test_is_battery_low_reads_the_topic_entry_first(room: World) -> None:
    body = '<IsBatteryLow min_battery="0.2"/>'
    assert load(room, body).tick().value == "FAILURE"  # no battery given: full
    assert load(room, body, {"battery_status": 0.15}).tick().value == "SUCCESS"
    assert load(room, body, {"battery_status": "0.25;11.9"}).tick().value == "FAILURE"
    topic = '<IsBatteryLow min_battery="11" is_voltage="true" battery_topic="/base/battery"/>'
    assert load(room, topic, {"base/battery": "0.9;10.5"}).tick().value == "SUCCESS"
    no_volts = load(room, topic, {"base/battery": 0.9})
    assert no_volts.tick().value == "FAILURE"
    assert "no voltage" in no_volts.root.feedback_message
    bad = load(room, body, {"battery_status": "full"})
    assert bad.tick().value == "FAILURE"
    assert "neither a percentage" in bad.root.feedback_message


def test_a_bad_battery_in_a_world_file_is_reported_with_its_line(tmp_path: Path) -> None:
    path = battery_world(tmp_path, "{percentage: 1.5, volts: 12}")
    with pytest.raises(InputError) as err:
        parse_world(path)
    text = "\n".join(str(p) for p in err.value.problems)
    assert "robots[0].battery.percentage must be within 0..1, got 1.5" in text
    assert "unknown key 'volts'" in text and "did you mean 'voltage'" in text
    assert f"{path}:" in text


# -- SmoothPath ----------------------------------------------------------------------------

def turn_angles(poses: np.ndarray) -> np.ndarray:
    d = np.diff(poses[:, :2], axis=0)
    keep = np.hypot(d[:, 0], d[:, 1]) > 1e-6
    h = np.arctan2(d[keep, 1], d[keep, 0])
    return np.abs(np.remainder(np.diff(h) + math.pi, math.tau) - math.pi)


def test_smooth_path_smooths_a_plan_keeping_its_ends_and_the_robot_follows_it(
        room: World) -> None:
    # round the crate: the plan bends; the smoothed path bends more gently
    pb.resetBasePositionAndOrientation(room.movable["crate"], [0.0, 0.0, 0.15], [0, 0, 0, 1],
                                       physicsClientId=room.client)
    room.step(24)
    report, tree = run(
        room,
        '<Sequence><ComputePathToPose goal="{goal}" path="{raw}"/>'
        '<SmoothPath unsmoothed_path="{raw}" smoothed_path="{path}" check_for_collisions="true"'
        ' was_completed="{done}" smoothing_duration="{took}" error_code_id="{code}"/>'
        '<FollowPath path="{path}" error_code_id="{fe}"/></Sequence>',
        {"goal": "1.8;0.5;0.0"},
    )
    assert report.status == "SUCCESS", report.reason
    raw, smooth = tree.blackboard.get("raw"), tree.blackboard.get("path")
    assert isinstance(smooth, Nav2Path) and smooth is not raw
    assert smooth.poses[0].tolist() == raw.poses[0].tolist()
    assert smooth.poses[-1].tolist() == raw.poses[-1].tolist()
    assert turn_angles(smooth.poses).max() < turn_angles(raw.poses).max()
    assert tree.blackboard.get("code") == 0 and tree.blackboard.get("took") == 0.0
    assert isinstance(tree.blackboard.get("done"), bool)
    x, y, _ = room.robots["husky"].base_pose2d()
    assert math.hypot(x - 1.8, y - 0.5) <= 0.25


def test_smooth_path_error_codes(room: World) -> None:
    report, tree = run(room, '<SmoothPath unsmoothed_path="{raw}" smoothed_path="{path}" '
                             'error_code_id="{code}" error_msg="{msg}"/>',
                       {"raw": Nav2Path(np.zeros((0, 3)))})
    assert report.status == "FAILURE"
    assert tree.blackboard.get("code") == 505  # INVALID_PATH
    assert "no path to smooth" in tree.blackboard.get("msg")
    # a plan that the crate now lies on: smoothing keeps it there, the check finds it
    plan = load(room, '<ComputePathToPose goal="{goal}" path="{raw}"/>', {"goal": "1.8;0.5;0.0"})
    assert plan.tick().value == "SUCCESS"
    raw = plan.blackboard.get("raw")
    mid = raw.poses[len(raw) // 2]
    pb.resetBasePositionAndOrientation(room.movable["crate"], [mid[0], mid[1], 0.15],
                                       [0, 0, 0, 1], physicsClientId=room.client)
    room.step(24)
    body = ('<SmoothPath unsmoothed_path="{raw}" smoothed_path="{path}" '
            'check_for_collisions="{check}" was_completed="{done}" error_code_id="{code}"/>')
    report, tree = run(room, body, {"raw": raw, "check": True})
    assert report.status == "FAILURE"
    assert tree.blackboard.get("code") == 503  # SMOOTHED_PATH_IN_COLLISION
    assert tree.blackboard.get("done") is False
    assert "crosses an obstacle" in report.reason
    report, tree = run(room, body, {"raw": raw, "check": False})
    assert report.status == "SUCCESS"  # Nav2's default: no check
    assert tree.blackboard.get("code") == 0


# -- Cancel* -------------------------------------------------------------------------------

def test_cancel_control_stops_the_running_follow_path_which_then_succeeds(room: World) -> None:
    x0, y0, _ = room.robots["husky"].base_pose2d()
    report, tree = run(
        room,
        '<Sequence><ComputePathToPose goal="{goal}" path="{path}"/>'
        '<Parallel success_count="2" failure_count="1">'
        '<FollowPath path="{path}" error_code_id="{fe}"/>'
        '<Sequence><Sleep msec="2000"/><CancelControl/></Sequence>'
        "</Parallel></Sequence>",
        {"goal": "1.8;0.5;0.0"},
    )
    assert report.status == "SUCCESS", report.reason
    assert tree.blackboard.get("fe") == 0
    x, y, _ = room.robots["husky"].base_pose2d()
    gone = math.hypot(x - x0, y - y0)
    assert gone > 0.3 and math.hypot(x - 1.8, y - 0.5) > 1.0  # stopped on the way
    room.step(int(room.rate_hz))  # braked: it does not drive on
    x1, y1, _ = room.robots["husky"].base_pose2d()
    assert math.hypot(x1 - x, y1 - y) < 0.1
    follow = next(n for n in tree.root.iterate() if n.name == "FollowPath")
    assert follow.feedback_message.startswith("cancelled: CancelControl")


@pytest.mark.parametrize(("action", "cancel"), [
    ('<Wait wait_duration="30"/>', "CancelWait"),
    ('<Spin spin_dist="6.0" time_allowance="60"/>', "CancelSpin"),
    ('<BackUp backup_dist="1.0" backup_speed="0.05" time_allowance="60"/>', "CancelBackUp"),
    ('<DriveOnHeading dist_to_travel="1.0" speed="0.05" time_allowance="60"/>',
     "CancelDriveOnHeading"),
])
def test_cancel_behaviours_end_them_early(room: World, action: str, cancel: str) -> None:
    report, _ = run(room, f'<Parallel success_count="2" failure_count="1">{action}'
                          f'<Sequence><Sleep msec="2000"/><{cancel}/></Sequence></Parallel>')
    assert report.status == "SUCCESS", report.reason
    assert report.sim_time < 3.0  # the action would take 20 s or more


def test_a_cancel_with_nothing_running_succeeds_and_leaves_other_actions(room: World) -> None:
    report, tree = run(room, '<Parallel success_count="2" failure_count="1">'
                             '<Wait wait_duration="3"/>'
                             '<Sequence><Sleep msec="500"/><CancelSpin/></Sequence></Parallel>')
    assert report.status == "SUCCESS"
    assert report.sim_time >= 3.0  # the Wait was not cancelled
    cancel = next(n for n in tree.root.iterate() if n.name == "CancelSpin")
    assert cancel.feedback_message == "no Spin running on husky"
