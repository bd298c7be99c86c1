"""World groups: several entities moved by one rigid motion, fixed or drawn per seed."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pybullet as pb
import pytest

from bt_manip.cli import main
from bt_manip.errors import InputError
from bt_manip.sim.randomize import Rigid2D, place_groups
from bt_manip.sim.world import World
from bt_manip.sim.world_reader import parse_world
from bt_manip.sim.world_spec import Pose2D

ROOT = Path(__file__).resolve().parents[2]

BASE = """\
name: grouped
furniture:
  - {name: stand, shape: box, size: [0.6, 0.1, 0.05], pose: [1.0, 1.0, 0.3]}
  - {name: shelf, shape: box, size: [0.3, 0.3, 0.3], pose: [-2.0, -2.0, 0.0]}
objects:
  - {name: plank, shape: box, size: [0.5, 0.02, 0.1], mass: 0.5,
     pose: {xyz: [1.0, 1.0, 0.1], rpy: [0.0, 0.0, 0.3]}}
  - {name: ball, shape: sphere, radius: 0.05, mass: 0.1, pose: [3.0, 0.0, 0.0],
     randomize: {x: [-0.1, 0.1]}}
models:
  - {name: spare, shape: box, size: [0.1, 0.1, 0.1], mass: 0.1, pose: [1.5, 0.5, 0.0]}
poses:
  near_stand: [0.4, 1.2, -0.5]
  far: [-3.0, 3.0, 0.0]
"""


def write(tmp_path: Path, groups: str, name: str = "grouped.yaml") -> Path:
    path = tmp_path / name
    path.write_text(BASE + groups)
    return path


GROUP = """\
groups:
  - name: plank_set
    members: [plank, stand, spare, near_stand]
    move: [0.5, -0.25, 0.4]
    randomize: {x: [-0.3, 0.3], y: [-0.3, 0.3], yaw: [-0.5, 0.5]}
"""


def relative(a: Pose2D, b: Pose2D) -> tuple[float, float, float]:
    """``b`` seen from ``a``."""
    dx, dy = b.x - a.x, b.y - a.y
    c, s = math.cos(a.yaw), math.sin(a.yaw)
    return c * dx + s * dy, -s * dx + c * dy, math.remainder(b.yaw - a.yaw, math.tau)


def planar(world: World, name: str) -> Pose2D:
    """A body's frame as placed in the world (its spec pose, which the world built)."""
    body = next(b for b in world.spec.furniture + world.spec.objects + world.spec.models
                if b.name == name)
    yaw = pb.getEulerFromQuaternion(body.pose.quat)[2]
    return Pose2D(body.pose.xyz[0], body.pose.xyz[1], yaw)


def test_members_keep_their_relative_poses_and_named_poses_move(tmp_path: Path) -> None:
    path = write(tmp_path, GROUP)
    file_spec = parse_world(path)
    before = {b.name: b for b in file_spec.furniture + file_spec.objects + file_spec.models}
    for seed in (0, 1, 7):
        with World(path, seed=seed) as world:
            move = world.group_moves["plank_set"]
            assert 0.2 <= move.dx <= 0.8 and -0.55 <= move.dy <= 0.05
            assert 0.4 - 0.5 <= move.dyaw <= 0.4 + 0.5
            stand, plank, spare = (planar(world, n) for n in ("stand", "plank", "spare"))
            near = world.poses["near_stand"]
            # each member moved by the group's transform...
            expected = move.pose2d(Pose2D(1.0, 1.0, 0.3))
            assert plank.x == pytest.approx(expected.x, abs=1e-12)
            assert plank.y == pytest.approx(expected.y, abs=1e-12)
            # ...so the members are where they were relative to each other
            orig_stand = Pose2D(1.0, 1.0, 0.3)
            for now, was in ((plank, Pose2D(1.0, 1.0, 0.3)), (spare, Pose2D(1.5, 0.5, 0.0)),
                             (near, Pose2D(0.4, 1.2, -0.5))):
                assert relative(stand, now) == pytest.approx(relative(orig_stand, was), abs=1e-9)
            # the plank keeps its height
            got = next(b for b in world.spec.objects if b.name == "plank")
            assert got.pose.xyz[2] == before["plank"].pose.xyz[2]
            # the simulated plank is where the placed spec says
            pos, quat = pb.getBasePositionAndOrientation(
                world.body_id("plank"), physicsClientId=world.client
            )
            assert pos[0] == pytest.approx(expected.x, abs=1e-6)
            assert pb.getEulerFromQuaternion(quat)[2] == pytest.approx(
                math.remainder(expected.yaw, math.tau), abs=1e-6
            )
            # non-members stay put
            assert world.poses["far"] == Pose2D(-3.0, 3.0, 0.0)
            assert planar(world, "shelf") == Pose2D(-2.0, -2.0, 0.0)
            # a model spawned later comes up moved with its group
            world.spawn_model("spare")
            spawned = pb.getBasePositionAndOrientation(
                world.body_id("spare"), physicsClientId=world.client
            )[0]
            assert spawned[:2] == pytest.approx((spare.x, spare.y), abs=1e-6)


