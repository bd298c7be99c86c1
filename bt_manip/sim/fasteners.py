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

from bt_manip.geometry import compose_poses, invert_pose
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
    """Fix ``body`` to ``structure`` where both are now; the constraint id."""
    client = world.client
    parent = pbq.com_pose(client, structure.body, -1)
    child = pbq.com_pose(client, body, -1)
    rel_pos, rel_quat = compose_poses(invert_pose(parent), child)
    cid = pb.createConstraint(
        structure.body, -1, body, -1, pb.JOINT_FIXED, [0, 0, 0],
        parentFramePosition=rel_pos, childFramePosition=[0, 0, 0],
        parentFrameOrientation=rel_quat, childFrameOrientation=[0, 0, 0, 1],
        physicsClientId=client,
    )
    pb.changeConstraint(cid, maxForce=HOLD_FORCE, physicsClientId=client)
    return int(cid)


def fastenings(world: Any) -> dict[str, str]:
    """Each fastened movable object's name with the structure it is fastened to."""
    static = {i.body_id: i.name for i in world.infos.values() if i.kind in STRUCTURE_KINDS}
    movable = {b: n for n, b in world.movable.items()}
    out: dict[str, str] = {}
    client = world.client
    for k in range(pb.getNumConstraints(physicsClientId=client)):
        cid = pb.getConstraintUniqueId(k, physicsClientId=client)
        info = pb.getConstraintInfo(cid, physicsClientId=client)
        parent, child, kind = info[0], info[2], info[4]
        if kind == pb.JOINT_FIXED and parent in static and child in movable:
            out[movable[child]] = static[parent]
    return out
