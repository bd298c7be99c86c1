"""Grasp frames computed from an object's shape and pose, for a two-finger parallel gripper.

A grasp frame is where the gripper's ``grasp_frame`` link must be for the fingers to hold the
object: its z axis is the approach direction (pointing from the gripper into the object), its y
axis the direction the fingers close along, the point between the pads at its origin (see
``robots/parts/parallel_gripper.urdf``: the pads reach 0.05 m back and 0.02 m beyond the grasp
frame along z).

``top``: for a box, a grasp from above at the middle of its top face. The top face is the face
whose normal points most upwards; the approach runs down that normal (straight down for a box
standing level, along the box for one that leans), the fingers close across the thinner of the
face's two sides, and the grasp frame sits :data:`GRASP_DEPTH` below the face so the pads hold
the top of the box. A panel standing on its long edge is thus held by its top edge, the fingers
closing across its thickness.

Of the two frames that differ by half a turn about the approach (the same grasp for a symmetric
gripper), :func:`top_grasp` returns the one whose x axis points to the ``side`` given (for a
robot, its left): a rule that does not flip for small changes of the robot's heading when the
fingers close roughly along that heading.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from bt_manip.manipulation.errors import ManipulationError

GRASPS = ("top",)
"""The grasps :func:`grasp_frame` knows."""
GRASP_DEPTH = 0.03
"""How far (m) below the top face the grasp frame sits (at most half the box's height)."""
OPENING_MARGIN = 0.01
"""The fingers must open this much (m) wider than the side they close across."""


class GraspError(ManipulationError, ValueError):
    """The object cannot be grasped that way; the message says why."""


def top_face(size: Sequence[float], pose: np.ndarray) -> tuple[int, np.ndarray]:
    """The box axis (0, 1 or 2) whose face points most upwards, and that face's outward
    normal (world frame), for a box of full extents ``size`` at ``pose`` (4x4)."""
    r = pose[:3, :3]
    up_axis = int(np.argmax(np.abs(r[2, :])))
    normal = r[:, up_axis] * (1.0 if r[2, up_axis] >= 0 else -1.0)
    return up_axis, normal


def top_grasp(
    size: Sequence[float],
    pose: np.ndarray,
    side: Sequence[float] = (0.0, 1.0),
    max_opening: float | None = None,
    depth: float = GRASP_DEPTH,
) -> np.ndarray:
    """The top grasp frame (4x4, world) of a box of full extents ``size`` at ``pose``.

    ``side`` is a horizontal direction (x, y) that the frame's x axis is turned towards (see
    the module docstring). With ``max_opening`` (m), a box whose thinner top side does not fit
    between the open fingers (with :data:`OPENING_MARGIN`) raises :class:`GraspError`.
    """
    if len(size) != 3 or min(size) <= 0:
        raise GraspError(f"a box needs three positive sizes, got {list(size)}")
    up_axis, normal = top_face(size, pose)
    others = [i for i in range(3) if i != up_axis]
    thin = min(others, key=lambda i: (size[i], i))
    width = float(size[thin])
    if max_opening is not None and width + OPENING_MARGIN > max_opening:
        raise GraspError(
            f"its top face is {width * 100:.1f} cm across at its narrowest, and the fingers "
            f"open {max_opening * 100:.1f} cm"
        )
    z = -normal
    y = pose[:3, thin] - np.dot(pose[:3, thin], z) * z
    y /= np.linalg.norm(y)
    x = np.cross(y, z)
    if float(np.dot(x[:2], np.asarray(side[:2], dtype=float))) < 0.0:
        x, y = -x, -y
    frame = np.eye(4)
    frame[:3, 0], frame[:3, 1], frame[:3, 2] = x, y, z
    half_height = float(size[up_axis]) / 2.0
    frame[:3, 3] = pose[:3, 3] + normal * (half_height - min(depth, half_height))
    return frame


def grasp_frame(
    kind: str,
    size: Sequence[float],
    pose: np.ndarray,
    side: Sequence[float] = (0.0, 1.0),
    max_opening: float | None = None,
) -> np.ndarray:
    """The grasp frame of kind ``kind`` (one of :data:`GRASPS`); GraspError if unknown."""
    if kind == "top":
        return top_grasp(size, pose, side, max_opening)
    raise GraspError(f"unknown grasp '{kind}'; known: {', '.join(GRASPS)}")


def box_size(world: Any, name: str) -> tuple[float, float, float]:
    """Full extents of the movable object ``name`` when it is one box centred on its frame;
    GraspError otherwise (the grasps here are for boxes)."""
    spec = world.infos[name].spec
    parts = getattr(spec, "parts", None) or []
    if getattr(spec, "urdf", None) is not None or len(parts) != 1 or parts[0].shape != "box":
        raise GraspError(f"'{name}' is not a single box: grasps are computed for boxes only")
    part = parts[0]
    if any(abs(v) > 1e-9 for v in (*part.xyz, *part.rpy)):
        raise GraspError(f"'{name}' is a box placed off its body frame")
    scale = float(getattr(spec, "scale", 1.0))
    sx, sy, sz = (float(v) * scale for v in part.size)
    return (sx, sy, sz)


def grasped_object(world: Any, robot: Any) -> str:
    """Name of the movable object every finger of ``robot`` touches, or ''."""
    movable: dict[str, int] = world.movable
    for name, body in movable.items():
        if robot.is_grasping(body):
            return name
    return ""
