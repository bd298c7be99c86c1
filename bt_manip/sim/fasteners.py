"""Fasteners: an object fixed to the structure it stands on or against by a fixed joint.

A fastening is a PyBullet fixed constraint between a static body of the world (a wall, a piece
of furniture, the floor) and a movable object, holding the pose they have when it is made, as
screws or clips would. The constraints themselves are the record: :func:`fastenings` reads them
back from PyBullet, so nothing else keeps state.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import pybullet as pb

from bt_manip.sim import pybullet_queries as pbq

STRUCTURE_KINDS = ("wall", "furniture", "ground")
"""Kinds of world bodies an object can be fastened to."""
HOLD_FORCE = 5000.0
"""Maximum force (N) a fastening applies."""


@dataclass(frozen=True)
class Structure:
    """A static body near an object: its name, id and gap (m; <= 0 when touching)."""

    name: str
    body: int
    kind: str
    gap: float


def structures_near(world: Any, body: int, max_gap: float) -> list[Structure]:
    """Static bodies within ``max_gap`` of ``body``: walls and furniture first (what it stands
    against), then the floor, each group nearest first."""
    found = []
    for info in world.infos.values():
        if info.kind not in STRUCTURE_KINDS or info.body_id == body:
            continue
        points = pbq.closest_points(world.client, body, info.body_id, max_gap)
        if points:
            gap = min(p.distance for p in points)
            found.append(Structure(info.name, info.body_id, info.kind, gap))
    found.sort(key=lambda s: (s.kind == "ground", s.gap, s.name))
    return found


def fasten(world: Any, body: int, structure: Structure) -> int:
    """Fix ``body`` where it is now, fastened to ``structure``; the constraint id.

    The joint holds the object to the world frame: walls, furniture and the floor are static
    rigid bodies (:mod:`bt_manip.sim.static_bodies`), fixed in the world, so this is the same
    joint as one to the structure (PyBullet makes no joint from an articulated body to a static
    rigid one). Which structure it is fastened to is kept in ``world.fastened_to``
    (:func:`fastenings`)."""
    client = world.client
    pos, quat = pbq.com_pose(client, body, -1)
    cid = pb.createConstraint(
        body, -1, -1, -1, pb.JOINT_FIXED, [0, 0, 0],
        parentFramePosition=[0, 0, 0], childFramePosition=list(pos),
        parentFrameOrientation=[0, 0, 0, 1], childFrameOrientation=list(quat),
        physicsClientId=client,
    )
    pb.changeConstraint(cid, maxForce=HOLD_FORCE, physicsClientId=client)
    world.fastened_to[int(cid)] = structure.name
    return int(cid)


def fastenings(world: Any) -> dict[str, str]:
    """Each fastened movable object's name with the structure it is fastened to."""
    movable = {b: n for n, b in world.movable.items()}
    to = world.fastened_to
    out: dict[str, str] = {}
    client = world.client
    for k in range(pb.getNumConstraints(physicsClientId=client)):
        cid = pb.getConstraintUniqueId(k, physicsClientId=client)
        if cid not in to:
            continue
        info = pb.getConstraintInfo(cid, physicsClientId=client)
        parent, child, kind = info[0], info[2], info[4]
        if kind == pb.JOINT_FIXED and child == -1 and parent in movable:
            out[movable[parent]] = to[cid]
    return out
