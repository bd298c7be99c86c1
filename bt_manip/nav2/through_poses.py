"""Nav2's nodes for navigating through several poses: ComputePathThroughPoses and
RemovePassedGoals.

The goals are a list of poses: from Python a list of ``(x, y, yaw)``, from the command line
text with the poses separated by ``|``, each a named pose of the world or ``x;y;yaw``
(``--bb "goals=-1;3;0|kitchen|2.6;-0.7;0.85"``).
"""

from __future__ import annotations

import enum
import math
from typing import Any

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ROBOT_PORT, ActionFailed, RobotAction, WorldAccess
from bt_manip.behaviours.navigate import synced_navigator
from bt_manip.bt.node import PortError, SyncActionNode
from bt_manip.bt.ports import POSITIVE, Port
from bt_manip.bt.registry import registry
from bt_manip.nav2.actions import PLAN_PORTS, PlanAction, ahead_of, error_ports, plan_error
from bt_manip.nav2.blocking import maybe_block
from bt_manip.nav2.path import Nav2Path, Pose2D, goal_pose, path_from_points
from bt_manip.nav2.waypoints import (
    WaypointStatus,
    mark_completed,
    pending_statuses,
    statuses_of,
)


class ThroughPosesError(enum.IntEnum):
    """ComputePathThroughPoses result codes."""

    NONE = 0
    UNKNOWN = 300
    INVALID_PLANNER = 301
    TF_ERROR = 302
    START_OUTSIDE_MAP = 303
    GOAL_OUTSIDE_MAP = 304
    START_OCCUPIED = 305
    GOAL_OCCUPIED = 306
    TIMEOUT = 307
    NO_VALID_PATH = 308
    NO_VIAPOINTS_GIVEN = 309


def goals_list(world: Any, value: Any) -> list[Pose2D]:
    """The goals of a port: a list of poses, or text with poses separated by ``|``."""
    if value is None:
        return []
    if isinstance(value, str):
        return [goal_pose(world, part) for part in value.split("|") if part.strip()]
    if isinstance(value, (list, tuple)):
        return [goal_pose(world, v) for v in value]
    raise ActionFailed(f"goals {value!r} are neither a list of poses nor poses separated by |")


ALL_GOALS = -1
"""``last_reached_index`` of a plan through every goal (Nav2's ComputePathThroughPoses
ALL_GOALS)."""


@registry.register
class ComputePathThroughPoses(PlanAction):
    """Plans one path from the robot (or ``start``) through every pose of ``goals`` in turn
    (A* on the robot's costmap, leg by leg), ending on the last one.

    - SUCCESS: ``path`` holds the path through every goal, ``last_reached_index`` -1 (Nav2's
      ALL_GOALS: plans are never partial here), ``error_code_id`` 0;
    - FAILURE: 309 NO_VIAPOINTS_GIVEN without goals, else a leg without a path gives Nav2's
      code (304 GOAL_OUTSIDE_MAP, 306 GOAL_OCCUPIED, 308 NO_VALID_PATH, ...) and the reason.
    """

    UNKNOWN = ThroughPosesError.UNKNOWN
    INPUT_PORTS: dict[str, PortInformation] = {
        **RobotAction.INPUT_PORTS,
        "goals": PortInformation(object, True, "Destinations to plan through"),
        **PLAN_PORTS,
        "server_name": PortInformation(
            str, False, "Action server name (no server here: read, not used)",
            "compute_path_through_poses"
        ),
        "server_timeout": PortInformation(
            float, False, "Action server timeout (ms; read, not used)", 20.0
        ),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "path": PortInformation(Nav2Path, False, "Path created by ComputePathThroughPoses node"),
        "last_reached_index": PortInformation(
            int, False, "Index of the last goal a partial plan reaches; -1 (ALL_GOALS): the "
            "plan reaches every goal (always so here: plans are never partial)"
        ),
        **error_ports("The compute path through poses"),
    }

    def __init__(self, name: str | None = None, **attributes: Any) -> None:
        super().__init__(name, **attributes)
        self.blocked_goals: set[tuple[Pose2D, ...]] = set()

    def begin(self) -> None:
        robot = self.base()
        world = self.world
        goals = goals_list(world, self.get_input("goals"))
        if not goals:
            self.fail(ThroughPosesError.NO_VIAPOINTS_GIVEN, "no goals to plan through")
        start = self.start_pose(robot)
        nav = synced_navigator(self, robot)
        nav.refresh()
        p = nav.pivot
        here = ahead_of(start, p)
        legs: list[np.ndarray] = []
        for k, goal in enumerate(goals):
            last = k == len(goals) - 1
            end = ahead_of(goal, p) if last else (goal[0], goal[1])
            plan = nav.plan_to((*here, 0.0), (*end, goal[2]))
            if not plan.ok or plan.polyline is None:
                base = nav.plan_to((*here, 0.0), goal)
                failed = plan if base.ok else base
                # the through-poses codes are the to-pose codes plus 100
                code = ThroughPosesError.NO_VALID_PATH if base.ok else ThroughPosesError(
                    int(plan_error(failed.outcome, failed.reason)) + 100
                )
                self.fail(code, f"no path to goal {k + 1} ({goal[0]:.3f};{goal[1]:.3f}): "
                                f"{failed.reason}")
            legs.append(plan.polyline if not legs else plan.polyline[1:])
            here = end
        points = np.vstack(legs)
        path = path_from_points(points, goals[-1], p)
        self.set_output("path", path)
        self.set_output("last_reached_index", ALL_GOALS)
        key = tuple(goals)
        if key not in self.blocked_goals:
            self.blocked_goals.add(key)
            g = goals[-1]
            maybe_block(self, points, f"{g[0]:.3f};{g[1]:.3f};{g[2]:.3f}")


