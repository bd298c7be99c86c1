"""Navigation of a holonomic base: the follower on an ideal base (sideways, heading, limits,
stuck), and ``Navigate`` driving the shipped omni_sawyer robot in PyBullet (sideways without
turning, around an obstacle to a heading, halted and braked)."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pybullet as pb
import pytest
from tree_files import write_tree

from bt_manip.cli import main
from bt_manip.episode import Episode, EpisodeSpec
from bt_manip.navigation.controller import FollowerOptions, FollowState, wrap
from bt_manip.navigation.footprint import PlanarFootprint
from bt_manip.navigation.holonomic import HolonomicFollower, turning_footprint
from bt_manip.navigation.smoothing import densify

TICK = 0.05


def _ideal_drive(
    follower: HolonomicFollower, pose: tuple[float, float, float], seconds: float,
    frozen: bool = False,
) -> tuple[FollowState, str, list[tuple[float, float, float]], list[tuple[float, float, float]]]:
    """Apply each command to a base that moves exactly as told (``frozen``: not at all)."""
    poses = [pose]
    commands = []
    t = 0.0
    status = follower.update(pose, t)
    while status.state is FollowState.RUNNING and t < seconds:
        vx, vy, w = status.velocity
        commands.append((vx, vy, w))
        if not frozen:
            x, y, yaw = pose
            mid = yaw + 0.5 * w * TICK
            c, s = math.cos(mid), math.sin(mid)
            pose = (x + (c * vx - s * vy) * TICK, y + (s * vx + c * vy) * TICK, yaw + w * TICK)
        poses.append(pose)
        t += TICK
        status = follower.update(pose, t)
    return status.state, status.reason, poses, commands


def test_goal_to_the_left_is_reached_sideways() -> None:
    path = np.column_stack([np.zeros(41), np.linspace(0.0, 2.0, 41)])
    follower = HolonomicFollower(path, (0.0, 2.0, 0.0))
    state, reason, poses, commands = _ideal_drive(follower, (0.0, 0.0, 0.0), 30.0)
    assert state is FollowState.SUCCEEDED, reason
    assert math.dist(poses[-1][:2], (0.0, 2.0)) <= 0.1
    assert max(abs(p[2]) for p in poses) < 1e-6  # never turned
    assert max(abs(c[0]) for c in commands) < 1e-6  # never drove forward
    assert max(c[1] for c in commands) == pytest.approx(FollowerOptions().max_speed, rel=0.01)


def test_turns_to_the_goal_heading_on_the_way_within_the_limits() -> None:
    opts = FollowerOptions(max_speed=0.5, max_accel=0.5, max_yaw_rate=1.0, max_yaw_accel=2.0)
    path = np.column_stack([np.linspace(0.0, 2.0, 41), np.linspace(0.0, 1.0, 41)])
    follower = HolonomicFollower(path, (2.0, 1.0, 2.5), opts)
    state, reason, poses, commands = _ideal_drive(follower, (0.0, 0.0, -0.5), 30.0)
    assert state is FollowState.SUCCEEDED, reason
    x, y, yaw = poses[-1]
    assert math.dist((x, y), (2.0, 1.0)) <= opts.xy_tolerance
    assert abs(wrap(yaw - 2.5)) <= opts.yaw_tolerance
    world_v = [
        (c * vx - s * vy, s * vx + c * vy)
        for (vx, vy, _), (_, _, a) in zip(commands, poses, strict=False)
        for c, s in [(math.cos(a), math.sin(a))]
    ]
    assert max(math.hypot(*v) for v in world_v) <= opts.max_speed + 1e-9
    assert max(abs(cmd[2]) for cmd in commands) <= opts.max_yaw_rate + 1e-9
    steps = [math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in itertools.pairwise(world_v)]
    assert max(steps) <= opts.max_accel * TICK * 1.05  # (a turning base re-aims mid-tick)


def test_keeps_to_the_path_round_a_right_angle() -> None:
    """It slows down for the corner and does not cut it: the planner's margin (8 cm beyond the
    swept disc) is kept."""
    path = densify(np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0]]), 0.05)
    follower = HolonomicFollower(path, (2.0, 2.0, 0.0))
    state, reason, poses, _ = _ideal_drive(follower, (0.0, 0.0, 0.0), 30.0)
    assert state is FollowState.SUCCEEDED, reason

    def off_path(x: float, y: float) -> float:
        return min(math.hypot(x - min(max(x, 0.0), 2.0), y),
                   math.hypot(x - 2.0, y - min(max(y, 0.0), 2.0)))

    assert max(off_path(x, y) for x, y, _ in poses) < 0.03


def test_a_base_that_does_not_move_is_stuck() -> None:
    path = np.column_stack([np.linspace(0.0, 1.0, 21), np.zeros(21)])
    follower = HolonomicFollower(path, (1.0, 0.0, 0.0), FollowerOptions(stuck_time=2.0))
    state, reason, _, _ = _ideal_drive(follower, (0.0, 0.0, 0.0), 10.0, frozen=True)
    assert state is FollowState.FAILED
    assert reason.startswith("stuck: no progress for 2.0 s, 1.00 m")


def test_planned_as_the_disc_it_sweeps() -> None:
    fp = PlanarFootprint.rectangle(0.6, 0.5, 0.1)
    disc = turning_footprint(fp)
    assert disc.half_width == pytest.approx(fp.circumradius)
    assert disc.circumradius == pytest.approx(fp.circumradius)


# -- Navigate with the omni_sawyer robot in PyBullet -------------------------------------------
WORLD = """\
name: holonomic_test
robots:
  - {{name: omni, description: omni_sawyer, pose: [0.0, 0.0, 0.0], arm_state: tuck}}
