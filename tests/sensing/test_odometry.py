"""Wheel odometry of the Husky: exact enough without noise, drifting with it, fooled by slip."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from bt_manip.sensing.odometry import OdometryNoise, WheelOdometry
from bt_manip.sim.world import World
from tests.sensing.worlds import ROOM, write


@pytest.fixture()
def room(tmp_path: pytest.TempPathFactory) -> World:
    world = World(write(tmp_path, ROOM.replace("pose: [0.0, 0.0, 0.0]",
                                               "pose: [-2.0, 0.0, 0.0]")))
    yield world
    world.close()


def _drive(world: World, odos: list[WheelOdometry], v: float, w: float, ticks: int) -> None:
    robot = world.robots["husky"]
    robot.set_base_twist(v, w)
    for _ in range(ticks):
        world.step(12)
        for odo in odos:
            odo.update(world.time)
    robot.stop_base()
    world.step(48)
    for odo in odos:
        odo.update(world.time)


def _moved(world: World, start: tuple[float, float, float]) -> tuple[float, float, float]:
    x, y, yaw = world.robots["husky"].base_pose2d()
    c, s = math.cos(start[2]), math.sin(start[2])
    dx, dy = x - start[0], y - start[1]
    return c * dx + s * dy, -s * dx + c * dy, yaw - start[2]


def test_straight_drive_and_spin_without_noise(room: World) -> None:
    robot = room.robots["husky"]
    start = robot.base_pose2d()
    odo = WheelOdometry(robot, time=room.time)
    assert (odo.x, odo.y, odo.yaw) == (0.0, 0.0, 0.0)  # the odom frame starts at the base
    _drive(room, [odo], 0.5, 0.0, 40)
    truth = _moved(room, start)
    assert truth[0] > 0.9
    assert math.hypot(odo.x - truth[0], odo.y - truth[1]) < 0.01
    assert abs(odo.yaw - truth[2]) < 0.01
    start = robot.base_pose2d()
    spin = WheelOdometry(robot, time=room.time)
    _drive(room, [spin], 0.0, -1.0, 40)
    truth = _moved(room, start)
    assert abs(truth[2]) > 1.5
    assert abs(spin.yaw - truth[2]) < 0.08 * abs(truth[2])
    # the frame slides about 0.2 m as the skid-steer pivots ahead of it: modelled, roughly
    assert math.hypot(spin.x - truth[0], spin.y - truth[1]) < 0.1


def test_noise_drifts_and_repeats_per_seed(room: World) -> None:
    robot = room.robots["husky"]
    noise = OdometryNoise(k=0.05, k_rot=0.05, k_drift=0.05)
    odos = [WheelOdometry(robot), WheelOdometry(robot, noise, np.random.default_rng(3)),
            WheelOdometry(robot, noise, np.random.default_rng(3)),
            WheelOdometry(robot, noise, np.random.default_rng(4))]
    _drive(room, odos, 0.5, 0.3, 40)
    exact, a, b, c = (o.reading() for o in odos)
    assert (a.x, a.y, a.yaw) == (b.x, b.y, b.yaw)
    assert (a.x, a.y, a.yaw) != (c.x, c.y, c.yaw)
    assert math.hypot(a.x - exact.x, a.y - exact.y) > 1e-4
    with pytest.raises(ValueError, match="generator"):
        WheelOdometry(robot, noise)


def test_slip_against_a_wall_fools_odometry(room: World) -> None:
    robot = room.robots["husky"]
    robot.reset_base_pose(2.3, 0.0, 0.0)  # the front bumper 0.2 m from the east wall
    room.step(24)
    start = robot.base_pose2d()
    odo = WheelOdometry(robot, time=room.time)
    _drive(room, [odo], 0.5, 0.0, 40)
    truth = _moved(room, start)
    assert truth[0] < 0.25  # the wall stopped it
    assert odo.x > truth[0] + 0.3  # the wheels kept turning


def test_holonomic_base_odometry_follows_sideways_and_turning_moves(tmp_path: Path) -> None:
    """The omni base's odometry reads its virtual x, y and yaw joints: a sideways drive and a
    drive while turning come out in the base's own frame as the truth has them."""
    world = World(write(tmp_path, """\
name: omni_room
walls:
  - {name: south, from: [-3.05, -3.05], to: [3.05, -3.05], thickness: 0.1, height: 1.0}
robots:
  - name: omni
    description: omni_sawyer
    pose: [-1.0, -1.0, 0.7]
    arm_state: tuck
"""))
    try:
        robot = world.robots["omni"]
        start = robot.base_pose2d()
        odo = WheelOdometry(robot, time=world.time)
        moves = [(0.0, 0.4, 0.0), (0.3, 0.0, 0.5), (0.2, -0.2, -0.4)]
        for vx, vy, w in moves:
            robot.set_base_velocity(vx, vy, w)
            for _ in range(40):
                world.step(12)
                odo.update(world.time)
        robot.set_base_velocity(0.0, 0.0, 0.0)
        world.step(48)
        odo.update(world.time)
        x, y, yaw = robot.base_pose2d()
        c, s = math.cos(start[2]), math.sin(start[2])
        dx, dy = x - start[0], y - start[1]
        truth = (c * dx + s * dy, -s * dx + c * dy, yaw - start[2])
        assert math.hypot(truth[0], truth[1]) > 0.8  # it really went somewhere
        assert abs(truth[2]) > 0.1
        assert math.hypot(odo.x - truth[0], odo.y - truth[1]) < 0.01
        assert abs(odo.yaw - truth[2]) < 0.005
    finally:
        world.close()