def test_group_moves_are_seeded_and_repeatable(tmp_path: Path) -> None:
    path = write(tmp_path, GROUP)
    spec = parse_world(path)
    moves = [place_groups(spec, seed)[1]["plank_set"] for seed in range(5)]
    again = [place_groups(spec, seed)[1]["plank_set"] for seed in range(5)]
    assert moves == again
    assert len({(m.dx, m.dy, m.dyaw) for m in moves}) == 5
    # the ball's own randomisation does not depend on the group
    plain = write(tmp_path, "", name="plain.yaml")
    assert parse_world(plain).groups == []
    with World(path, seed=3) as a, World(plain, seed=3) as b:
        assert a.body_pose("ball") == b.body_pose("ball")
        assert a.body_pose("plank") != b.body_pose("plank")


def test_origin_is_the_pivot_and_defaults_to_the_members_centre(tmp_path: Path) -> None:
    spec = parse_world(write(tmp_path, """\
groups:
  - name: a
    members: [stand, near_stand]
    move: [0.0, 0.0, 1.5707963267948966]
  - name: b
    members: [shelf]
    origin: [-2.0, -1.0]
    move: [0.0, 0.0, 3.141592653589793]
"""))
    a, b = spec.groups
    assert a.origin == pytest.approx((0.7, 1.1))
    placed, _ = place_groups(spec, 0)
    shelf = next(f for f in placed.furniture if f.name == "shelf")
    # half a turn about (-2, -1) takes (-2, -2) to (-2, 0)
    assert shelf.pose.xyz[:2] == pytest.approx((-2.0, 0.0), abs=1e-12)
    assert b.origin == (-2.0, -1.0)


def test_rigid2d_composes_a_turn_about_the_origin_and_a_shift() -> None:
    t = Rigid2D((1.0, 1.0), dx=0.5, dy=0.0, dyaw=math.pi / 2)
    assert t.point(2.0, 1.0) == pytest.approx((1.5, 2.0))
    assert t.pose2d(Pose2D(1.0, 1.0, 0.2)) == pytest.approx((1.5, 1.0, 0.2 + math.pi / 2))
    q = t.pose3d(parse_pose_with_roll()).quat
    r = np.array(pb.getMatrixFromQuaternion(q)).reshape(3, 3)
    # the body's x axis (pointing along world x, rolled) now points along world y
    assert r[:, 0] == pytest.approx((0.0, 1.0, 0.0), abs=1e-12)


def parse_pose_with_roll() -> object:
    from bt_manip.sim.world_spec import Pose3D

    return Pose3D((0.0, 0.0, 0.5), tuple(pb.getQuaternionFromEuler([0.4, 0.0, 0.0])))


