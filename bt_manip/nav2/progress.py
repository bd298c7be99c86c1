"""Nav2's conditions on the robot's progress: GoalReached, DistanceTraveled, TimeExpired,
IsPathValid and IsStuck. They read the robot's pose and speed in the world and the tree's
clock."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ROBOT_PORT, ActionFailed, WorldCondition
from bt_manip.behaviours.navigate import synced_navigator
from bt_manip.bt.node import PortError
from bt_manip.bt.ports import NON_NEGATIVE, POSITIVE, Port
from bt_manip.bt.registry import registry
from bt_manip.bt.status import NodeStatus
from bt_manip.nav2.path import Nav2Path, goal_pose

FRAME_PORTS: dict[str, PortInformation] = {
    "robot": ROBOT_PORT,
    "global_frame": PortInformation(str, False, "Global frame", "map"),
    "robot_base_frame": PortInformation(str, False, "Robot base frame", "base_link"),
}

GOAL_REACHED_TOLERANCE = 0.25
"""Nav2's default ``goal_reached_tol`` (m)."""


def _inactive(node: Any) -> bool:
    return node.bt_status in (NodeStatus.IDLE, NodeStatus.SKIPPED)


@registry.register
class GoalReached(WorldCondition):
    """SUCCESS when the robot is within 0.25 m of ``goal`` (x, y), FAILURE otherwise."""

    INPUT_PORTS: dict[str, PortInformation] = {
        **FRAME_PORTS,
        "goal": PortInformation(object, True, "Destination"),
    }

    def check(self) -> tuple[bool, str]:
        goal = goal_pose(self.world, self.get_input("goal"))
        x, y, _ = self.believed_pose()
        d = math.hypot(goal[0] - x, goal[1] - y)
        return d <= GOAL_REACHED_TOLERANCE, f"{d:.2f} m from the goal"


class _Every(WorldCondition):
    """SUCCESS each time a measure has grown by a threshold since the last SUCCESS; FAILURE
    otherwise, and on the first tick after being reset (which starts the measure)."""

    def tick_node(self) -> NodeStatus:
        self._was_inactive = _inactive(self)
        return super().tick_node()

    _was_inactive = True

    def update(self) -> Status:
        try:
            mark = self.mark()
            if self._was_inactive:
                self.start = mark
                self.feedback_message = "started"
                return Status.FAILURE
            gone, threshold = self.since(self.start, mark)
        except (ActionFailed, PortError) as exc:
            self.feedback_message = str(exc)
            return Status.FAILURE
        if gone < threshold:
            self.feedback_message = f"{gone:.2f} of {threshold:g}"
            return Status.FAILURE
        self.start = mark
        self.feedback_message = ""
        return Status.SUCCESS

    start: Any = None

    def mark(self) -> Any:
        raise NotImplementedError

    def since(self, start: Any, now: Any) -> tuple[float, float]:
        raise NotImplementedError


@registry.register
class DistanceTraveled(_Every):
    """SUCCESS each time the robot has moved ``distance`` metres (straight-line) from where it
    was at the last SUCCESS; FAILURE otherwise and on its first tick (which records the pose).
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        **FRAME_PORTS,
        "distance": Port(float, False, "The distance that must travel before returning success (m)",
                         1.0, POSITIVE),
    }

    def mark(self) -> tuple[float, float]:
        x, y, _ = self.believed_pose()
        return (x, y)

    def since(self, start: Any, now: Any) -> tuple[float, float]:
        return math.hypot(now[0] - start[0], now[1] - start[1]), float(self.get_input("distance"))


@registry.register
class TimeExpired(_Every):
    """SUCCESS each time ``seconds`` have passed (on the tree's clock) since the last SUCCESS;
    FAILURE otherwise and on its first tick (which starts the clock)."""

    INPUT_PORTS: dict[str, PortInformation] = {
        "seconds": Port(float, False, "Time to check if expired (s)", 1.0, NON_NEGATIVE),
    }

    def mark(self) -> float:
        return self.now()

    def since(self, start: Any, now: Any) -> tuple[float, float]:
        return now - start, float(self.get_input("seconds"))


@registry.register
class IsPathValid(WorldCondition):
    """SUCCESS while the rest of ``path`` (from the pose nearest the robot on) is free on the
    robot's costmap, redrawn with the movable objects where they are now; FAILURE when an
    obstacle now lies on it (or there is no path)."""

    INPUT_PORTS: dict[str, PortInformation] = {
        "robot": ROBOT_PORT,
        "path": PortInformation(Nav2Path, True, "Path to check"),
        "server_timeout": PortInformation(float, False, "Server timeout (ms)", 20.0),
        "max_cost": PortInformation(int, False, "Maximum cost of the path", 253),
        "consider_unknown_as_obstacle": PortInformation(
            bool, False, "Whether to consider unknown cost as obstacle", False
        ),
    }

    def check(self) -> tuple[bool, str]:
        path = self.get_input("path", None)
        if not isinstance(path, Nav2Path) or len(path) == 0:
            return False, "no path to check"
        robot = self.robot()
        nav = synced_navigator(self, robot)
        nav.refresh()
        pts = path.shifted(nav.pivot)
        x, y, yaw = self.believed_pose(robot)
        here = np.array([x + nav.pivot * math.cos(yaw), y + nav.pivot * math.sin(yaw)])
        nearest = int(np.argmin(np.hypot(*(pts - here).T)))
        ahead = pts[nearest:]
        grid = nav.costmap.grid
        rows = np.floor((ahead[:, 1] - grid.origin[1]) / grid.resolution).astype(int)
        cols = np.floor((ahead[:, 0] - grid.origin[0]) / grid.resolution).astype(int)
        r, c = grid.shape
        inside = (rows >= 0) & (rows < r) & (cols >= 0) & (cols < c)
        if not inside.all():
            return False, "the path leaves the map"
        blocked = np.isinf(nav.cost[rows, cols])
        if blocked.any():
            k = int(np.argmax(blocked))
            return False, f"an obstacle lies on the path at ({ahead[k, 0]:.2f}, {ahead[k, 1]:.2f})"
        return True, ""


BRAKE_ACCEL_LIMIT = -10.0
"""Nav2's IsStuck threshold: a forward deceleration (m/s^2) beyond it means the robot hit
something."""


@registry.register
class IsStuck(WorldCondition):
    """SUCCESS when the base's forward speed fell faster than 10 m/s^2 since the last tick
    (it ran into something), FAILURE otherwise (and on the first tick, which has nothing to
    compare with)."""

    INPUT_PORTS: dict[str, PortInformation] = {"robot": ROBOT_PORT}

    previous: tuple[float, float] | None = None

    def check(self) -> tuple[bool, str]:
        speed = self.robot().base_velocity()[0]
        now = self.now()
        before, self.previous = self.previous, (now, speed)
        if before is None or now <= before[0]:
            return False, "robot is free"
        accel = (speed - before[1]) / (now - before[0])
        if accel < BRAKE_ACCEL_LIMIT:
            return True, ""
        return False, "robot is free"
