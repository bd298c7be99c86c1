"""Conditions on the world: attachments, grasps, where objects are, what they touched."""

from __future__ import annotations

import math

import numpy as np
import pybullet as pb
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ROBOT_PORT, ActionFailed, WorldCondition
from bt_manip.behaviours.regions import region_of
from bt_manip.bt import registry
from bt_manip.bt.ports import NON_NEGATIVE, Accepts, Port, count_of
from bt_manip.geometry import rotation_matrix
from bt_manip.manipulation.grasps import grasped_object
from bt_manip.sim import pybullet_queries as pbq

OBJECT = PortInformation(str, True, "name of a movable object of the world")


@registry.register
class IsAttached(WorldCondition):
    """SUCCESS when ``object`` is held by an attach joint (of ``robot``, if given), else FAILURE."""

    INPUT_PORTS: dict[str, PortInformation] = {"object": OBJECT, "robot": ROBOT_PORT}

    def check(self) -> tuple[bool, str]:
        name = self.get_input("object")
        self.object_body(name)
        robot = self.get_input("robot") or None
        if self.world.attachments.is_attached(name, robot):
            return True, ""
        return False, f"'{name}' is not attached" + (f" to {robot}" if robot else "")


@registry.register
class IsHolding(WorldCondition):
    """SUCCESS when the gripper holds ``object`` (every finger touches it, or it is attached);
    with ``object`` empty, when it holds anything. FAILURE otherwise."""

    INPUT_PORTS: dict[str, PortInformation] = {
        "object": PortInformation(str, False, "object name (empty: any object)", ""),
        "robot": ROBOT_PORT,
    }

    def check(self) -> tuple[bool, str]:
        name = self.get_input("object")
        robot = self.robot()
        if name:
            body = self.object_body(name)
            if robot.is_grasping(body) or self.world.attachments.is_attached(name):
                return True, ""
            return False, f"the gripper does not hold '{name}'"
        if grasped_object(self.world, robot) or self.world.attachments.held_by(self.robot_name()):
            return True, ""
        return False, "the gripper holds nothing"


@registry.register
class ObjectInRegion(WorldCondition):
    """SUCCESS when the centre of ``object`` lies in a box region, else FAILURE (also when
    ``inside`` names no body of the world).

    The region is either ``inside``, the name of a body (its box in its own frame, e.g. a bin,
    turned with it; see :mod:`bt_manip.behaviours.regions`), or ``min``/``max`` world corners
    as ``x;y;z``.
    """

    REQUIRED_ANY_OF = (("inside", "min+max"),)
    INPUT_PORTS: dict[str, PortInformation] = {
        "object": OBJECT,
        "inside": PortInformation(str, False, "body whose box is the region", ""),
        "min": Port(list[float], False, "lower corner x;y;z (m, world)", [], count_of(0, 3)),
        "max": Port(list[float], False, "upper corner x;y;z (m, world)", [], count_of(0, 3)),
    }

    def check(self) -> tuple[bool, str]:
        name = self.get_input("object")
        body = self.object_body(name)
        world = self.world
        inside = self.get_input("inside")
        pos, _ = pb.getBasePositionAndOrientation(body, physicsClientId=world.client)
        if inside:
            if region_of(world, inside).contains(np.asarray(pos)):
                return True, ""
            region = f"'{inside}'"
        else:
            lo, hi = self.get_input("min"), self.get_input("max")
            if len(lo) != 3 or len(hi) != 3:
                raise ActionFailed('give inside="body" or min="x;y;z" and max="x;y;z"')
            region = f"[{lo}, {hi}]"
            if all(lo[i] <= pos[i] <= hi[i] for i in range(3)):
                return True, ""
        where = ", ".join(f"{v:.3f}" for v in pos)
        return False, f"'{name}' at ({where}) is not in {region}"


