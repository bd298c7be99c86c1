"""Nav2's action nodes on the Husky in a small room: planning, following, behaviours, clearing."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import bt_manip.nav2  # noqa: F401  (registers the Nav2 nodes)
from bt_manip.bt import Tree, load_tree_string
from bt_manip.nav2.path import Nav2Path
from bt_manip.run.context import RunContext
from bt_manip.run.report import RunReport
from bt_manip.run.runner import Runner, RunOptions
from bt_manip.sim.world import World

ROOM = Path(__file__).resolve().parent / "room.yaml"


_CONTEXTS: dict[int, RunContext] = {}


def context_of(world: World) -> RunContext:
    """One run context per world of a test, so that the trees a test runs one after the other
    share the robot's navigator (as the nodes of one tree do)."""
    context = _CONTEXTS.get(id(world))
    if context is None or context.world is not world:
        context = _CONTEXTS[id(world)] = RunContext.for_world(world)
    return context


@pytest.fixture
def room() -> Iterator[World]:
    with World(ROOM, seed=0) as world:
        yield world
    _CONTEXTS.clear()


def run(world: World, body: str, bb: dict[str, Any] | None = None,
        max_sim_time: float = 60.0) -> tuple[RunReport, dict[str, Any]]:
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="Main">{body}</BehaviorTree></root>'
    tree: Tree = load_tree_string(
        xml, context=context_of(world), blackboard=dict(bb or {})
    )
    report = Runner(tree, world, RunOptions(max_sim_time=max_sim_time)).run()
    entries = {key: tree.blackboard.get(key) for key in tree.blackboard.as_dict()}
    return report, entries


def yaw_gap(a: float, b: float) -> float:
    return abs(math.remainder(a - b, math.tau))


def test_compute_path_then_follow_path_reaches_the_goal(room: World) -> None:
    x0, y0, _ = room.robots["husky"].base_pose2d()
    report, bb = run(
        room,
        '<Sequence><ComputePathToPose goal="{goal}" path="{path}" error_code_id="{pe}"/>'
        '<FollowPath path="{path}" error_code_id="{fe}" error_msg="{fm}"/></Sequence>',
        {"goal": "1.8;0.5;1.0"},
    )
    assert report.status == "SUCCESS", report.reason
    x, y, yaw = room.robots["husky"].base_pose2d()
    assert math.hypot(x - 1.8, y - 0.5) <= 0.25
    assert yaw_gap(yaw, 1.0) <= 0.25
    path = bb["path"]
    assert isinstance(path, Nav2Path)
    assert path.goal == pytest.approx((1.8, 0.5, 1.0))
    assert math.hypot(path.poses[0, 0] - x0, path.poses[0, 1] - y0) <= 0.3
    assert path.length >= math.hypot(1.8 - x0, 0.5 - y0) - 0.05
    assert (bb["pe"], bb["fe"], bb["fm"]) == (0, 0, "")


def test_compute_path_failures_carry_nav2_result_codes(room: World) -> None:
    body = '<ComputePathToPose goal="{goal}" path="{path}" error_code_id="{code}" ' \
           'error_msg="{msg}"/>'
    report, bb = run(room, body, {"goal": "inside_wall"})
    assert report.status == "FAILURE"
    assert bb["code"] == 206  # GOAL_OCCUPIED
    assert "inside an obstacle" in bb["msg"]
    assert "path" not in bb
    report, bb = run(room, body, {"goal": "40;0;0"})
    assert (report.status, bb["code"]) == ("FAILURE", 204)  # GOAL_OUTSIDE_MAP


def test_follow_path_without_a_path_is_an_invalid_path(room: World) -> None:
    report, bb = run(room, '<FollowPath path="{path}" error_code_id="{code}"/>',
                     {"path": "not a path"})
    assert report.status == "FAILURE"
    assert bb["code"] == 103  # INVALID_PATH


