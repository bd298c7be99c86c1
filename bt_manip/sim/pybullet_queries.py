"""PyBullet queries with named results.

PyBullet answers its queries with plain tuples (``getJointInfo(...)[12]`` is a link name,
``getLinkState(...)[4]`` a link frame position). Every query bt-manip makes goes through a
function here, which returns a :class:`~typing.NamedTuple` whose fields say what each value is.
Names are decoded to text. Every function takes the client id explicitly.

:func:`contacts` is the one contact query: everything that asks what touches what uses it.
"""

from __future__ import annotations

import itertools
from typing import NamedTuple

import numpy as np
import pybullet as pb

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]


class JointInfo(NamedTuple):
    """``getJointInfo``: one joint and the link it moves (the link has the joint's index)."""

    index: int  # type: ignore[assignment]  # mypy: a field named like tuple.index
    name: str
    type: int
    q_index: int
    u_index: int
    flags: int
    damping: float
    friction: float
    lower_limit: float
    upper_limit: float
    max_force: float
    max_velocity: float
    link_name: str
    axis: Vec3
    parent_frame_position: Vec3
    parent_frame_orientation: Quat
    parent_index: int


class JointState(NamedTuple):
    """``getJointStates``: where one joint is and what drives it."""

    position: float
    velocity: float
    reaction_forces: tuple[float, float, float, float, float, float]
    applied_torque: float


class LinkState(NamedTuple):
    """``getLinkState`` (forward kinematics computed): a link's centre of mass and URDF frame."""

    com_position: Vec3
    com_orientation: Quat
    local_inertial_position: Vec3
    local_inertial_orientation: Quat
    frame_position: Vec3
    """World position of the URDF link frame."""
    frame_orientation: Quat


class DynamicsInfo(NamedTuple):
    """``getDynamicsInfo``: mass, friction and the inertial frame of one link."""

    mass: float
    lateral_friction: float
    local_inertia_diagonal: Vec3
    local_inertial_position: Vec3
    """Centre of mass in the URDF link frame."""
    local_inertial_orientation: Quat
    restitution: float
    rolling_friction: float
    spinning_friction: float
    contact_damping: float
    contact_stiffness: float
    body_type: int
    collision_margin: float


class ContactInfo(NamedTuple):
    """``getContactPoints``: one contact point between body A and body B."""

    flag: int
    body_a: int
    body_b: int
    link_a: int
    link_b: int
    position_on_a: Vec3
    position_on_b: Vec3
    normal_on_b: Vec3
    distance: float
    normal_force: float
    lateral_friction_1: float
    lateral_friction_dir_1: Vec3
    lateral_friction_2: float
    lateral_friction_dir_2: Vec3


class ShapeData(NamedTuple):
    """``getVisualShapeData`` / ``getCollisionShapeData``: one geometry of one link.

    ``dimensions`` depends on ``geometry_type``: box full extents (x, y, z), cylinder
    (height, radius, -), sphere (radius, -, -). The frame is relative to the link's centre of
    mass for collision shapes and to the URDF link frame for visual shapes.
    """

    body: int
    link: int
    geometry_type: int
    dimensions: Vec3
    filename: str
    local_position: Vec3
    local_orientation: Quat


class Aabb(NamedTuple):
    """``getAABB``: the corners of an axis-aligned box in world coordinates."""

    lower: Vec3
    upper: Vec3


class RayHit(NamedTuple):
    """``rayTest``/``rayTestBatch``: what one ray hit first (``body`` -1: nothing)."""

    body: int
    link: int
    fraction: float
    position: Vec3
    normal: Vec3


def _text(value: bytes | str) -> str:
    return value.decode() if isinstance(value, bytes) else value


MAX_BODY_LINKS = 128
"""Links of one PyBullet body (its base included) that PyBullet answers queries about: a body
loaded with more has them all refused (``getLinkState failed``)."""