BAD_GROUPS = """\
groups:
  - name: g
    members: [plank, stnd, near_stand, near_stand]
    move: [1, 2]
    randomize: {x: [0.1, -0.1], yaw: [-9, 0.3]}
  - name: h
    members: [near_stand, ball, wall_a, spare]
    origin: [0, 0, 0]
  - name: shelf
    members: []
  - name: g
    members: [far]
    surprise: 1
"""


def test_bad_groups_are_reported_with_file_line_and_problem(tmp_path: Path) -> None:
    path = tmp_path / "grouped.yaml"
    path.write_text(BASE.replace("furniture:\n", "walls:\n  - {name: wall_a, from: [5, 5], "
                                 "to: [6, 5]}\nfurniture:\n") + BAD_GROUPS)
    with pytest.raises(InputError) as info:
        parse_world(path)
    found = [(p.line, p.message) for p in info.value.problems]
    start = path.read_text().splitlines().index("groups:") + 1

    def has(offset: int, text: str) -> bool:
        return any(line == start + offset and text in msg for line, msg in found)

    assert has(2, "unknown member 'stnd'; did you mean 'stand'?"), found
    assert has(2, "'near_stand' is listed twice in this group"), found
    assert has(3, "groups[0].move ([dx, dy, dyaw]) must be a list of 3 numbers"), found
    assert has(4, "groups[0].randomize.x: low 0.1 > high -0.1"), found
    assert has(4, "groups[0].randomize.yaw must lie within +-6.283 rad"), found
    assert has(6, "'near_stand' is already in group 'g'"), found
    assert has(6, "'ball' has a randomize of its own"), found
    assert has(6, "'wall_a' is a wall; a group moves objects, furniture, models and named "
               "poses only"), found
    assert has(7, "groups[1].origin ([x, y]) must be a list of 2 numbers"), found
    assert has(8, "group name 'shelf' is already the name of an entity"), found
    assert has(9, "groups[2] ('shelf') needs 'members'"), found
    assert has(10, "group name 'g' is used twice"), found
    assert has(12, "unknown key 'surprise' in groups[3]"), found


def test_the_cli_exits_2_on_a_bad_group(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write(tmp_path, "groups:\n  - name: g\n    members: [plank, nothing_here]\n")
    assert main(["world", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    members_line = BASE.count("\n") + 3
    assert err == [
        f"{path}:{members_line}: groups[0].members: unknown member 'nothing_here'; known: "
        "ball, far, near_stand, plank, shelf, spare, stand"
    ]


def test_a_group_moved_into_something_is_reported_as_overlapping(tmp_path: Path) -> None:
    # the plank moved onto the shelf starts inside it
    path = write(tmp_path, "groups:\n  - name: g\n    members: [plank]\n"
                 "    move: [-3.0, -3.0, 0.0]\n")
    with pytest.raises(InputError) as info:
        World(path, seed=0)
    assert any("'plank' and 'shelf' overlap" in p.message for p in info.value.problems)


VARIANTS = ["turned", "turned_ccw", "north", "west", "south", "random"]


@pytest.mark.parametrize("variant", VARIANTS)
def test_the_panel_variants_load_with_the_panel_set_moved_together(variant: str) -> None:
    path = ROOT / "worlds" / f"tb3_house_panel_{variant}.yaml"
    with World(ROOT / "worlds" / "tb3_house.yaml", seed=0) as house:
        base_pre = house.poses["pregrasp_panel"]
        base_panel = planar(house, "panel")
    for seed in (0, 1, 2) if variant == "random" else (0,):
        with World(path, seed=seed) as world:
            move = world.group_moves["panel_set"]
            assert not move.is_identity()
            pre, panel = world.poses["pregrasp_panel"], planar(world, "panel")
            # the grasp geometry is the original one, wherever the set went
            assert relative(pre, panel) == pytest.approx(relative(base_pre, base_panel),
                                                         abs=1e-9)
            assert planar(world, "panel_stand")[:2] == pytest.approx(panel[:2], abs=1e-9)
            assert world.poses["start"] == house.poses["start"]