@pytest.mark.parametrize("dist", [1.57, -1.0])
def test_spin_turns_the_base_by_spin_dist(room: World, dist: float) -> None:
    x0, y0, yaw0 = room.robots["husky"].base_pose2d()
    report, bb = run(room, f'<Spin spin_dist="{dist}" error_code_id="{{code}}"/>')
    assert report.status == "SUCCESS", report.reason
    x, y, yaw = room.robots["husky"].base_pose2d()
    assert yaw_gap(yaw, yaw0 + dist) <= 0.15
    assert math.hypot(x - x0, y - y0) <= 0.3  # on the spot (a skid-steer pivots ahead)
    assert bb["code"] == 0


def test_back_up_reverses_by_backup_dist(room: World) -> None:
    x0, y0, _ = room.robots["husky"].base_pose2d()
    report, _ = run(room, '<BackUp backup_dist="0.3" backup_speed="0.1"/>')
    assert report.status == "SUCCESS", report.reason
    x, y, _ = room.robots["husky"].base_pose2d()
    assert 0.3 <= math.hypot(x - x0, y - y0) <= 0.4
    assert x < x0  # backwards: the robot faces +x


def test_back_up_into_a_wall_stops_with_collision_ahead(room: World) -> None:
    x0, _, _ = room.robots["husky"].base_pose2d()
    report, bb = run(room, '<BackUp backup_dist="2.0" backup_speed="0.2" '
                           'error_code_id="{code}" error_msg="{msg}"/>')
    assert report.status == "FAILURE"
    assert bb["code"] == 703  # COLLISION_AHEAD
    assert "wall_west" in bb["msg"]
    x, _, _ = room.robots["husky"].base_pose2d()
    assert x0 - 1.0 < x < x0 - 0.3  # it went back until the wall, not through it


def test_wait_waits_wait_duration_of_sim_time(room: World) -> None:
    before = room.clock.now()
    report, _ = run(room, '<Wait wait_duration="2"/>')
    assert report.status == "SUCCESS"
    assert 2.0 <= room.clock.now() - before <= 2.2


def test_clear_entire_costmap_forgets_what_the_map_marked(room: World) -> None:
    report, _ = run(room, '<ComputePathToPose goal="east" path="{path}"/>')
    assert report.status == "SUCCESS", report.reason
    nav = context_of(room).robot_services("husky").navigator
    crate = room.movable["crate"]
    assert crate in nav.costmap.grid.sources  # the crate is marked
    report, _ = run(room, '<ClearEntireCostmap service_name="local_costmap/clear"/>')
    assert report.status == "SUCCESS"
    assert not nav.costmap.grid.sources
    assert not np.any(nav.costmap.grid.occupied & ~nav.static.occupied)


def place(world: World, x: float, y: float, yaw: float = 0.0) -> None:

    world.robots["husky"].reset_base_pose(x, y, yaw)
    world.step(24)


def load(world: World, body: str, bb: dict[str, Any] | None = None) -> Tree:
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="Main">{body}</BehaviorTree></root>'
    return load_tree_string(
        xml, context=context_of(world), blackboard=dict(bb or {})
    )


def test_goal_reached_within_a_quarter_metre(room: World) -> None:
    x, y, _ = room.robots["husky"].base_pose2d()
    near = load(room, '<GoalReached goal="{goal}"/>', {"goal": f"{x + 0.2};{y};3.0"})
    far = load(room, '<GoalReached goal="{goal}"/>', {"goal": f"{x + 0.4};{y};0.0"})
    assert near.tick().value == "SUCCESS"
    assert far.tick().value == "FAILURE"


def test_distance_traveled_and_distance_controller_follow_the_robot(room: World) -> None:
    cond = load(room, '<DistanceTraveled distance="0.5"/>').root
    tree = load(room, '<PipelineSequence><DistanceController distance="0.5">'
                      '<Script code="n += 1"/></DistanceController>'
                      '<Wait wait_duration="100"/></PipelineSequence>', {"n": 0})
    seen = []
    for x in (-1.8, -1.6, -1.2, -1.0, -0.6):
        place(room, x, 0.0)
        assert tree.tick().value == "RUNNING"
        seen.append((cond.execute_tick().value, tree.blackboard.get("n")))
    # DistanceController: its child at once, then each 0.5 m from where it last succeeded
    assert [n for _, n in seen] == [1, 1, 2, 2, 3]
    # DistanceTraveled: records at -1.8, succeeds at -1.2 (0.6 m), then at -0.6 (0.6 m)
    assert [s for s, _ in seen] == ["FAILURE", "FAILURE", "SUCCESS", "FAILURE", "SUCCESS"]


