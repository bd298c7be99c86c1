"""The simulated laser against ranges worked out by hand, against PyBullet's own ray test,
and on what it must and must not see."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pybullet as pb
import pytest

from bt_manip.sensing.lidar import Lidar, Scan
from bt_manip.sensing.sensors import LidarSpec
from bt_manip.sim.world import World
from bt_manip.sim.world_spec import BodySpec, Part, Pose3D, Range2D
from tests.sensing.worlds import ROOM, spawn_held, write

FRONT = LidarSpec("front", "top_plate_link", xyz=(0.45, 0.0, 0.104), fov_deg=180.0, beams=181,
                  range_m=10.0, noise_m=0.0)
"""The Husky's laser narrowed to 180 degrees: its own wheels stay out of sight."""


@pytest.fixture(scope="module")
def room(tmp_path_factory: pytest.TempPathFactory) -> World:
    world = World(write(tmp_path_factory.mktemp("room"), ROOM))
    yield world
    world.close()


@pytest.fixture(scope="module")
def house() -> World:
    world = World("worlds/tb3_house.yaml")
    yield world
    world.close()


def _polygon_hit(o: np.ndarray, d: np.ndarray, corners: np.ndarray) -> float:
    """First entry of the ray o + t d into the convex polygon ``corners`` (Cyrus-Beck)."""
    t_in, t_out = 0.0, math.inf
    n = len(corners)
    for i in range(n):
        a, b = corners[i], corners[(i + 1) % n]
        normal = np.array([b[1] - a[1], a[0] - b[0]])  # outward for counter-clockwise corners
        num, den = normal @ (a - o), normal @ d
        if den == 0.0:
            if num < 0.0:
                return math.inf
            continue
        t = num / den
        if den < 0.0:
            t_in = max(t_in, t)
        else:
            t_out = min(t_out, t)
    return t_in if 0.0 < t_in <= t_out else math.inf


def _circle_hit(o: np.ndarray, d: np.ndarray, c: np.ndarray, r: float) -> float:
    w = c - o
    b = d @ w
    disc = b * b - (w @ w - r * r)
    if disc < 0.0:
        return math.inf
    t = b - math.sqrt(disc)
    return t if t > 0.0 else math.inf


def _room_ranges(o: np.ndarray, heading: float, scan: Scan) -> tuple[np.ndarray, np.ndarray]:
    """Per beam, the range to the room's inner walls, the drum and the chest worked out from
    the room's measures, and which of the three each beam meets (0 walls, 1 drum, 2 chest)."""
    c, s = math.cos(math.pi / 6), math.sin(math.pi / 6)
    chest = np.array([[2.0, -1.0]]) + np.array(
        [[-0.3, -0.2], [0.3, -0.2], [0.3, 0.2], [-0.3, 0.2]]) @ np.array([[c, s], [-s, c]])
    out, what = [], []
    for a in heading + scan.angles:
        d = np.array([math.cos(a), math.sin(a)])
        walls = min(t for t in ((3.0 - o[0]) / d[0] if d[0] else math.inf,
                                (-3.0 - o[0]) / d[0] if d[0] else math.inf,
                                (2.0 - o[1]) / d[1] if d[1] else math.inf,
                                (-2.0 - o[1]) / d[1] if d[1] else math.inf) if t > 0.0)
        hits = [walls, _circle_hit(o, d, np.array([2.0, 1.0]), 0.3), _polygon_hit(o, d, chest)]
        out.append(min(hits))
        what.append(int(np.argmin(hits)))
    return np.array(out), np.array(what)


def test_box_room_ranges_as_worked_out_by_hand(room: World) -> None:
    lidar = Lidar(room, room.robots["husky"], FRONT)
    scan = lidar.scan()
    origin, heading = lidar.sensor_pose()
    expected, what = _room_ranges(origin[:2], heading, scan)
    assert set(what) == {0, 1, 2}  # walls, the drum and the turned chest are all in view
    # the shelf board at x = 1.2 floats above the plane: the beams under it reach the far wall
    assert abs(scan.ranges[90] - (3.0 - origin[0])) < 1e-3
    np.testing.assert_allclose(scan.ranges, expected, atol=1e-3, rtol=0.0)
    assert not scan.no_return.any()
    assert scan.sensor_pose == pytest.approx((0.45, 0.0, 0.0), abs=1e-4)
    assert origin[2] == pytest.approx(0.25, abs=0.005)


def test_beams_meeting_nothing_within_range_read_range_max(room: World) -> None:
    spec = dataclasses.replace(FRONT, range_m=1.5)
    scan = Lidar(room, room.robots["husky"], spec).scan()
    assert scan.range_max == 1.5
    assert scan.no_return[90] and scan.ranges[90] == 1.5  # the far wall is 2.5 m away
    side = scan.ranges[0]  # straight right: the south wall, 2 m away
    assert side == 1.5
    assert (scan.ranges <= 1.5).all()


def _reference(world: World, lidar: Lidar, scan: Scan) -> tuple[np.ndarray, np.ndarray]:
    """PyBullet's rayTestBatch along the same beams: ranges, and which beams a fair comparison
    keeps (not grazing a surface, not at the edge of a body)."""
    origin, heading = lidar.sensor_pose()
    angles = heading + scan.angles
    ends = origin + scan.range_max * np.column_stack(
        [np.cos(angles), np.sin(angles), np.zeros(len(angles))])
    hits = pb.rayTestBatch([origin.tolist()] * len(angles), ends.tolist(),
                           physicsClientId=world.client)
    ranges = np.array([h[2] * scan.range_max if h[0] >= 0 else scan.range_max for h in hits])
    target = [(h[0], h[1]) for h in hits]
    keep = np.ones(len(hits), dtype=bool)
    for k, h in enumerate(hits):
        if h[0] >= 0:
            facing = abs(np.dot(h[4][:2], [math.cos(angles[k]), math.sin(angles[k])]))
            keep[k] = facing > 0.25
        for j in (k - 1, k + 1):
            if 0 <= j < len(hits) and target[j] != target[k]:
                keep[k] = False
    return ranges, keep


