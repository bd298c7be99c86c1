"""What the robot perceives of an object's pose: the one place nodes read it for planning.

A node that plans from where an object is (MoveToPose ``object=...``, PlanBaseForGrasp, the grasp
frame of an object) reads the object's pose with :func:`perceived_pose`: the simulator's ground
truth, plus the episode's perception error of that object when ``--inject pose_noise:...`` is
on (:meth:`bt_manip.run.faults.FaultInjector.pose_offset`: drawn once per object and episode, so
every node of the run sees the object at the same wrong place). Conditions and physics
(ObjectInRegion, IsAttached, the proximity check of Attach) keep reading the ground truth.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pybullet as pb

from bt_manip.geometry import pose_matrix
from bt_manip.manipulation.errors import ManipulationError


class PerceptionError(ManipulationError):
    """The robot cannot see the object asked for; the message says why."""


def movable_body(world: Any, name: str) -> int:
    """PyBullet id of the movable object ``name`` of ``world``; PerceptionError naming the
    world's movable objects when it has no such object."""
    movable: dict[str, int] = world.movable
    if name not in movable:
        raise PerceptionError(
            f"no movable object named '{name}'; objects: {', '.join(sorted(movable)) or 'none'}"
        )
    return movable[name]


def true_pose(world: Any, body: int) -> np.ndarray:
    """The ground-truth world pose (4x4) of a body's base frame."""
    pos, quat = pb.getBasePositionAndOrientation(body, physicsClientId=world.client)
    return pose_matrix(pos, quat)


def perceived_pose(world: Any, faults: Any, name: str) -> np.ndarray:
    """The pose (4x4, world frame) at which the robot sees the movable object ``name``.

    Without ``pose_noise`` (``faults`` None or without that fault) it is the ground truth. With
    it, the ground truth turned about the vertical through the object's centre by the offset's
    ``dyaw`` and shifted by ``dx``, ``dy``. KeyError when the world has no such object.
    """
    pose = true_pose(world, world.movable[name])
    offset = faults.pose_offset(name) if faults is not None else None
    if offset is None:
        return pose
    c, s = np.cos(offset.dyaw), np.sin(offset.dyaw)
    turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    seen = pose.copy()
    seen[:3, :3] = turn @ pose[:3, :3]
    seen[0, 3] += offset.dx
    seen[1, 3] += offset.dy
    return seen


def seen_pose(world: Any, faults: Any, name: str) -> np.ndarray:
    """:func:`perceived_pose` of the movable object ``name``; PerceptionError when the world
    has no such object."""
    movable_body(world, name)
    return perceived_pose(world, faults, name)
