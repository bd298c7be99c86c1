"""Gripper behaviours: open and close the parallel fingers under position control."""

from __future__ import annotations

from typing import Any

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ActionFailed, RobotAction
from bt_manip.bt import registry
from bt_manip.bt.ports import POSITIVE, Accepts, Port
from bt_manip.manipulation.grasps import grasped_object

OPENING = Accepts(low=0, also=(-1,))
"""An opening is a distance between the pads, or -1 (fully open or closed)."""
SETTLED_SPEED = 0.04
"""The fingers count as stopped while the opening changes slower than this (m/s)."""
SETTLE_TIME = 0.15
"""A gripper move ends once the fingers have stayed stopped this long (sim s)."""
MIN_MOVE_TIME = 0.2
"""A gripper move lasts longer than this (sim s): the fingers need time to start moving."""
TIME_EPS = 1e-9
"""Tolerance (s) when comparing sim-time differences."""


class _GripperMove(RobotAction):
    """Command an opening, then wait until the fingers stop moving."""

    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "timeout": Port(float, False, "sim seconds allowed", 3.0, POSITIVE),
    }

    def target(self, robot: Any) -> float:
        raise NotImplementedError

    def start(self) -> None:
        robot = self.robot()
        self.goal = self.target(robot)
        robot.set_gripper(self.goal)
        self.last = robot.gripper_opening()
        self.last_time = self.now()
        self.still_since: float | None = None
        """Sim time from which the fingers have been stopped (None: they are moving)."""

    def step(self) -> Status:
        robot = self.robot()
        opening = robot.gripper_opening()
        now = self.now()
        moved = abs(opening - self.last)
        if moved <= SETTLED_SPEED * (now - self.last_time):
            if self.still_since is None:
                self.still_since = self.last_time
        else:
            self.still_since = None
        self.last, self.last_time = opening, now
        settled = self.still_since is not None and now - self.still_since >= SETTLE_TIME - TIME_EPS
        if settled and self.elapsed() > MIN_MOVE_TIME:
            return self.finished(robot, opening)
        if self.elapsed() > float(self.get_input("timeout")):
            raise ActionFailed(
                f"fingers still moving after {self.get_input('timeout')} s "
                f"(opening {opening * 1000:.0f} mm, target {self.goal * 1000:.0f} mm)"
            )
        return Status.RUNNING

    def finished(self, robot: Any, opening: float) -> Status:
        return Status.SUCCESS


@registry.register
class OpenGripper(_GripperMove):
    """Opens the gripper (fully, or to ``opening`` metres between the pads).

    - RUNNING while the fingers move; SUCCESS once they have stopped;
    - FAILURE if they are still moving after ``timeout`` s.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        **_GripperMove.INPUT_PORTS,
        "opening": Port(
            float, False, "opening between the pads (m); -1 = fully", -1.0, OPENING
        ),
    }

    def target(self, robot: Any) -> float:
        value = float(self.get_input("opening"))
        return robot.description.gripper.max_opening if value < 0 else value


@registry.register
class CloseGripper(_GripperMove):
    """Closes the gripper (fully, or to ``opening`` metres) and reports what it holds.

    - RUNNING while the fingers close; SUCCESS once they have stopped, with ``holding`` set to
      whether an object is between the fingers (both touch it) and ``object`` to its name;
    - FAILURE if ``require_object`` is true and the fingers closed on nothing, or on a time-out.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        **_GripperMove.INPUT_PORTS,
        "opening": Port(
            float, False, "target opening (m); -1 = fully closed", -1.0, OPENING
        ),
        "require_object": PortInformation(
            bool, False, "fail when nothing is between the fingers", False
        ),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "holding": PortInformation(bool, False, "an object is between the fingers"),
        "object": PortInformation(str, False, "name of the object between the fingers"),
    }

    def target(self, robot: Any) -> float:
        value = float(self.get_input("opening"))
        return robot.description.gripper.min_opening if value < 0 else value

    def finished(self, robot: Any, opening: float) -> Status:
        name = grasped_object(self.world, robot)
        self.set_output("holding", bool(name))
        self.set_output("object", name)
        if not name and self.get_input("require_object"):
            raise ActionFailed(f"closed on nothing (opening {opening * 1000:.0f} mm)")
        return Status.SUCCESS