@pytest.mark.parametrize("pose", [(-1.0, 3.0, 0.2), (0.3, -0.4, -1.9), (4.5, -2.0, 2.6)])
def test_house_ranges_equal_pybullet_ray_tests(house: World, pose: tuple[float, ...]) -> None:
    robot = house.robots["husky"]
    robot.reset_base_pose(*pose)
    lidar = Lidar(house, robot)
    scan = lidar.scan()
    ranges, keep = _reference(house, lidar, scan)
    assert keep.mean() > 0.85
    error = np.abs(scan.ranges - ranges)[keep]
    # Bullet's convex ray cast is itself a few mm off near a convex body's corners
    assert (error < 1e-3).mean() > 0.98 and error.max() < 5e-3
    assert np.median(np.abs(scan.ranges - ranges)) < 1e-4


def test_own_wheels_seen_and_chassis_around_the_laser_not(house: World) -> None:
    robot = house.robots["husky"]
    robot.reset_base_pose(-1.0, 3.0, 0.0)
    scan = Lidar(house, robot).scan()
    rear = np.abs(np.degrees(scan.angles)) > 100.0
    # the front wheels' outer faces, 0.2 to 0.4 m behind and beside the laser
    assert ((scan.ranges[rear] > 0.15) & (scan.ranges[rear] < 0.45)).all()
    # the laser sits inside the chassis' collision box and sees out of it
    assert scan.ranges[np.abs(np.degrees(scan.angles)) < 60.0].min() > 0.3


def _crate(name: str, x: float, y: float, z: float, size: float = 0.3,
           movable: bool = True) -> BodySpec:
    return BodySpec(name=name, movable=movable, parts=[Part("box", (size, size, size))],
                    urdf=None, pose=Pose3D((x, y, z)), planar=False, mass=2.0, friction=0.8,
                    colour=(0.5, 0.3, 0.2, 1.0), randomize=Range2D(), line=0)


def test_crate_added_while_running_is_seen_and_removed_is_gone(room: World) -> None:
    robot = room.robots["husky"]
    lidar = Lidar(room, robot, FRONT)
    before = lidar.scan().ranges[90]
    room.spawn(_crate("crate_x", 1.0, 0.0, 0.16))
    room.step(60)
    origin, _ = lidar.sensor_pose()
    seen = lidar.scan().ranges[90]
    assert before > 2.0
    assert seen == pytest.approx(1.0 - 0.15 - origin[0], abs=0.01)
    room.remove("crate_x")
    assert lidar.scan().ranges[90] == pytest.approx(before, abs=1e-6)


def test_moved_object_is_cut_again_only_when_it_moves(room: World) -> None:
    robot = room.robots["husky"]
    lidar = Lidar(room, robot, FRONT)
    room.spawn(_crate("box_m", -1.0, 1.0, 0.16))  # behind the laser: out of its view
    room.step(120)
    lidar.scan()
    cuts = lidar.scene.cuts
    lidar.scan()
    assert lidar.scene.cuts == cuts  # nothing moved: nothing cut again
    body = room.body_id("box_m")
    pb.resetBasePositionAndOrientation(body, [1.6, 0.3, 0.25], [0, 0, 0, 1],
                                       physicsClientId=room.client)
    scan = lidar.scan()
    origin, _ = lidar.sensor_pose()
    beam = round(math.degrees(math.atan2(0.3 - origin[1], 1.6 - 0.15 - origin[0]))) + 90
    face = (1.6 - 0.15 - origin[0]) / math.cos(scan.angles[beam])  # its near face, x = 1.45
    assert scan.ranges[beam] == pytest.approx(face, abs=1e-3)
    room.remove("box_m")


def test_held_object_is_seen(tmp_path: Path) -> None:
    world = World(write(tmp_path, ROOM.replace("arm_state: tuck", "arm_state: home")))
    try:
        robot = world.robots["husky"]
        # a 0.5 m bar held upright between the fingers reaches down through the scan plane
        lidar = Lidar(world, robot, FRONT)
        spawn_held(world, "bar", (0.03, 0.03, 0.5))
        bar_xy = np.asarray(world.body_pose("bar").xyz[:2])
        scan = lidar.scan()
        origin, heading = lidar.sensor_pose()
        offset = bar_xy - origin[:2]
        beam = round(math.degrees(math.atan2(offset[1], offset[0]) - heading)) + 90
        assert scan.ranges[beam] == pytest.approx(np.linalg.norm(offset) - 0.015, abs=0.02)
    finally:
        world.close()


def test_noise_and_dropout_repeat_per_seed(room: World) -> None:
    robot = room.robots["husky"]
    spec = dataclasses.replace(FRONT, noise_m=0.01)
    exact = Lidar(room, robot, spec).scan().ranges

    def noisy(seed: int, dropout: float = 0.0) -> np.ndarray:
        return Lidar(room, robot, spec, np.random.default_rng(seed)).scan(dropout).ranges

    a, b, c = noisy(7), noisy(7), noisy(8)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    error = a - exact
    assert 0.007 < error.std() < 0.013 and abs(error.mean()) < 0.003
    lost = noisy(7, dropout=0.5) == spec.range_m
    assert 0.35 < lost.mean() < 0.65
    with pytest.raises(ValueError, match="generator"):
        Lidar(room, robot, spec).scan(dropout=0.1)
