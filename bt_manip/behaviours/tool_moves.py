"""MoveToolBy: move the gripper by an offset along a straight line, orientation kept.

The offset is given in the robot base's frame (x ahead, y to the left, z up) or in the world's.
It is the horizontal counterpart of ``Lift height=...``: pulling a carried panel in towards the
robot after lifting it, so that it stays clear of a wall the robot drives up to, and reaching
out again to set it down.
"""

from __future__ import annotations

import numpy as np
from py_trees.ports import PortInformation

from bt_manip.behaviours.arm import VIA, JointMove, Stage, _through
from bt_manip.behaviours.base import ActionFailed
from bt_manip.bt import registry
from bt_manip.bt.ports import Accepts, Port, count_of
from bt_manip.manipulation import cartesian
from bt_manip.manipulation.base_search import planar

MAX_OFFSET = 1.0
"""Largest offset (m) along each axis."""


@registry.register
class MoveToolBy(JointMove):
    """Moves the grasp frame by ``offset`` (x;y;z, m) on a straight line of IK waypoints, its
    orientation kept; ``frame`` says whose axes: ``base`` (the robot's: x ahead, y left, z up)
    or ``world``.

    - RUNNING while the arm moves;
    - SUCCESS when the arm is at the end of the line within ``tolerance``;
    - FAILURE when a point of the line is out of reach (the reason says which), on a time-out,
      or when the arm or what it carries touches a wall, furniture or the floor (the line is
      checked in the arm's planning scene before the arm moves, naming what it would touch).
    Halted: the arm holds where it is.
    """

    LINE_CHECK = True
    LINE_NAME = "the tool's straight move"

    CARRIES = True
    INPUT_PORTS: dict[str, PortInformation] = {
        **JointMove.INPUT_PORTS,
        "offset": Port(
            list[float], True, "how far to move the tool x;y;z (m)", [0.0, 0.0, 0.0],
            Accepts(-MAX_OFFSET, MAX_OFFSET, check=count_of(3).check),
        ),
        "frame": Port(
            str, False, "axes of the offset: base or world", "base",
            Accepts(choices=("base", "world")),
        ),
        "via_tolerance": VIA,
    }

    def plan(self, q_now: np.ndarray) -> list[Stage]:
        offset = np.asarray(self.get_input("offset"), dtype=float)
        if offset.shape != (3,):
            raise ActionFailed(f"offset takes three numbers x;y;z, got {offset.size}")
        robot = self.robot()
        if self.get_input("frame") == "base":
            offset = planar(*robot.base_pose2d())[:3, :3] @ offset
        tip = robot.description.grasp_frame
        start = robot.link_transform(tip)
        goal = start.copy()
        goal[:3, 3] += offset
        path = cartesian.line(self.services(), tip, start, goal, q_now)
        return _through(path, len(q_now))
