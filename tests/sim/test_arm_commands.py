"""Arm commands and queries of a Robot: ``set_arm_targets`` gives PyBullet the same motor
settings as the keyword form of ``setJointMotorControl2`` with numpy's clip and minimum (the
run is the same, step for step), and the one-query readings agree with the named ones.

Every test runs on its own PyBullet DIRECT client: a plane, 240 Hz, gravity -9.81.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pybullet as pb
import pybullet_data
import pytest

from bt_manip.sim import pybullet_queries as pbq
from bt_manip.sim.robot import Robot, RobotDescription

RATE = 240


def _client() -> int:
    cid = pb.connect(pb.DIRECT)
    pb.setGravity(0, 0, -9.81, physicsClientId=cid)
    pb.setTimeStep(1.0 / RATE, physicsClientId=cid)
    pb.loadURDF(str(Path(pybullet_data.getDataPath()) / "plane.urdf"), physicsClientId=cid)
    return cid


@pytest.fixture
def clients() -> Iterator[tuple[int, int]]:
    a, b = _client(), _client()
    yield a, b
    pb.disconnect(a)
    pb.disconnect(b)


@pytest.fixture(scope="module")
def sawyer() -> RobotDescription:
    return RobotDescription.load("sawyer")


def _keyword_targets(robot: Robot, q: np.ndarray, max_velocity: object) -> None:
    """The arm command spelled with numpy and PyBullet's keyword arguments."""
    arm = robot.description.arm
    n = len(robot.arm_joint_ids)
    limits = np.asarray(robot._arm_velocity, dtype=float)
    if max_velocity is not None:
        limits = np.minimum(limits, np.broadcast_to(np.asarray(max_velocity, float), (n,)))
    q = np.clip(np.asarray(q, dtype=float), arm.lower, arm.upper)
    for j, target, speed, effort in zip(
        robot.arm_joint_ids, q, limits, robot._arm_effort, strict=True
    ):
        pb.setJointMotorControl2(
            robot.body, j, pb.POSITION_CONTROL, targetPosition=float(target),
            targetVelocity=0.0, force=effort, maxVelocity=float(speed),
            positionGain=arm.position_gain, velocityGain=1.0, physicsClientId=robot.client,
        )


def _run(robot: Robot) -> list[tuple[float, float]]:
    for _ in range(int(0.4 * RATE)):
        pb.stepSimulation(physicsClientId=robot.client)
    states = pbq.joint_states(robot.client, robot.body, robot.arm_joint_ids)
    return [(s.position, s.velocity) for s in states]


@pytest.mark.parametrize("max_velocity", [None, 0.3, "per_joint"])
def test_targets_drive_the_arm_exactly_as_the_keyword_form(
    clients: tuple[int, int], sawyer: RobotDescription, max_velocity: object
) -> None:
    ours = Robot.spawn(clients[0], sawyer, 0.0, 0.0, 0.0)
    reference = Robot.spawn(clients[1], sawyer, 0.0, 0.0, 0.0)
    for robot in (ours, reference):
        robot.reset_arm("home")
    home = np.array(sawyer.state("home"))
    n = len(home)
    target = home + np.array([0.6, -0.5, 0.4, -0.3, 0.5, -0.4, 0.3])[:n]
    target[0] = sawyer.arm.upper[0] + 1.0         # beyond its limit: clipped
    cap: object = max_velocity
    if max_velocity == "per_joint":               # some caps above the limits, some below
        cap = [0.2 + 0.5 * i for i in range(n)]
    ours.set_arm_targets(target, max_velocity=cap)
    _keyword_targets(reference, target, cap)
    a, b = _run(ours), _run(reference)
    assert a == b
    moved = np.abs(np.array([p for p, _ in a]) - home)
    assert moved.min() > 1e-3                     # every joint was driven, not held


def test_speed_caps_must_match_the_joints(
    clients: tuple[int, int], sawyer: RobotDescription
) -> None:
    robot = Robot.spawn(clients[0], sawyer, 0.0, 0.0, 0.0)
    home = np.array(sawyer.state("home"))
    with pytest.raises(ValueError, match="expected 7 arm targets"):
        robot.set_arm_targets(home[:3])
    with pytest.raises(ValueError):
        robot.set_arm_targets(home, max_velocity=[0.1, 0.2])


def test_one_query_readings_agree_with_the_named_ones(
    clients: tuple[int, int], sawyer: RobotDescription
) -> None:
    robot = Robot.spawn(clients[0], sawyer, 0.0, 0.0, 0.0)
    robot.reset_arm("home")
    robot.set_arm_targets(np.array(sawyer.state("home")) + 0.3)
    for _ in range(30):
        pb.stepSimulation(physicsClientId=robot.client)
    named = pbq.joint_states(robot.client, robot.body, robot.arm_joint_ids)
    q, qd = robot.arm_motion()
    assert q == [s.position for s in named] and qd == [s.velocity for s in named]
    assert robot.arm_positions().tolist() == q and robot.arm_velocities().tolist() == qd
    assert max(abs(v) for v in qd) > 1e-3         # the arm is moving
    assert pbq.joint_motion(robot.client, robot.body, []) == ([], [])
    assert robot.arm_link_set() == frozenset(robot.arm_link_ids())
    cid = robot.client
    shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[0.1, 0.1, 0.1], physicsClientId=cid)
    box = pb.createMultiBody(1.0, shape, -1, [2.0, 0.0, 0.1], physicsClientId=cid)
    pb.stepSimulation(physicsClientId=cid)
    contacts = pbq.contacts(cid, box)
    assert contacts
    assert pbq.contact_links(cid, box) == [(c.link_a, c.body_b) for c in contacts]
