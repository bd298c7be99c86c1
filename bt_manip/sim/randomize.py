"""Seeded randomness of a world: the per-seed variation of the poses a world file gives.

Each object or robot with a ``randomize`` range gets offsets drawn from a generator seeded by
(world seed, entity name) (:func:`entity_rng`), so adding an entity does not change the others.
Each group (:mod:`bt_manip.sim.groups`) gets one planar rigid motion per seed
(:func:`group_motion`: its ``move`` plus the offsets drawn the same way), and
:func:`place_groups` moves its members by it before anything is built. Nothing here reads a
file or touches the simulation: the same spec and seed give the same poses.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass, replace

import numpy as np

from bt_manip.sim.world_spec import BodySpec, GroupSpec, Pose2D, Pose3D, Range2D, WorldSpec


def sample_offset(rng: np.random.Generator, r: Range2D) -> tuple[float, float, float]:
    """Offsets (dx, dy, dyaw) drawn uniformly from the ranges of ``r``."""
    return (float(rng.uniform(*r.x)), float(rng.uniform(*r.y)), float(rng.uniform(*r.yaw)))


def entity_rng(seed: int, name: str) -> np.random.Generator:
    """The random generator of one named entity for one world seed."""
    return np.random.default_rng([int(seed) & 0xFFFFFFFF, zlib.crc32(name.encode())])


@dataclass(frozen=True)
class Rigid2D:
    """A planar rigid motion: turn by ``dyaw`` about ``origin``, then shift by (dx, dy)."""

    origin: tuple[float, float]
    dx: float = 0.0
    dy: float = 0.0
    dyaw: float = 0.0

    def point(self, x: float, y: float) -> tuple[float, float]:
        """Where the point (x, y) goes."""
        ox, oy = self.origin
        c, s = math.cos(self.dyaw), math.sin(self.dyaw)
        rx, ry = x - ox, y - oy
        return ox + c * rx - s * ry + self.dx, oy + s * rx + c * ry + self.dy

    def pose2d(self, pose: Pose2D) -> Pose2D:
        """A planar pose moved: its point moved, its heading turned."""
        x, y = self.point(pose.x, pose.y)
        return Pose2D(x, y, pose.yaw + self.dyaw)

    def pose3d(self, pose: Pose3D) -> Pose3D:
        """A full pose moved: position moved in x and y (z kept), orientation turned about
        the world's z axis."""
        x, y = self.point(pose.xyz[0], pose.xyz[1])
        half = self.dyaw / 2.0
        qz = (0.0, 0.0, math.sin(half), math.cos(half))
        return Pose3D((x, y, pose.xyz[2]), _quat_mul(qz, pose.quat))

    def is_identity(self) -> bool:
        return self.dx == 0.0 and self.dy == 0.0 and self.dyaw == 0.0


def _quat_mul(
    a: tuple[float, float, float, float], b: tuple[float, float, float, float]
) -> tuple[float, float, float, float]:
    """Hamilton product a * b of quaternions (x, y, z, w): rotate by b, then by a."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def group_motion(group: GroupSpec, seed: int) -> Rigid2D:
    """The group's rigid motion for a world seed: ``move`` plus the seeded offsets."""
    rx, ry, ryaw = sample_offset(entity_rng(seed, group.name), group.randomize)
    dx, dy, dyaw = group.move
    return Rigid2D(group.origin, dx + rx, dy + ry, dyaw + ryaw)


def place_groups(spec: WorldSpec, seed: int) -> tuple[WorldSpec, dict[str, Rigid2D]]:
    """``spec`` with every group's members moved by the group's transform for ``seed``
    (``spec`` itself when it has no groups), and each group's transform by name."""
    groups: list[GroupSpec] = spec.groups
    if not groups:
        return spec, {}
    moves: dict[str, Rigid2D] = {}
    by_member: dict[str, Rigid2D] = {}
    for group in groups:
        t = group_motion(group, seed)
        moves[group.name] = t
        by_member.update(dict.fromkeys(group.members, t))

    def body(b: BodySpec) -> BodySpec:
        t = by_member.get(b.name)
        return b if t is None else replace(b, pose=t.pose3d(b.pose))

    poses = {
        name: (by_member[name].pose2d(p) if name in by_member else p)
        for name, p in spec.poses.items()
    }
    placed = replace(
        spec,
        furniture=[body(b) for b in spec.furniture],
        objects=[body(b) for b in spec.objects],
        models=[body(b) for b in spec.models],
        poses=poses,
    )
    return placed, moves