def too_many_links(client: int, body: int) -> str | None:
    """Why PyBullet cannot serve ``body`` (more than :data:`MAX_BODY_LINKS` links), or None."""
    links = joint_count(client, body) + 1
    if links <= MAX_BODY_LINKS:
        return None
    return (f"PyBullet answers for at most {MAX_BODY_LINKS} links of one body, and this URDF "
            f"loads as {links}")


def joint_count(client: int, body: int) -> int:
    """Number of joints (= links other than the root) of ``body``."""
    return int(pb.getNumJoints(body, physicsClientId=client))


def joint_info(client: int, body: int, joint: int) -> JointInfo:
    """Joint ``joint`` of ``body`` (names decoded)."""
    info = pb.getJointInfo(body, joint, physicsClientId=client)
    return JointInfo(
        info[0], _text(info[1]), info[2], info[3], info[4], info[5], info[6], info[7], info[8],
        info[9], info[10], info[11], _text(info[12]), info[13], info[14], info[15], info[16],
    )


def joint_infos(client: int, body: int) -> list[JointInfo]:
    """Every joint of ``body`` in index order."""
    return [joint_info(client, body, j) for j in range(joint_count(client, body))]


def joint_states(client: int, body: int, joints: list[int]) -> list[JointState]:
    """Positions, velocities and efforts of ``joints`` of ``body``, in that order."""
    if not joints:
        return []
    return [JointState(*s) for s in pb.getJointStates(body, joints, physicsClientId=client)]


def joint_motion(client: int, body: int, joints: list[int]) -> tuple[list[float], list[float]]:
    """Positions and velocities of ``joints`` of ``body``, in that order, from one
    ``getJointStates`` query (the fields of :class:`JointState` a controller reads each tick,
    without building a record per joint)."""
    if not joints:
        return [], []
    states = pb.getJointStates(body, joints, physicsClientId=client)
    return [s[0] for s in states], [s[1] for s in states]


def root_link_name(client: int, body: int) -> str:
    """URDF name of the root link of ``body`` (``getBodyInfo``)."""
    return _text(pb.getBodyInfo(body, physicsClientId=client)[0])


def dynamics_info(client: int, body: int, link: int = -1) -> DynamicsInfo:
    """Dynamics of one link of ``body`` (-1: the root link)."""
    return DynamicsInfo(*pb.getDynamicsInfo(body, link, physicsClientId=client)[:12])


def link_state(client: int, body: int, link: int) -> LinkState:
    """World frames of link ``link`` (>= 0) of ``body``, forward kinematics computed."""
    state = pb.getLinkState(body, link, computeForwardKinematics=1, physicsClientId=client)
    return LinkState(*state[:6])


def link_states(client: int, body: int, links: list[int]) -> list[LinkState]:
    """:func:`link_state` for several links of ``body`` in one call."""
    states = pb.getLinkStates(body, links, computeForwardKinematics=1, physicsClientId=client)
    return [LinkState(*s[:6]) for s in states]


def com_pose(client: int, body: int, link: int) -> tuple[Vec3, Quat]:
    """World pose of a link's centre of mass (the root's for ``link`` -1): the frame PyBullet
    gives collision shapes and constraints in."""
    if link < 0:
        pos, quat = pb.getBasePositionAndOrientation(body, physicsClientId=client)
        return tuple(pos), tuple(quat)  # type: ignore[return-value]
    state = link_state(client, body, link)
    return state.com_position, state.com_orientation


def aabb(client: int, body: int, link: int = -1) -> Aabb:
    """World axis-aligned box of one link of ``body`` (-1: the root link)."""
    lower, upper = pb.getAABB(body, link, physicsClientId=client)
    return Aabb(tuple(lower), tuple(upper))  # type: ignore[arg-type]


def visual_shapes(client: int, body: int) -> list[ShapeData]:
    """Visual geometries of every link of ``body``."""
    return [
        ShapeData(s[0], s[1], s[2], tuple(s[3]), _text(s[4]), tuple(s[5]), tuple(s[6]))
        for s in pb.getVisualShapeData(body, physicsClientId=client)
    ]


_REGISTERED_SHAPES: dict[tuple[int, int], list[ShapeData]] = {}
"""Collision geometries of bodies PyBullet gives none for (static rigid bodies, see
:mod:`bt_manip.sim.static_bodies`), by client and body."""


