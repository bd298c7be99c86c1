"""A robot spawned in PyBullet, driven through the names of its descriptor.

:class:`Robot` wraps one spawned multibody. Every call passes the PyBullet client id it was
spawned with; nothing here touches a global client. Joints are position controlled within the
velocity and effort limits of the descriptor, wheels are velocity controlled. ``stop_base()``
followed by ``hold_arm()`` leaves the robot safe (wheels braked, arm holding where it is).

A holonomic base (``base.type: holonomic``) is a root link fixed to the world at the spawn pose
with the base link hanging from it by three virtual joints: prismatic x, prismatic y and yaw,
in that order. :meth:`Robot.set_base_velocity` drives them with velocity motors of bounded
force (so a wall or a heavy object still stops the base), :meth:`Robot.stop_base` brakes them
by holding their positions, and :meth:`Robot.base_pose2d` is the pose of the base link (the
child of the yaw joint), not of the fixed root.

The descriptor itself (schema, checks, lookup) is :mod:`bt_manip.sim.robot_description`; its
names are re-exported here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pybullet as pb

from bt_manip.errors import InputError
from bt_manip.geometry import compose_poses, invert_pose, pose_matrix, quat_from_yaw, yaw_of
from bt_manip.sim import pybullet_queries as pbq
from bt_manip.sim.compose import composed_urdf
from bt_manip.sim.fixed_links import MergedFrame
from bt_manip.sim.physics_urdf import physics_model
from bt_manip.sim.pybullet_queries import JointInfo
from bt_manip.sim.robot_description import (
    ArmSpec,
    BaseSpec,
    Footprint,
    GripperSpec,
    RobotDescription,
    find_descriptor,
    known_robots,
    load_description,
)

__all__ = [
    "ArmSpec",
    "BaseSpec",
    "ContactPoint",
    "Footprint",
    "GripperSpec",
    "Robot",
    "RobotDescription",
    "composed_urdf",
    "find_descriptor",
    "known_robots",
    "load_description",
]


@dataclass(frozen=True)
class ContactPoint:
    """One contact between a robot link and another body, from ``getContactPoints``."""

    link: str
    other_body: int
    other_link: int
    position: tuple[float, float, float]
    normal_force: float


class Robot:
    """A robot spawned in a PyBullet world, driven through its descriptor's names.

    Build it with :meth:`spawn`. Link and joint names are the URDF's; :meth:`link_pose` returns
    the URDF link frame (not the centre of mass).
    """

    def __init__(
        self,
        client: int,
        body: int,
        description: RobotDescription,
        merged: dict[str, MergedFrame] | None = None,
    ) -> None:
        self.client = client
        self.body = body
        self.description = description
        self._joints: dict[str, int] = {}
        self._links: dict[str, int] = {}
        self._joint_info: dict[int, JointInfo] = {}
        dynamics = pbq.dynamics_info(client, body, -1)
        self._root_inertial = (
            dynamics.local_inertial_position, dynamics.local_inertial_orientation
        )
        self._links[pbq.root_link_name(client, body)] = -1
        for info in pbq.joint_infos(client, body):
            self._joints[info.name] = info.index
            self._links[info.link_name] = info.index
            self._joint_info[info.index] = info
        self.merged_frames: dict[str, tuple[int, MergedFrame]] = {
            name: (self._links[frame.carrier], frame)
            for name, frame in (merged or {}).items()
            if frame.carrier in self._links and name not in self._links
        }
        """URDF links folded into another link of the loaded file (see
        :mod:`bt_manip.sim.fixed_links`): the carrier's PyBullet index and the frame's offset."""
        self.arm_joint_ids = [self.joint_index(n) for n in description.arm.joints]
        self.gripper_joint_ids = [self.joint_index(n) for n in description.gripper.joints]
        self.finger_link_ids = [self.link_index(n) for n in description.gripper.finger_links]
        self._arm_links: list[int] | None = None
        self._arm_link_set: frozenset[int] | None = None
        self.wheel_ids_left = [self.joint_index(n) for n in description.base.left_wheels]
        self.wheel_ids_right = [self.joint_index(n) for n in description.base.right_wheels]
        self.base_joint_ids = [self.joint_index(n) for n in description.base.joints]
        """Holonomic base: PyBullet indices of the x, y and yaw joints (empty otherwise)."""
        arm = description.arm
        self._arm_velocity = [
            v if v is not None else float(self._joint_info[j].max_velocity)
            for v, j in zip(arm.velocity_limits, self.arm_joint_ids, strict=True)
        ]
        self._arm_effort = [
            e if e is not None else float(self._joint_info[j].max_force)
            for e, j in zip(arm.efforts, self.arm_joint_ids, strict=True)
        ]
        self._gripper_target = self.gripper_opening()

    # -- construction -------------------------------------------------------------------------
    @classmethod
    def spawn(
        cls,
        client: int,
        description: RobotDescription | str | Path,
        x: float,
        y: float,
        yaw: float,
        z: float | None = None,
    ) -> Robot:
        """Load the robot as one multibody at (x, y, yaw) and hold it still.

        ``z`` defaults to the descriptor's ``spawn_height`` (wheels touching z=0). Fixed-base
        robots are welded to the world, and so is the root of a holonomic base (the spawn pose
        is where its virtual joints are at 0). Arm and gripper then hold their initial positions
        and the base is braked, so the robot stays at rest until commanded.

        Without PyBullet's own window the file loaded is :func:`physics_model`'s (no visuals,
        collision meshes as their hulls, fixed links merged): the same rigid parts, masses and
        collision shapes; the merged links' frames stay reachable by name.
        """
        if not isinstance(description, RobotDescription):
            description = RobotDescription.load(description)
        path = composed_urdf(description)
        merged: dict[str, MergedFrame] = {}
        if not _has_window(client):
            model = physics_model(path)
            path, merged = model.path, model.merged
        z = description.spawn_height if z is None else z
        flags = pb.URDF_USE_INERTIA_FROM_FILE
        try:
            body = pb.loadURDF(
                str(path),
                basePosition=(x, y, z),
                baseOrientation=quat_from_yaw(yaw),
                useFixedBase=description.base.type in ("fixed", "holonomic"),
                flags=flags,
                physicsClientId=client,
            )
        except pb.error:
            raise InputError.single(
                str(description.path), None,
                f"PyBullet cannot load the robot's URDF {path} (check its links and meshes)"
            ) from None
        why = pbq.too_many_links(client, body)
        if why is not None:
            pb.removeBody(body, physicsClientId=client)
            raise InputError.single(str(description.path), None,
                                    f"{why} ({path}, fixed links merged)" if merged else
                                    f"{why} ({path})")
        robot = cls(client, body, description, merged)
        robot._apply_friction()
        robot._couple_fingers()
        robot._hold_other_joints()
        robot._arm_within_limits()
        robot.hold_arm()
        robot.set_gripper(robot.gripper_opening())
        if robot.has_wheels or robot.is_holonomic:
            robot.stop_base()
        return robot

    def _arm_within_limits(self) -> None:
        """PyBullet loads every joint at 0; an arm joint whose limits leave 0 out (a Kinova's
        second, third and fifth joints, 47-313 deg) is set at its nearest limit, where the real
        arm could be: a plan then starts from a configuration within the limits."""
        q = self.arm_positions()
        inside = np.clip(q, self.description.arm.lower, self.description.arm.upper)
        for j, was, now in zip(self.arm_joint_ids, q, inside, strict=True):
            if now != was:
                pb.resetJointState(self.body, j, float(now), 0.0, physicsClientId=self.client)

    def _apply_friction(self) -> None:
        base = self.description.base
        for j in self.wheel_ids_left + self.wheel_ids_right:
            axle = np.abs(np.asarray(self._joint_info[j].axis, dtype=float))
            anisotropic = 1.0 - (1.0 - base.wheel_axle_friction_scale) * axle
            pb.changeDynamics(
                self.body,
                j,
                lateralFriction=base.wheel_friction,
                spinningFriction=base.wheel_spinning_friction,
                rollingFriction=base.wheel_rolling_friction,
                anisotropicFriction=anisotropic.tolist(),
                frictionAnchor=1,
                contactProcessingThreshold=WHEEL_CONTACT_GAP,
                physicsClientId=self.client,
            )
        gripper = self.description.gripper
        for link in self.finger_link_ids:
            pb.changeDynamics(
                self.body,
                link,
                lateralFriction=gripper.pad_friction,
                frictionAnchor=1,
                physicsClientId=self.client,
            )

    def _hold_other_joints(self) -> None:
        """Hold every movable joint that is neither arm, gripper, wheel nor base (a head, a
        torso left out of the arm, a hand's spreading joints) where it is, with its own effort
        limit, so it neither flops under gravity nor gives way when touched."""
        used = set(self.arm_joint_ids + self.gripper_joint_ids + self.wheel_ids_left
                   + self.wheel_ids_right + self.base_joint_ids)
        for index, info in self._joint_info.items():
            if index in used or info.type not in (pb.JOINT_REVOLUTE, pb.JOINT_PRISMATIC):
                continue
            position = float(pb.getJointState(self.body, index, physicsClientId=self.client)[0])
            pb.setJointMotorControl2(
                self.body, index, pb.POSITION_CONTROL, targetPosition=position,
                force=max(float(info.max_force), 1.0), physicsClientId=self.client,
            )

    def _couple_fingers(self) -> None:
        """Make two fingers move as mirror images (a gear constraint: equal joint positions).

        Without it, each finger's motor saturates on its own when squeezing and a held object
        can be walked sideways by the pair.
        """
        if len(self.gripper_joint_ids) != 2 or not self.description.gripper.is_parallel:
            return
        a, b = self.gripper_joint_ids
        gear = pb.createConstraint(
            self.body,
            a,
            self.body,
            b,
            pb.JOINT_GEAR,
            [0, 1, 0],
            [0, 0, 0],
            [0, 0, 0],
            physicsClientId=self.client,
        )
        pb.changeConstraint(
            gear,
            gearRatio=-1,
            maxForce=10 * self.description.gripper.max_force,
            erp=0.2,
            physicsClientId=self.client,
        )

    # -- names --------------------------------------------------------------------------------
    @property
    def name(self) -> str:
        return self.description.name

    @property
    def has_wheels(self) -> bool:
        return bool(self.wheel_ids_left)

    @property
    def is_holonomic(self) -> bool:
        """True for a base driven by virtual planar joints (x, y, yaw)."""
        return bool(self.base_joint_ids)

    def joint_index(self, name: str) -> int:
        """PyBullet joint index of the joint called ``name`` (KeyError names the choices)."""
        return self._index(self._joints, name, "joint")

    def arm_link_ids(self) -> list[int]:
        """PyBullet indices of the links the arm moves: the first arm joint's child link and
        everything below it (gripper included)."""
        if self._arm_links is None:
            parents = {j: info.parent_index for j, info in self._joint_info.items()}
            links = {self.joint_index(self.description.arm.joints[0])}
            grew = True
            while grew:
                grew = False
                for child, parent in parents.items():
                    if parent in links and child not in links:
                        links.add(child)
                        grew = True
            self._arm_links = sorted(links)
        return list(self._arm_links)

    def arm_link_set(self) -> frozenset[int]:
        """:meth:`arm_link_ids` as a set, kept (a robot's links do not change): what a contact
        check that runs every tick tests links against."""
        if self._arm_link_set is None:
            self._arm_link_set = frozenset(self.arm_link_ids())
        return self._arm_link_set

    def link_index(self, name: str) -> int:
        """PyBullet link index of the URDF link ``name`` (-1 for the root link); for a link merged
        into another, the index of the link that carries it."""
        merged = self.merged_frames.get(name)
        if merged is not None:
            return merged[0]
        return self._index(self._links, name, "link")

    def has_link(self, name: str) -> bool:
        """Whether the URDF has a link ``name`` (merged or not)."""
        return name in self._links or name in self.merged_frames

    def _index(self, table: dict[str, int], name: str, what: str) -> int:
        try:
            return table[name]
        except KeyError:
            raise KeyError(
                f"{self.name} has no {what} '{name}'; {what}s: {', '.join(table)}"
            ) from None

    def link_name(self, index: int) -> str:
        """URDF name of the link with PyBullet index ``index``."""
        for name, i in self._links.items():
            if i == index:
                return name
        raise KeyError(f"{self.name} has no link index {index}")

    # -- poses --------------------------------------------------------------------------------
    def link_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """World pose of URDF link ``name``: position (3,) and quaternion (x, y, z, w)."""
        index = self.link_index(name)
        pos: Sequence[float]
        quat: Sequence[float]
        if index == -1:
            pos, quat = self._root_pose()
        else:
            state = pbq.link_state(self.client, self.body, index)
            pos, quat = state.frame_position, state.frame_orientation
        merged = self.merged_frames.get(name)
        if merged is not None:
            pos, quat = compose_poses((pos, quat), (merged[1].position, merged[1].quat))
        return np.array(pos), np.array(quat)

    def link_transform(self, name: str) -> np.ndarray:
        """World pose of URDF link ``name`` as a 4x4 homogeneous matrix."""
        return pose_matrix(*self.link_pose(name))

    def _root_pose(self) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """URDF frame of the root link (PyBullet reports the root's centre-of-mass frame)."""
        com_pos, com_quat = pb.getBasePositionAndOrientation(self.body, physicsClientId=self.client)
        return compose_poses((com_pos, com_quat), invert_pose(self._root_inertial))

    def base_pose2d(self) -> tuple[float, float, float]:
        """Planar pose (x, y, yaw) of the root link frame in the world (of the base link, the
        child of the yaw joint, for a holonomic base)."""
        pos: Sequence[float]
        quat: Sequence[float]
        if self.is_holonomic:
            state = pbq.link_state(self.client, self.body, self.base_joint_ids[2])
            pos, quat = state.frame_position, state.frame_orientation
        else:
            pos, quat = self._root_pose()
        return float(pos[0]), float(pos[1]), yaw_of(quat)

    def base_velocity(self) -> tuple[float, float, float]:
        """Forward and sideways speed (m/s, in the base heading frame) and yaw rate (rad/s)."""
        if self.is_holonomic:
            states = pbq.joint_states(self.client, self.body, self.base_joint_ids)
            xd, yd, wd = (s.velocity for s in states)
            theta = states[2].position  # heading relative to the root, whose axes x, y follow
            c, s = math.cos(theta), math.sin(theta)
            return c * xd + s * yd, -s * xd + c * yd, float(wd)
        lin, ang = pb.getBaseVelocity(self.body, physicsClientId=self.client)
        # PyBullet gives the velocity of the root's centre of mass; the root frame moves with
        # v + w x (frame - centre of mass)
        com, _ = pb.getBasePositionAndOrientation(self.body, physicsClientId=self.client)
        frame, quat = self._root_pose()
        arm = np.subtract(frame, com)
        v = np.asarray(lin) + np.cross(ang, arm)
        yaw = yaw_of(quat)
        c, s = math.cos(yaw), math.sin(yaw)
        return float(c * v[0] + s * v[1]), float(-s * v[0] + c * v[1]), float(ang[2])

    def reset_base_pose(self, x: float, y: float, yaw: float, z: float | None = None) -> None:
        """Put the root link frame at (x, y, z) with heading ``yaw`` at rest (``z`` defaults to
        the descriptor's spawn height): a set-up step for tools and tests, not a motion. Not for
        a holonomic base (its root is welded to the world)."""
        z = self.description.spawn_height if z is None else z
        pos, quat = compose_poses(((x, y, z), quat_from_yaw(yaw)), self._root_inertial)
        pb.resetBasePositionAndOrientation(self.body, pos, quat, physicsClientId=self.client)
        pb.resetBaseVelocity(self.body, [0, 0, 0], [0, 0, 0], physicsClientId=self.client)

    # -- arm ----------------------------------------------------------------------------------
    def _positions(self, ids: Sequence[int]) -> np.ndarray:
        return np.array(pbq.joint_motion(self.client, self.body, list(ids))[0])

    def arm_positions(self) -> np.ndarray:
        """Arm joint positions (rad) in descriptor order."""
        return self._positions(self.arm_joint_ids)

    def arm_velocities(self) -> np.ndarray:
        """Arm joint velocities (rad/s) in descriptor order."""
        return np.array(self.arm_motion()[1])

    def arm_motion(self) -> tuple[list[float], list[float]]:
        """Arm joint positions (rad) and velocities (rad/s) in descriptor order, as plain
        floats, from one query (what a controller checks every tick)."""
        return pbq.joint_motion(self.client, self.body, self.arm_joint_ids)

    def set_arm_targets(
        self, q: Sequence[float] | np.ndarray, max_velocity: float | Sequence[float] | None = None
    ) -> None:
        """Drive the arm joints toward ``q`` (rad, descriptor order) under position control.

        Each joint moves at most at its velocity limit (or ``max_velocity``, one value for all
        joints or one per joint, if lower) and pushes with at most its effort limit. Targets
        outside the joint limits are clipped.
        """
        q_arr = np.asarray(q, dtype=float)
        arm = self.description.arm
        ids = self.arm_joint_ids
        n = len(ids)
        if q_arr.shape != (n,):
            raise ValueError(f"{self.name}: expected {n} arm targets, got {q_arr.shape}")
        # element-wise min and clip on plain floats: the same values numpy's minimum and clip
        # give, without building arrays for a handful of joints
        limits: list[float] = self._arm_velocity
        if max_velocity is not None:
            if isinstance(max_velocity, list) and len(max_velocity) == n:
                caps = [float(v) for v in max_velocity]
            else:
                caps = np.broadcast_to(np.asarray(max_velocity, float), (n,)).tolist()
            # numpy.minimum(limits, caps) on plain floats (a NaN wins, as there)
            limits = [c if c < v or c != c else v for v, c in zip(limits, caps, strict=True)]
        gain = arm.position_gain
        client, body, control = self.client, self.body, pb.POSITION_CONTROL
        for j, target, lo, hi, speed, effort in zip(
            ids, q_arr.tolist(), arm.lower, arm.upper, limits, self._arm_effort, strict=True
        ):
            # numpy.clip(target, lo, hi): minimum(maximum(target, lo), hi)
            if lo > target:
                target = float(lo)
            if hi < target:
                target = float(hi)
            # positional arguments (PyBullet parses them several times faster than keywords),
            # in its order: targetPosition, targetVelocity, force, positionGain, velocityGain,
            # maxVelocity, physicsClientId
            pb.setJointMotorControl2(
                body, j, control, target, 0.0, effort, gain, 1.0, speed, client
            )

    def hold_arm(self) -> None:
        """Hold every arm joint at its current position."""
        self.set_arm_targets(self.arm_positions())

    def reset_arm(self, q: Sequence[float] | str) -> None:
        """Teleport the arm to ``q`` (rad, or a named state such as ``"home"``) and hold it there.

        For setting a scene up only: it ignores dynamics and contacts.
        """
        if isinstance(q, str):
            q = self.description.state(q)
        for j, value in zip(self.arm_joint_ids, q, strict=True):
            pb.resetJointState(self.body, j, float(value), 0.0, physicsClientId=self.client)
        self.hold_arm()

    # -- gripper ------------------------------------------------------------------------------
    def set_gripper(self, opening: float) -> None:
        """Command the distance between the finger pads (m), clipped to the gripper's stroke.

        A revolute or hand gripper turns every finger joint the same fraction of its way from
        closed to open (the opening over the gripper's ``width``)."""
        g = self.description.gripper
        if not self.gripper_joint_ids:  # an arm without a gripper
            self._gripper_target = 0.0
            return
        if g.is_parallel:
            finger = float(
                np.clip(
                    opening / len(self.gripper_joint_ids),
                    min(g.closed, g.open), max(g.closed, g.open),
                )
            )
            self._gripper_target = finger * len(self.gripper_joint_ids)
            targets = [finger] * len(self.gripper_joint_ids)
        else:
            fraction = float(np.clip(opening / g.width, 0.0, 1.0))
            self._gripper_target = fraction * g.width
            targets = [
                c + fraction * (o - c)
                for o, c in zip(g.open_positions, g.closed_positions, strict=True)
            ]
        for j, target in zip(self.gripper_joint_ids, targets, strict=True):
            pb.setJointMotorControl2(
                self.body,
                j,
                pb.POSITION_CONTROL,
                targetPosition=target,
                targetVelocity=0.0,
                force=g.max_force,
                maxVelocity=g.max_speed,
                physicsClientId=self.client,
            )

    def open_gripper(self) -> None:
        """Open the fingers fully."""
        self.set_gripper(self.description.gripper.max_opening)

    def close_gripper(self) -> None:
        """Close the fingers; on an object they squeeze it with the gripper's max force."""
        self.set_gripper(self.description.gripper.min_opening)

    def gripper_opening(self) -> float:
        """Current distance between the finger pads (m); for a revolute or hand gripper, the
        mean fraction of the way its joints are open times its ``width``."""
        q = self._positions(self.gripper_joint_ids)
        g = self.description.gripper
        if g.is_parallel or not len(q):
            return float(q.sum())
        opens = np.asarray(g.open_positions, dtype=float)
        closeds = np.asarray(g.closed_positions, dtype=float)
        return float(np.mean((q - closeds) / (opens - closeds)) * g.width)

    @property
    def gripper_target(self) -> float:
        """Last commanded opening (m)."""
        return self._gripper_target

    def contacts(
        self, other_body: int | None = None, links: Sequence[int] | None = None
    ) -> list[ContactPoint]:
        """Contacts of this robot's links (all, or ``links``) with ``other_body`` (or any body)."""
        wanted = None if links is None else set(links)
        out = []
        for c in pbq.contacts(self.client, self.body, other_body):
            if c.body_b == self.body or (wanted is not None and c.link_a not in wanted):
                continue
            out.append(
                ContactPoint(
                    self.link_name(c.link_a),
                    c.body_b,
                    c.link_b,
                    (c.position_on_a[0], c.position_on_a[1], c.position_on_a[2]),
                    float(c.normal_force),
                )
            )
        return out

    def finger_contacts(self, other_body: int | None = None) -> list[ContactPoint]:
        """Contacts of the finger links with ``other_body`` (or any body)."""
        return self.contacts(other_body, self.finger_link_ids)

    def is_grasping(self, other_body: int) -> bool:
        """True when every finger touches ``other_body`` (for a hand: two fingers or more)."""
        touching = {c.link for c in self.finger_contacts(other_body)}
        if self.description.gripper.kind == "hand":
            return len(touching) >= min(2, len(self.finger_link_ids))
        return len(touching) == len(self.finger_link_ids)

    # -- base ---------------------------------------------------------------------------------
    def set_wheel_velocities(self, left: float, right: float) -> None:
        """Spin the left and right wheels at these speeds (rad/s), clipped to the max speed."""
        base = self.description.base
        if not self.has_wheels:
            raise RuntimeError(f"{self.name} has a fixed base")
        limit = base.max_wheel_speed
        for ids, speed in ((self.wheel_ids_left, left), (self.wheel_ids_right, right)):
            speed = min(max(float(speed), -limit), limit)  # np.clip's value, without numpy
            for j in ids:
                pb.setJointMotorControl2(
                    self.body,
                    j,
                    pb.VELOCITY_CONTROL,
                    targetVelocity=speed,
                    force=base.wheel_max_torque,
                    physicsClientId=self.client,
                )

    def set_base_twist(self, v: float, w: float) -> None:
        """Drive the base at forward speed ``v`` (m/s) and yaw rate ``w`` (rad/s), skid-steer.

        If a wheel would exceed the max wheel speed, both sides are scaled down together so the
        path curvature is kept. A holonomic base drives with no sideways speed.
        """
        if self.is_holonomic:
            self.set_base_velocity(v, 0.0, w)
            return
        base = self.description.base
        left = (v - w * base.track_width / 2.0) / base.wheel_radius
        right = (v + w * base.track_width / 2.0) / base.wheel_radius
        peak = max(abs(left), abs(right))
        if peak > base.max_wheel_speed:
            left, right = (left * base.max_wheel_speed / peak, right * base.max_wheel_speed / peak)
        self.set_wheel_velocities(left, right)

    def set_base_velocity(self, vx: float, vy: float, w: float) -> None:
        """Drive a holonomic base at ``vx`` forward, ``vy`` to the left (m/s, base frame) and
        yaw rate ``w`` (rad/s).

        The planar speed is scaled down to ``base.max_speed`` keeping its direction and the yaw
        rate clipped to ``base.max_yaw_rate``. Each virtual joint gets a velocity motor of at
        most ``base.max_force`` (``max_torque`` for yaw), so contacts can stop the base. Raises
        ``RuntimeError`` on a base that is not holonomic.
        """
        if not self.is_holonomic:
            raise RuntimeError(f"{self.name} has no holonomic base")
        base = self.description.base
        speed = math.hypot(vx, vy)
        if speed > base.max_speed:
            vx, vy = vx * base.max_speed / speed, vy * base.max_speed / speed
        w = float(np.clip(w, -base.max_yaw_rate, base.max_yaw_rate))
        theta = pbq.joint_states(self.client, self.body, self.base_joint_ids[2:])[0].position
        c, s = math.cos(theta), math.sin(theta)
        targets = (c * vx - s * vy, s * vx + c * vy, w)
        forces = (base.max_force, base.max_force, base.max_torque)
        for j, target, force in zip(self.base_joint_ids, targets, forces, strict=True):
            pb.setJointMotorControl2(
                self.body,
                j,
                pb.VELOCITY_CONTROL,
                targetVelocity=float(target),
                force=force,
                physicsClientId=self.client,
            )

    def stop_base(self) -> None:
        """Brake: hold every wheel at its current angle with full torque (no creep); a
        holonomic base holds its virtual joints where they are with their motors' force.

        Does nothing on a fixed base.
        """
        if self.is_holonomic:
            base = self.description.base
            forces = (base.max_force, base.max_force, base.max_torque)
            ids = self.base_joint_ids
            for j, q, force in zip(ids, self._positions(ids), forces, strict=True):
                pb.setJointMotorControl2(
                    self.body,
                    j,
                    pb.POSITION_CONTROL,
                    targetPosition=float(q),
                    targetVelocity=0.0,
                    force=force,
                    positionGain=0.5,
                    velocityGain=1.0,
                    physicsClientId=self.client,
                )
            return
        if not self.has_wheels:
            return
        base = self.description.base
        ids = self.wheel_ids_left + self.wheel_ids_right
        for j, angle in zip(ids, self._positions(ids), strict=True):
            pb.setJointMotorControl2(
                self.body,
                j,
                pb.POSITION_CONTROL,
                targetPosition=float(angle),
                targetVelocity=0.0,
                force=base.wheel_max_torque,
                positionGain=0.5,
                velocityGain=1.0,
                physicsClientId=self.client,
            )

    def halt(self) -> None:
        """Leave the robot safe: base braked, arm holding its position, gripper unchanged."""
        self.stop_base()
        self.hold_arm()


WHEEL_CONTACT_GAP = 0.0
"""m: a wheel's contact points further from the floor than this are not solved. A rolling wheel
leaves behind points its contact manifold keeps for a while, a few tenths of a millimetre up
(two to four per wheel); solving them changes nothing (they are apart and closing at the speed
of a rolling rim) and they were most of a driving robot's contact rows."""


def _has_window(client: int) -> bool:
    """True when ``client`` is PyBullet's GUI, which draws the URDF's own visuals."""
    info = pb.getConnectionInfo(physicsClientId=client)
    return bool(info.get("connectionMethod") == pb.GUI)
