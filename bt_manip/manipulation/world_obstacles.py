"""The PyBullet bodies of a world as collision shapes for the arm's planning scene.

:func:`body_obstacles` turns every collision shape of a body into an
:class:`~bt_manip.manipulation.collision_scene.Obstacle` with its world pose: boxes, spheres and
cylinders as they are, a capsule as the cylinder round it, a mesh as the convex hull of its
vertices (``getMeshData``), a plane (the floor) as a thick slab under it. Shapes are read from
``getCollisionShapeData``, whose frames are given relative to the link's centre of mass.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pybullet as pb

from bt_manip.geometry import pose_matrix
from bt_manip.manipulation.collision_scene import Obstacle
from bt_manip.sim import pybullet_queries as pbq

__all__ = ["FLOOR_SLAB", "body_obstacles", "world_obstacles"]

FLOOR_SLAB = (200.0, 200.0, 0.2)
"""m: the box standing for a plane, its top face on the plane."""


def body_obstacles(client: int, body: int, name: str) -> list[Obstacle]:
    """Every collision shape of ``body`` as an obstacle in the world frame."""
    out: list[Obstacle] = []
    for link in range(-1, pbq.joint_count(client, body)):
        shapes = pbq.collision_shapes(client, body, link)
        if not shapes:
            continue
        com = pose_matrix(*pbq.com_pose(client, body, link))
        for k, shape in enumerate(shapes):
            local = pose_matrix(shape.local_position, shape.local_orientation)
            pose = com @ local
            label = name if len(shapes) == 1 and link == -1 else f"{name}#{link}.{k}"
            geom, dims = shape.geometry_type, shape.dimensions
            if geom == pb.GEOM_BOX:
                out.append(Obstacle(label, "box", tuple(float(d) for d in dims), _rows(pose)))
            elif geom == pb.GEOM_SPHERE:
                out.append(Obstacle(label, "sphere", (float(dims[0]),), _rows(pose)))
            elif geom == pb.GEOM_CYLINDER:
                out.append(Obstacle(label, "cylinder", (float(dims[1]), float(dims[0])),
                                    _rows(pose)))
            elif geom == pb.GEOM_CAPSULE:
                r = float(dims[1])
                out.append(Obstacle(label, "cylinder", (r, float(dims[0]) + 2.0 * r),
                                    _rows(pose)))
            elif geom == pb.GEOM_PLANE:
                slab = np.eye(4)
                slab[2, 3] = -FLOOR_SLAB[2] / 2.0
                out.append(Obstacle(label, "box", FLOOR_SLAB, _rows(pose @ slab)))
            elif geom == pb.GEOM_MESH:
                points = pbq.mesh_vertices(client, body, link, k)
                if len(points) >= 4:  # vertices come in the centre-of-mass frame
                    out.append(Obstacle(label, "convex", (), _rows(com),
                                        tuple(map(tuple, points))))
                else:
                    lo, hi = pbq.aabb(client, body, link)
                    box = np.eye(4)
                    box[:3, 3] = (np.asarray(lo) + np.asarray(hi)) / 2.0
                    out.append(Obstacle(label, "box", tuple(np.subtract(hi, lo).tolist()),
                                        _rows(box)))
    return out


def _rows(m: np.ndarray) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(float(v) for v in row) for row in m)


def world_obstacles(
    world: Any, skip: set[str], near: np.ndarray | None = None, reach: float = float("inf")
) -> list[Obstacle]:
    """The shapes of the world's bodies (robots and ``skip`` aside), in the world frame; with
    ``near``, only bodies whose bounding box comes within ``reach`` of that point."""
    out: list[Obstacle] = []
    for info in world.infos.values():
        if info.kind == "robot" or info.name in skip:
            continue
        if near is not None and info.kind != "ground":
            box = pbq.aabb(world.client, info.body_id, -1)
            lo, hi = np.asarray(box.lower), np.asarray(box.upper)
            for link in range(pbq.joint_count(world.client, info.body_id)):
                more = pbq.aabb(world.client, info.body_id, link)
                lo, hi = np.minimum(lo, more.lower), np.maximum(hi, more.upper)
            gap = np.maximum(np.maximum(lo - near, near - hi), 0.0)
            if float(np.linalg.norm(gap)) > reach:
                continue
        out += body_obstacles(world.client, info.body_id, info.name)
    return out