def register_collision_shapes(client: int, body: int, shapes: list[ShapeData]) -> None:
    """Have :func:`collision_shapes` answer ``shapes`` for the base of ``body`` (a body
    without links)."""
    _REGISTERED_SHAPES[(client, body)] = list(shapes)


def forget_collision_shapes(client: int, body: int | None = None) -> None:
    """Drop what :func:`register_collision_shapes` said of ``body`` (of every body of
    ``client`` when ``None``: before the client is disconnected or reset)."""
    if body is not None:
        _REGISTERED_SHAPES.pop((client, body), None)
        return
    for key in [k for k in _REGISTERED_SHAPES if k[0] == client]:
        del _REGISTERED_SHAPES[key]


def collision_shapes(client: int, body: int, link: int) -> list[ShapeData]:
    """Collision geometries of one link of ``body`` (frames relative to its centre of mass)."""
    known = _REGISTERED_SHAPES.get((client, body))
    if known is not None:
        return list(known) if link == -1 else []
    return [
        ShapeData(s[0], s[1], s[2], tuple(s[3]), _text(s[4]), tuple(s[5]), tuple(s[6]))
        for s in pb.getCollisionShapeData(body, link, physicsClientId=client)
    ]


def mesh_vertices(client: int, body: int, link: int, index: int) -> np.ndarray:
    """The vertices (n, 3) of collision shape ``index`` of one link (``getMeshData``), in the
    link's centre-of-mass frame with the shape's offset applied; none when PyBullet gives none."""
    try:
        n, verts = pb.getMeshData(body, link, collisionShapeIndex=index, physicsClientId=client)
    except pb.error:
        return np.zeros((0, 3))
    if not n:
        return np.zeros((0, 3))
    # the (x, y, z) tuples' floats read in order: numpy's conversion of the nested tuples,
    # without looking at each tuple as a sequence first
    flat = np.fromiter(itertools.chain.from_iterable(verts), dtype=float, count=3 * len(verts))
    return flat.reshape(-1, 3)


def contacts(client: int, body: int, other: int | None = None) -> list[ContactInfo]:
    """Contact points of ``body`` (as body A) with ``other`` (or with any body, itself included)
    found by the last simulation step."""
    if other is None:
        points = pb.getContactPoints(bodyA=body, physicsClientId=client)
    else:
        points = pb.getContactPoints(bodyA=body, bodyB=other, physicsClientId=client)
    return [ContactInfo(*p[:14]) for p in points]


def contact_links(client: int, body: int) -> list[tuple[int, int]]:
    """(``link_a``, ``body_b``) of each contact point of ``body`` (as body A) with any body,
    from the same query as :func:`contacts`, without the rest of each point: what a check
    that runs every tick needs to tell which of its links touch which bodies."""
    return [(p[3], p[2]) for p in pb.getContactPoints(bodyA=body, physicsClientId=client)]


def closest_points(
    client: int, body: int, other: int, max_distance: float, link: int | None = None
) -> list[ContactInfo]:
    """Closest points (``getClosestPoints``) between ``body`` (or its link ``link``) and
    ``other`` within ``max_distance``; ``distance`` is negative when they overlap."""
    if link is None:
        points = pb.getClosestPoints(body, other, max_distance, physicsClientId=client)
    else:
        points = pb.getClosestPoints(
            body, other, max_distance, linkIndexA=link, physicsClientId=client
        )
    return [ContactInfo(*p[:14]) for p in points]


def ray_hits(client: int, starts: list[list[float]], ends: list[list[float]]) -> list[RayHit]:
    """First hit of each ray ``starts[i]`` -> ``ends[i]`` (one batch)."""
    return [RayHit(*h[:5]) for h in pb.rayTestBatch(starts, ends, physicsClientId=client)]


def touching(client: int, body: int) -> set[int]:
    """Bodies ``body`` touches now (itself excluded)."""
    return {c.body_b for c in contacts(client, body) if c.body_b != body}
