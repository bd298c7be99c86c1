"""Attach and Detach: a fixed joint between an object and a gripper link, made at run time.

The joint is made only when the object touches a finger or is within ``max_distance`` of one
(see :mod:`bt_manip.sim.attach`); otherwise Attach fails and says how far the object is.
"""

from __future__ import annotations

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ActionFailed, RobotAction
from bt_manip.bt import registry
from bt_manip.bt.ports import NON_NEGATIVE, Port
from bt_manip.sim.attach import DEFAULT_MAX_DISTANCE

OBJECT = PortInformation(str, True, "name of a movable object of the world")


@registry.register
class Attach(RobotAction):
    """Holds ``object`` to the gripper with a fixed joint, if it is at the fingers.

    - SUCCESS when the joint is made (the object then moves with the hand);
    - FAILURE when the object is farther than ``max_distance`` from every finger (the reason
      gives the distance), unknown, or already attached.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "object": OBJECT,
        "link": PortInformation(str, False, "robot link to attach to (default: end effector)", ""),
        "max_distance": Port(
            float, False, "farthest the object may be from a finger (m)", DEFAULT_MAX_DISTANCE,
            NON_NEGATIVE,
        ),
    }

    def step(self) -> Status:
        result = self.world.attachments.attach(
            self.robot_name(),
            self.get_input("object"),
            link=self.get_input("link") or None,
            max_distance=float(self.get_input("max_distance")),
        )
        if not result.ok:
            raise ActionFailed(result.reason)
        return Status.SUCCESS


@registry.register
class Detach(RobotAction):
    """Removes the attach joint of ``object``.

    - SUCCESS when it was attached and is now free;
    - FAILURE when it was not attached.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "object": OBJECT,
    }

    def step(self) -> Status:
        result = self.world.attachments.detach(self.get_input("object"))
        if not result.ok:
            raise ActionFailed(result.reason)
        return Status.SUCCESS