@registry.register
class RemovePassedGoals(WorldAccess, SyncActionNode):
    """Drops the goals at the front of ``input_goals`` that the robot is within ``radius`` of
    (always keeping the last) and writes the rest to ``output_goals``; each goal dropped is
    marked COMPLETED in ``output_waypoint_statuses`` (:mod:`bt_manip.nav2.waypoints`). When
    ``input_waypoint_statuses`` holds no statuses yet, they start as PENDING for the goals of
    this first tick (Nav2's navigator writes them when the navigation starts). SUCCESS
    (FAILURE without a world or with goals it cannot read)."""

    INPUT_PORTS: dict[str, PortInformation] = {
        "robot": ROBOT_PORT,
        "input_goals": PortInformation(object, True, "Original goals to remove viapoints from"),
        "input_waypoint_statuses": PortInformation(
            list, False, "Original waypoint_statuses to mark waypoint status from"
        ),
        "radius": Port(float, False, "Radius to goal for it to be considered for removal (m)", 0.5,
                       POSITIVE),
        "global_frame": PortInformation(str, False, "Global frame", "map"),
        "robot_base_frame": PortInformation(str, False, "Robot base frame", "base_link"),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "output_goals": PortInformation(object, False, "Goals with passed viapoints removed"),
        "output_waypoint_statuses": PortInformation(
            list, False, "Waypoint_statuses with passed waypoints marked"
        ),
    }

    def __init__(self, name: str | None = None, **attributes: Any) -> None:
        super().__init__(name, **attributes)
        self.started: list[WaypointStatus] | None = None

    def update(self) -> Status:
        try:
            goals = goals_list(self.world, self.get_input("input_goals"))
            x, y, _ = self.believed_pose()
            statuses = statuses_of(self.get_input("input_waypoint_statuses", None))
        except (ActionFailed, PortError) as exc:
            self.feedback_message = str(exc)
            return Status.FAILURE
        if statuses is None:
            if self.started is None:
                self.started = pending_statuses(goals)
            statuses = self.started
        radius = float(self.get_input("radius"))
        while len(goals) > 1 and math.hypot(goals[0][0] - x, goals[0][1] - y) <= radius:
            statuses = mark_completed(statuses, goals.pop(0))
        self.started = statuses
        self.set_output("output_goals", goals)
        self.set_output("output_waypoint_statuses", statuses)
        return Status.SUCCESS
