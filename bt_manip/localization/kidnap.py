"""The ``kidnap:T`` fault: at sim time T a robot, with what it holds, is carried to another
free pose nearby, and its localisation is not told.

The new pose is drawn from the fault's own generator (seeded by the episode seed): 0.5 to 1.5 m
away in any direction, the heading turned by up to 0.5 rad. A draw is kept only when neither the
robot nor what it holds touches anything but the floor there; after :data:`KIDNAP_TRIES` draws
without a free pose the robot stays where it is and the fault's event says so. The robot is
not pushed through physics: its base and the held objects are set at their new poses at rest
(the arm keeps its joints, the attach joints keep their relative poses).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pybullet as pb

from bt_manip.sim import pybullet_queries as pbq

if TYPE_CHECKING:
    from bt_manip.sim.robot import Robot
    from bt_manip.sim.world import World

KIDNAP_DISTANCE = (0.5, 1.5)
"""How far (m) the robot is carried."""
KIDNAP_TURN = 0.5
"""Largest turn (rad) of the robot's heading."""
KIDNAP_TRIES = 60
"""Draws of a new pose before the kidnap gives up."""


@dataclass(frozen=True)
class KidnapResult:
    """Where the robot went (or why it stayed)."""

    moved: bool
    note: str


def _yaw_quat(yaw: float) -> tuple[float, float, float, float]:
    return (0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0))


def _move_held(world: World, bodies: list[tuple[int, tuple, tuple]],
               origin: tuple[float, float, float], to: tuple[float, float, float]) -> None:
    """Set each held body at the rigid planar motion taking ``origin`` to ``to``."""
    dyaw = to[2] - origin[2]
    c, s = math.cos(dyaw), math.sin(dyaw)
    turn = _yaw_quat(dyaw)
    for body, pos, quat in bodies:
        rx, ry = pos[0] - origin[0], pos[1] - origin[1]
        new_pos = (to[0] + c * rx - s * ry, to[1] + s * rx + c * ry, pos[2])
        _, new_quat = pb.multiplyTransforms((0, 0, 0), turn, (0, 0, 0), quat)
        pb.resetBasePositionAndOrientation(body, new_pos, new_quat, physicsClientId=world.client)
        pb.resetBaseVelocity(body, [0, 0, 0], [0, 0, 0], physicsClientId=world.client)


def _clear(world: World, mine: set[int]) -> bool:
    """Nothing of ``mine`` touches a body other than the floor and each other."""
    client = world.client
    pb.performCollisionDetection(physicsClientId=client)
    ground = world.body_id("ground")
    for body in mine:
        for other in pbq.touching(client, body):
            if other != ground and other not in mine:
                return False
    return True


def kidnap(world: World, robot: Robot, robot_name: str,
           rng: np.random.Generator) -> KidnapResult:
    """Carry ``robot`` and what it holds to a free pose nearby (see the module docstring)."""
    if robot.is_holonomic:
        return KidnapResult(False, "not moved: a holonomic base is fixed to the world's frame")
    start = robot.base_pose2d()
    held = [a.object_body for a in world.attachments.held_by(robot_name)]
    saved = [(b, *pb.getBasePositionAndOrientation(b, physicsClientId=world.client))
             for b in held]
    mine = {robot.body, *held}
    for _ in range(KIDNAP_TRIES):
        d = float(rng.uniform(*KIDNAP_DISTANCE))
        bearing = float(rng.uniform(-math.pi, math.pi))
        turn = float(rng.uniform(-KIDNAP_TURN, KIDNAP_TURN))
        to = (start[0] + d * math.cos(bearing), start[1] + d * math.sin(bearing),
              start[2] + turn)
        robot.reset_base_pose(*to)
        _move_held(world, saved, start, to)
        if _clear(world, mine):
            robot.stop_base()
            return KidnapResult(True, f"carried {d:.2f} m, turned {turn:+.2f} rad to "
                                      f"x={to[0]:.2f} y={to[1]:.2f}")
    robot.reset_base_pose(*start)
    _move_held(world, saved, start, start)
    return KidnapResult(False, f"not moved: no free pose found in {KIDNAP_TRIES} draws")
