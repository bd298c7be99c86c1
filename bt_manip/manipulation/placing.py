"""Target poses of placed objects, how far an object is from one, and where the hand goes to
put a held object at one.

A place target is the pose an object's centre must take: ``x;y;z;yaw`` (metres, radians; the
object upright as it stands in the world file, turned by ``yaw`` about the vertical). A box is
the same box turned half a turn about the vertical, so both turns count as the target: the
deviation of a placed pose is measured against the nearer of the two.

The deviation has two parts: the distance (m) between the object's centre and the target's,
and the angle (rad) of the rotation that takes the target's orientation to the object's (tilt
and yaw together).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bt_manip.manipulation.errors import ManipulationError

TARGET_PARTS = 4
"""Numbers in a target: x;y;z;yaw."""
MAX_COORDINATE = 1000.0
"""Largest target coordinate (m) accepted."""


class TargetError(ManipulationError, ValueError):
    """A target text that is not x;y;z;yaw; the message says why."""


@dataclass(frozen=True)
class Target:
    """Where an object's centre goes, and its yaw (rad)."""

    x: float
    y: float
    z: float
    yaw: float

    def matrix(self, flip: bool = False) -> np.ndarray:
        """The target pose (4x4), turned half a turn about the vertical with ``flip``."""
        yaw = self.yaw + (math.pi if flip else 0.0)
        t = np.eye(4)
        c, s = math.cos(yaw), math.sin(yaw)
        t[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
        t[:3, 3] = [self.x, self.y, self.z]
        return t

    def text(self) -> str:
        return ";".join(f"{v:.4f}" for v in (self.x, self.y, self.z, self.yaw))


def parse_target(text: str) -> Target:
    """A target from ``x;y;z;yaw``; TargetError with the reason otherwise."""
    parts = str(text).split(";")
    if len(parts) != TARGET_PARTS:
        raise TargetError(f"a target is x;y;z;yaw (4 numbers), got '{text}'")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise TargetError(f"a target is x;y;z;yaw (4 numbers), got '{text}'") from None
    if not all(math.isfinite(v) and abs(v) <= MAX_COORDINATE for v in values):
        raise TargetError(
            f"target numbers must be finite and within +-{MAX_COORDINATE:g}, got '{text}'"
        )
    return Target(*values)


def target_problem(value: object) -> str | None:
    """What is wrong with a target literal (for a port's Accepts rule), or None."""
    if not isinstance(value, str) or value.startswith("{"):
        return None
    try:
        parse_target(value)
    except TargetError as exc:
        return str(exc)
    return None


@dataclass(frozen=True)
class Deviation:
    """How far a pose is from a target: centre distance (m) and rotation angle (rad)."""

    distance: float
    angle: float

    @property
    def mm(self) -> float:
        return self.distance * 1000.0

    @property
    def deg(self) -> float:
        return math.degrees(self.angle)

    def within(self, distance: float, angle: float) -> bool:
        return self.distance <= distance and self.angle <= angle

    def text(self) -> str:
        return f"{self.mm:.1f} mm and {self.deg:.2f} deg"


def rotation_angle(ra: np.ndarray, rb: np.ndarray) -> float:
    """Angle (rad) of the rotation from ``ra`` to ``rb`` (3x3)."""
    return float(np.arccos(np.clip((np.trace(ra.T @ rb) - 1.0) / 2.0, -1.0, 1.0)))


def deviation(pose: np.ndarray, target: Target) -> Deviation:
    """Deviation of ``pose`` (4x4) from ``target``, the nearer of its two turns."""
    distance = float(np.linalg.norm(pose[:3, 3] - np.array([target.x, target.y, target.z])))
    angle = min(rotation_angle(target.matrix(flip)[:3, :3], pose[:3, :3]) for flip in (False, True))
    return Deviation(distance, angle)


def yaw_of_matrix(pose: np.ndarray) -> float:
    """Heading (rad) of a pose's x axis in the horizontal plane."""
    return math.atan2(float(pose[1, 0]), float(pose[0, 0]))


def place_frames(target: Target, object_in_grasp: np.ndarray, hand: np.ndarray) -> list[np.ndarray]:
    """Grasp-frame poses (4x4) that put the object held as ``object_in_grasp`` at ``target``:
    the two turns of the target, the one nearer the hand's orientation ``hand`` first."""
    to_grasp = np.linalg.inv(object_in_grasp)
    frames = [target.matrix(flip) @ to_grasp for flip in (False, True)]
    frames.sort(key=lambda f: rotation_angle(hand[:3, :3], f[:3, :3]))
    return frames


def lifted(frame: np.ndarray, height: float) -> np.ndarray:
    """``frame`` moved up by ``height`` (m)."""
    out = frame.copy()
    out[2, 3] += height
    return out