walls:
  - {{name: south, from: [-2.0, -2.0], to: [4.0, -2.0], thickness: 0.1, height: 1.0}}
  - {{name: north, from: [-2.0, 3.0], to: [4.0, 3.0], thickness: 0.1, height: 1.0}}
furniture:
{furniture}
"""
CRATE = "  - {name: crate, pose: [1.5, 0.0, 0.0], parts: [{shape: box, size: [0.6, 0.8, 0.6], " \
    "xyz: [0, 0, 0.3]}]}"
NONE = "  []"


def _episode(tmp_path: Path, tree: str, furniture: str = NONE) -> Episode:
    (tmp_path / "world.yaml").write_text(WORLD.format(furniture=furniture))
    (tmp_path / "tree.xml").write_text(
        f'<root BTCPP_format="4"><BehaviorTree ID="Main">{tree}</BehaviorTree></root>\n'
    )
    return Episode(EpisodeSpec(tree=str(tmp_path / "tree.xml"), world=str(tmp_path / "world.yaml")))


def test_navigate_reaches_a_goal_to_the_left_without_turning(tmp_path: Path) -> None:
    yaws: list[float] = []
    with _episode(tmp_path, '<Navigate goal="0;1.5;0" xy_tolerance="0.05"/>') as episode:
        robot = episode.world.robots["omni"]
        report = episode.run(hooks=[lambda _: yaws.append(robot.base_pose2d()[2])])
        assert report.status == "SUCCESS", report.reason
        x, y, yaw = robot.base_pose2d()
    assert math.hypot(x, y - 1.5) <= 0.05 and abs(yaw) <= 0.1
    assert len(yaws) > 20
    assert max(abs(a) for a in yaws) < math.radians(3.0)


def test_navigate_around_an_obstacle_to_a_heading(tmp_path: Path) -> None:
    touched: set[int] = set()
    tree = '<Navigate goal="3.0;0.0;1.5708" xy_tolerance="0.05" yaw_tolerance="0.05"/>'
    with _episode(tmp_path, tree, CRATE) as episode:
        world = episode.world
        robot = world.robots["omni"]
        crate = world.body_id("crate")

        def watch(_: object) -> None:
            touched.update(c[2] for c in pb.getContactPoints(
                bodyA=robot.body, bodyB=crate, physicsClientId=world.client))

        report = episode.run(hooks=[watch])
        assert report.status == "SUCCESS", report.reason
        x, y, yaw = robot.base_pose2d()
    assert math.hypot(x - 3.0, y) <= 0.05 and abs(wrap(yaw - 1.5708)) <= 0.05
    assert not touched


def test_halting_navigate_brakes_the_base(tmp_path: Path) -> None:
    tree = '<Timeout msec="2500"><Navigate goal="3.0;2.0;0"/></Timeout>'
    with _episode(tmp_path, tree) as episode:
        report = episode.run()
        assert report.status == "FAILURE"
        world = episode.world
        robot = world.robots["omni"]
        moved = robot.base_pose2d()
        assert math.hypot(*moved[:2]) > 0.3  # it was on its way when halted
        world.step(240)
        here = robot.base_pose2d()
        world.step(480)
        there = robot.base_pose2d()
    assert math.dist(here[:2], there[:2]) < 0.005 and abs(there[2] - here[2]) < 0.005
    assert math.dist(moved[:2], here[:2]) < 0.1  # it stopped within its braking distance


def test_reverse_backs_a_holonomic_base_straight(tmp_path: Path) -> None:
    with _episode(tmp_path, '<Reverse distance="0.3" speed="0.2"/>') as episode:
        report = episode.run()
        assert report.status == "SUCCESS", report.reason
        x, y, yaw = episode.world.robots["omni"].base_pose2d()
    assert -0.4 < x <= -0.3 and abs(y) < 0.01 and abs(yaw) < 0.01


@pytest.mark.parametrize(("node", "attrs"), [
    ("GetClear", ""),
    ("PlanBaseForGrasp", ' object="block_0" base_pose="{b}"'),
])
def test_skid_steer_only_nodes_say_why_they_refuse_a_holonomic_base(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], node: str, attrs: str
) -> None:
    tree = write_tree(tmp_path, f'<{node} name="n"{attrs}/>')
    world = Path(__file__).resolve().parents[2] / "worlds" / "omni_sawyer_room.yaml"
    assert main(["run", str(tree), "--world", str(world), "--quiet"]) == 1
    first = capsys.readouterr().out.splitlines()[0]
    assert first == (
        f"result: FAILURE (n: omni_sawyer has a holonomic base; {node} drives skid-steer "
        "bases only (Navigate and Reverse drive every mobile base))"
    )