@registry.register
class ObjectAbove(WorldCondition):
    """SUCCESS when the lowest point of ``object`` is at least ``height`` m above the floor."""

    INPUT_PORTS: dict[str, PortInformation] = {
        "object": OBJECT,
        "height": Port(float, False, "clearance above the floor (m)", 0.1, NON_NEGATIVE),
    }

    def check(self) -> tuple[bool, str]:
        name = self.get_input("object")
        body = self.object_body(name)
        lo, _ = pbq.aabb(self.world.client, body)
        need = float(self.get_input("height"))
        if lo[2] >= need:
            return True, ""
        return False, f"'{name}' is {lo[2]:.3f} m above the floor, less than {need:g} m"


@registry.register
class CarriedClear(WorldCondition):
    """SUCCESS when ``object`` has touched no wall, furniture or floor while attached, since
    it was last attached; FAILURE naming what it touched (or when it is not attached)."""

    INPUT_PORTS: dict[str, PortInformation] = {"object": OBJECT}

    def check(self) -> tuple[bool, str]:
        name = self.get_input("object")
        self.object_body(name)
        attachments = self.world.attachments
        if not attachments.is_attached(name):
            return False, f"'{name}' is not attached"
        touched = attachments.touched(name)
        if touched:
            return False, f"'{name}' touched {', '.join(touched)} while carried"
        return True, ""


REST_SPEED = 0.05
"""An object moving slower than this (m/s) ..."""
REST_SPIN = 0.3
"""... and turning slower than this (rad/s) is at rest."""


@registry.register
class ObjectUpright(WorldCondition):
    """SUCCESS when ``object`` stands as it was placed in the world file, within ``max_tilt``
    degrees, or is still moving; FAILURE (the reason gives the tilt) when it has fallen over.

    The tilt is the angle between the world's vertical and the object's axis that pointed most
    upwards in the world file's pose (a panel standing on its long edge: its height axis), taken
    from the ground truth. A panel lying flat has a tilt near 90 deg: its top edge is not up
    any more and a gripper coming from above cannot take it.

    An object is judged at rest: one tilted beyond ``max_tilt`` that still moves (faster than
    5 cm/s or 0.3 rad/s) is falling, and may yet come to rest leaning on something within
    reach, so the answer is SUCCESS until it stops, or until
    it has been tilted and moving for ``settle`` sim seconds, when it is judged as it is.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "object": OBJECT,
        "max_tilt": Port(float, False, "largest tilt that counts as upright (deg)", 30.0,
                         Accepts(0.0, 90.0)),
        "settle": Port(float, False, "longest wait (sim s) for a tilted object to come to rest",
                       3.0, Accepts(0.0, 60.0)),
    }

    falling_since: float | None = None
    """Sim time the object was first seen tilted and moving (None: it is not)."""

    def check(self) -> tuple[bool, str]:
        name = self.get_input("object")
        body = self.object_body(name)
        world = self.world
        placed = rotation_matrix(world.infos[name].spec.pose.quat)
        axis = int(np.argmax(np.abs(placed[2, :])))
        _, quat = pb.getBasePositionAndOrientation(body, physicsClientId=world.client)
        up = rotation_matrix(quat)[:, axis]
        tilt = math.degrees(math.acos(min(1.0, abs(float(up[2])))))
        limit = float(self.get_input("max_tilt"))
        if tilt <= limit:
            self.falling_since = None
            return True, ""
        linear, angular = pb.getBaseVelocity(body, physicsClientId=world.client)
        moving = float(np.linalg.norm(linear)) > REST_SPEED or (
            float(np.linalg.norm(angular)) > REST_SPIN
        )
        now = float(world.clock.now())
        if not moving:
            self.falling_since = None
        else:
            if self.falling_since is None:
                self.falling_since = now
            if now - self.falling_since < float(self.get_input("settle")):
                return True, ""
        return False, (
            f"'{name}' fell over: it is tilted {tilt:.0f} deg from upright (more than "
            f"{limit:g} deg), and the gripper cannot take it from above"
        )
