"""Nav2's TransformAvailable on bt-manip's frames: the world frame (named ``map``, ``odom`` or
``world``), the base (``base_link``, ``base_footprint``) and every link of the robot."""

from __future__ import annotations

from typing import Any

from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ROBOT_PORT, WorldCondition
from bt_manip.bt.registry import registry

WORLD_FRAMES = frozenset({"map", "odom", "world"})
BASE_FRAMES = frozenset({"base_link", "base_footprint"})


def known_frame(robot: Any, frame: str) -> bool:
    """Whether bt-manip can give a pose of ``frame`` for ``robot``."""
    name = frame.lstrip("/")
    return name in WORLD_FRAMES or name in BASE_FRAMES or bool(robot.has_link(name))


@registry.register
class TransformAvailable(WorldCondition):
    """SUCCESS once the transform between ``parent`` and ``child`` is known (both are frames
    of the world or of the robot); from then on SUCCESS at every tick, as Nav2's latches.
    FAILURE, naming the unknown frame, until then."""

    INPUT_PORTS: dict[str, PortInformation] = {
        "robot": ROBOT_PORT,
        "child": PortInformation(str, False, "Child frame for transform", ""),
        "parent": PortInformation(str, False, "Parent frame for transform", ""),
    }

    found = False

    def check(self) -> tuple[bool, str]:
        if self.found:
            return True, ""
        child, parent = self.get_input("child"), self.get_input("parent")
        if not child or not parent:
            return False, "child and parent frames must both be given"
        robot = self.robot()
        unknown = [f for f in (parent, child) if not known_frame(robot, f)]
        if unknown:
            return False, f"no frame '{unknown[0]}' (frames: map, odom, base_link, links)"
        self.found = True
        return True, ""