def test_is_path_valid_until_an_object_lands_on_the_path(room: World) -> None:
    import pybullet as pb

    tree = load(room, '<Sequence><ComputePathToPose goal="east" path="{path}"/>'
                      '<IsPathValid path="{path}"/></Sequence>')
    assert tree.tick().value == "SUCCESS"
    path = tree.blackboard.get("path")
    mid = path.poses[len(path) // 2]
    crate = room.movable["crate"]
    pb.resetBasePositionAndOrientation(crate, [mid[0], mid[1], 0.15], [0, 0, 0, 1],
                                       physicsClientId=room.client)
    room.step(24)
    check = load(room, '<IsPathValid path="{path}"/>', {"path": path})
    assert check.tick().value == "FAILURE"
    assert "obstacle lies on the path" in check.root.feedback_message


@pytest.mark.parametrize(("node", "kept"), [("ClearCostmapAroundRobot", True),
                                            ("ClearCostmapExceptRegion", False)])
def test_clearing_round_the_robot_or_except_there(room: World, node: str, kept: bool) -> None:
    report, _ = run(room, '<ComputePathToPose goal="east" path="{path}"/>')
    assert report.status == "SUCCESS", report.reason
    nav = context_of(room).robot_services("husky").navigator
    crate = room.movable["crate"]  # about 4 m from the robot
    report, _ = run(room, f'<{node} reset_distance="1.5"/>')
    assert report.status == "SUCCESS"
    assert (crate in nav.costmap.grid.sources) is kept
    assert nav.costmap.grid.occupied.sum() > nav.static.occupied.sum() or not kept


def test_speed_controller_ticks_slowly_while_the_robot_stands_and_at_once_on_a_new_goal(
    room: World,
) -> None:
    tree = load(room, '<PipelineSequence><SpeedController min_rate="0.2" max_rate="2.0">'
                      '<Script code="n += 1"/></SpeedController>'
                      '<Wait wait_duration="100"/></PipelineSequence>', {"n": 0, "goal": "a"})
    counts = []
    for k in range(120):  # 6 s of sim time at 20 Hz
        if k == 110:
            tree.blackboard.set("goal", "b")
        tree.tick()
        room.step(12)
        counts.append(tree.blackboard.get("n"))
    # standing still: 0.2 Hz, so once at the start and once 5 s later; a new goal: at once
    assert counts[0] == 1
    assert counts[90] == 1
    assert counts[105] == 2
    assert counts[110] == 3


def test_is_stuck_on_a_sudden_stop(room: World) -> None:
    import pybullet as pb

    robot = room.robots["husky"]
    cond = load(room, "<IsStuck/>")
    pb.resetBaseVelocity(robot.body, [1.0, 0, 0], [0, 0, 0], physicsClientId=room.client)
    assert cond.tick().value == "FAILURE"  # nothing to compare with yet
    room.step(1)
    pb.resetBaseVelocity(robot.body, [0.9, 0, 0], [0, 0, 0], physicsClientId=room.client)
    room.step(11)
    pb.resetBaseVelocity(robot.body, [0.9, 0, 0], [0, 0, 0], physicsClientId=room.client)
    assert cond.tick().value == "FAILURE"  # slowing down gently
    room.step(12)
    pb.resetBaseVelocity(robot.body, [0.0, 0, 0], [0, 0, 0], physicsClientId=room.client)
    assert cond.tick().value == "SUCCESS"  # 0.9 m/s to rest within a tick: it hit something


def test_transform_available_for_the_world_the_base_and_links(room: World) -> None:
    ok = load(room, '<TransformAvailable parent="map" child="base_link"/>')
    assert ok.tick().value == "SUCCESS"
    missing = load(room, '<TransformAvailable parent="map" child="laser_frame"/>')
    assert missing.tick().value == "FAILURE"
    assert "laser_frame" in missing.root.feedback_message
