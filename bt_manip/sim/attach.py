"""Attaching objects to robots with a fixed joint made at run time.

An attachment is a PyBullet fixed constraint between a robot link (by default the gripper's
end-effector link) and an object, holding the pose they had when it was made. It is only made
when the object really is in the hand: touching a finger, or within ``max_distance`` (1 cm) of
one. Otherwise :meth:`Attachments.attach` refuses and says how far the object is.

PyBullet expresses constraint frames relative to each link's centre of mass, not the URDF link
frame; the relative pose is computed in those frames so nothing jumps when the joint is made.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, cast

import pybullet as pb

from bt_manip.geometry import compose_poses, invert_pose
from bt_manip.sim import pybullet_queries as pbq
from bt_manip.sim.events import Attached, Detached

DEFAULT_MAX_DISTANCE = 0.01
"""Farthest an object may be from a finger (m) and still be attached."""

SUPPORT_MARGIN = 0.001
"""A static body this close (m) to an object when it is attached supports it, even where the
last step found no contact point (a panel leaning on the side of its slot)."""

LEAVE_CLEARANCE = 0.005
"""Gap (m) an attached object must open from a support before the support counts as left."""

HOLD_FORCE = 2000.0
"""Maximum force (N) the attach joint applies; high enough that a carried panel does not sag."""


@dataclass(frozen=True)
class Attachment:
    """An object held to a robot link by a fixed constraint."""

    object_name: str
    object_body: int
    robot_name: str
    robot_body: int
    link_index: int
    link_name: str
    constraint_id: int


@dataclass(frozen=True)
class AttachResult:
    """Whether an attach/detach happened, and why not when it did not."""

    ok: bool
    reason: str = ""
    distance: float | None = None


class Attachments:
    """The attach joints of one world."""

    def __init__(self, world: Any) -> None:
        self.world = world
        self._by_object: dict[str, Attachment] = {}
        self._touched: dict[str, set[str]] = {}
        self._supports: dict[str, set[int]] = {}

    @property
    def client(self) -> int:
        return cast(int, self.world.client)

    def finger_distance(self, robot: Any, body: int) -> float:
        """Smallest distance (m) between the object and any finger link; <= 0 when touching."""
        best = float("inf")
        for link in robot.finger_link_ids:
            for p in pbq.closest_points(self.client, robot.body, body, 0.05, link):
                best = min(best, p.distance)
        return best

    def attach(
        self,
        robot_name: str,
        object_name: str,
        link: str | None = None,
        max_distance: float = DEFAULT_MAX_DISTANCE,
    ) -> AttachResult:
        """Hold ``object_name`` to a link of ``robot_name`` if it is at the fingers (announced
        as :class:`~bt_manip.sim.events.Attached`).

        Fails (nothing changes) when the robot or object is unknown, the object is already
        attached, or it is farther than ``max_distance`` from every finger.
        """
        world = self.world
        robot = world.robots.get(robot_name)
        if robot is None:
            return AttachResult(False, f"no robot named '{robot_name}'")
        if object_name not in world.movable:
            return AttachResult(False, f"no movable object named '{object_name}'")
        if object_name in self._by_object:
            held = self._by_object[object_name]
            return AttachResult(False, f"'{object_name}' is already attached to {held.robot_name}")
        body = world.movable[object_name]
        distance = self.finger_distance(robot, body)
        if distance > max_distance:
            far = "more than 5 cm" if distance == float("inf") else f"{distance * 100:.1f} cm"
            return AttachResult(
                False,
                f"'{object_name}' is {far} from the fingers (must touch or be within "
                f"{max_distance * 100:.1f} cm)",
                distance,
            )
        link_name = link or robot.description.end_effector
        link_index = robot.link_index(link_name)
        parent = pbq.com_pose(self.client, robot.body, link_index)
        child = pbq.com_pose(self.client, body, -1)
        rel_pos, rel_quat = compose_poses(invert_pose(parent), child)
        cid = pb.createConstraint(
            robot.body,
            link_index,
            body,
            -1,
            pb.JOINT_FIXED,
            [0, 0, 0],
            parentFramePosition=rel_pos,
            childFramePosition=[0, 0, 0],
            parentFrameOrientation=rel_quat,
            childFrameOrientation=[0, 0, 0, 1],
            physicsClientId=self.client,
        )
        pb.changeConstraint(cid, maxForce=HOLD_FORCE, physicsClientId=self.client)
        self._by_object[object_name] = Attachment(
            object_name, body, robot_name, robot.body, link_index, link_name, cid
        )
        self._touched[object_name] = set()
        self._supports[object_name] = self._supports_of(body, robot.body)
        world.events.announce(Attached(world.time, object_name, robot_name, link_name))
        return AttachResult(True, "", distance)

    def detach(self, object_name: str) -> AttachResult:
        """Remove the attach joint of ``object_name`` (announced as
        :class:`~bt_manip.sim.events.Detached`); fails if it is not attached."""
        held = self._by_object.pop(object_name, None)
        if held is None:
            return AttachResult(False, f"'{object_name}' is not attached")
        self._supports.pop(object_name, None)
        pb.removeConstraint(held.constraint_id, physicsClientId=self.client)
        self.world.events.announce(Detached(self.world.time, object_name, held.robot_name))
        return AttachResult(True)

    def _static_names(self) -> dict[int, str]:
        return {
            i.body_id: i.name
            for i in self.world.infos.values()
            if i.kind in ("wall", "furniture", "ground")
        }

    def _supports_of(self, body: int, robot_body: int) -> set[int]:
        """Bodies ``body`` touches, or static bodies within :data:`SUPPORT_MARGIN` of it."""
        out = {c.body_b for c in pbq.contacts(self.client, body) if c.body_b != robot_body}
        for other in self._static_names():
            if other not in out and pbq.closest_points(self.client, body, other, SUPPORT_MARGIN):
                out.add(other)
        return out

    def static_contacts(self, object_name: str) -> list[str]:
        """Static bodies (walls, furniture, floor) the attached object touches now.

        What supported the object when it was attached (the floor, a rack, the sides of a
        slot) does not count until the object has left it, that is moved more than
        :data:`LEAVE_CLEARANCE` away: lifting an object off or out of its support is not a
        collision, touching the support again after that is.
        """
        held = self._by_object.get(object_name)
        if held is None:
            return []
        return self._static_contacts(object_name, held)

    def _static_contacts(self, object_name: str, held: Attachment) -> list[str]:
        """:meth:`static_contacts` of an attached object."""
        supports = self._supports.get(object_name, set())
        if not supports:  # the common case once lifted: touching the hand alone is nothing
            points = pb.getContactPoints(bodyA=held.object_body, physicsClientId=self.client)
            robot = held.robot_body
            if all(p[2] == robot for p in points):
                return []
        touching = self._touching(held.object_body)
        for support in list(supports):  # a support left once is a support no more
            if support not in touching and not pbq.closest_points(
                self.client, held.object_body, support, LEAVE_CLEARANCE
            ):
                supports.discard(support)
        touching -= supports
        touching.discard(held.robot_body)
        if not touching:  # the common case, checked after every step: nothing to name
            return []
        static = self._static_names()
        return sorted(static[b] for b in touching if b in static)

    def _touching(self, body: int) -> set[int]:
        """The bodies ``body`` has contact points with after the last step (read straight from
        ``getContactPoints``, index 2 being body B: this runs after every physics step)."""
        points = pb.getContactPoints(bodyA=body, physicsClientId=self.world.client)
        return {p[2] for p in points}

    def record_contacts(self) -> None:
        """Note every static body an attached object touches now (see :meth:`static_contacts`).

        The World calls this after each step while anything is attached.
        """
        for name, held in self._by_object.items():
            touched = self._static_contacts(name, held)
            if touched:
                self._touched[name].update(touched)

    def touched(self, object_name: str) -> list[str]:
        """Static bodies ``object_name`` has touched since it was last attached."""
        return sorted(self._touched.get(object_name, ()))

    def is_attached(self, object_name: str, robot_name: str | None = None) -> bool:
        held = self._by_object.get(object_name)
        return held is not None and (robot_name is None or held.robot_name == robot_name)

    def held_by(self, robot_name: str) -> list[Attachment]:
        """What a robot holds through attach joints."""
        return [a for a in self._by_object.values() if a.robot_name == robot_name]

    def any(self) -> bool:
        """Whether anything is attached."""
        return bool(self._by_object)

    def all(self) -> list[Attachment]:
        return list(self._by_object.values())
