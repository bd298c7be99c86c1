"""Nav2's small nodes on poses, paths and goal lists, used by its route-server trees:
GetCurrentPose, GetPoseFromPath, ArePosesNear, ConcatenatePaths, GetNextFewGoals and
AppendGoalPoseToGoals.

Poses are ``(x, y, yaw)`` tuples in the world frame (or text a goal port accepts); goal lists
are lists of them (:mod:`bt_manip.nav2.through_poses`).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ROBOT_PORT, ActionFailed, WorldAccess, WorldCondition
from bt_manip.bt.node import PortError, SyncActionNode
from bt_manip.bt.ports import Port
from bt_manip.bt.registry import registry
from bt_manip.nav2.path import Nav2Path, goal_pose
from bt_manip.nav2.through_poses import goals_list

NO_WORLD = SimpleNamespace(poses={})
"""What reads poses without a world: it names none."""


class _PoseAction(WorldAccess, SyncActionNode):
    """A synchronous node whose :meth:`act` may raise ActionFailed or PortError: SUCCESS when
    it returns, FAILURE with the reason when it raises."""

    def update(self) -> Status:
        try:
            self.act()
        except (ActionFailed, PortError) as exc:
            self.feedback_message = str(exc)
            return Status.FAILURE
        self.feedback_message = ""
        return Status.SUCCESS

    def act(self) -> None:
        raise NotImplementedError

    def world_or_none(self) -> object:
        """The world when there is one (to read named poses), else a stand-in without named
        poses (poses as numbers need no world)."""
        try:
            return self.world
        except ActionFailed:
            return NO_WORLD


@registry.register
class GetCurrentPose(_PoseAction):
    """Writes the robot's base pose to ``current_pose``: SUCCESS (FAILURE without a world or
    with a robot it cannot name)."""

    INPUT_PORTS: dict[str, PortInformation] = {
        "robot": ROBOT_PORT,
        "robot_base_frame": PortInformation(str, False, "Robot base frame", "base_link"),
        "global_frame": PortInformation(str, False, "Global frame", "map"),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "current_pose": PortInformation(object, False, "The current pose in the global frame"),
    }

    def act(self) -> None:
        self.set_output("current_pose", tuple(float(v) for v in self.believed_pose()))


@registry.register
class GetPoseFromPath(_PoseAction):
    """Writes the pose at ``index`` of ``path`` to ``pose`` (``-1`` the last, ``-2`` the one
    before, ...): SUCCESS; FAILURE without a path, with an empty one or an index outside it."""

    INPUT_PORTS: dict[str, PortInformation] = {
        "path": PortInformation(Nav2Path, True, "Path to extract pose from"),
        "index": Port(int, False, "Index from path to use (-1: the last pose)", 0),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "pose": PortInformation(object, False, "Pose from path"),
    }

    def act(self) -> None:
        path = self.get_input("path", None)
        if not isinstance(path, Nav2Path) or len(path) == 0:
            raise ActionFailed(f"no pose to take from {path!r}")
        index = int(self.get_input("index"))
        if not -len(path) <= index < len(path):
            raise ActionFailed(f"index {index} is outside the path's {len(path)} poses")
        self.set_output("pose", tuple(float(v) for v in path.poses[index]))


@registry.register
class ArePosesNear(WorldCondition):
    """SUCCESS when ``ref_pose`` and ``target_pose`` are closer than ``tolerance`` metres (in
    the plane), FAILURE otherwise or when a pose cannot be read."""

    INPUT_PORTS: dict[str, PortInformation] = {
        "ref_pose": PortInformation(object, True, "The initial pose to check"),
        "target_pose": PortInformation(object, True, "The other pose to check against"),
        "global_frame": PortInformation(str, False, "Global frame", "map"),
        "tolerance": Port(float, False, "Tolerance to check poses if nearby with respect to (m)",
                          0.5),
    }

    def check(self) -> tuple[bool, str]:
        world = self.world if _named(self.get_input("ref_pose", None),
                                     self.get_input("target_pose", None)) else NO_WORLD
        a = goal_pose(world, self.get_input("ref_pose"))
        b = goal_pose(world, self.get_input("target_pose"))
        d = math.hypot(a[0] - b[0], a[1] - b[1])
        tolerance = float(self.get_input("tolerance"))
        return d < tolerance, f"the poses are {d:.2f} m apart, not within {tolerance:g} m"


def _named(*values: object) -> bool:
    """Whether any value is text (a named pose needs the world to be read)."""
    return any(isinstance(v, str) for v in values)


@registry.register
class ConcatenatePaths(_PoseAction):
    """Writes ``input_path1`` followed by ``input_path2`` to ``output_path`` (in the first
    path's frame): SUCCESS; FAILURE when either is not a path or both are empty."""

    INPUT_PORTS: dict[str, PortInformation] = {
        "input_path1": PortInformation(Nav2Path, True, "First path to concatenate"),
        "input_path2": PortInformation(Nav2Path, True, "Second path to concatenate"),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "output_path": PortInformation(Nav2Path, False, "Output concatenated path"),
    }

    def act(self) -> None:
        first = self.get_input("input_path1", None)
        second = self.get_input("input_path2", None)
        if not isinstance(first, Nav2Path) or not isinstance(second, Nav2Path):
            raise ActionFailed(f"cannot concatenate {first!r} and {second!r}")
        if len(first) == 0 and len(second) == 0:
            raise ActionFailed("both paths are empty")
        self.set_output("output_path", concatenated(first, second))


def concatenated(first: Nav2Path, second: Nav2Path) -> Nav2Path:
    """The poses of ``first`` then ``second``; the length counts the gap between them."""
    poses = np.vstack([p.poses.reshape(-1, 3) for p in (first, second)])
    gap = 0.0
    if len(first) and len(second):
        a, b = first.poses[-1], second.poses[0]
        gap = math.hypot(float(b[0] - a[0]), float(b[1] - a[1]))
    return Nav2Path(poses, first.frame_id, first.planner_id or second.planner_id,
                    first.length + second.length + gap)


@registry.register
class GetNextFewGoals(_PoseAction):
    """Writes the first ``num_goals`` goals of ``input_goals`` (all of them when there are
    fewer) to ``output_goals``: SUCCESS; FAILURE when the goals cannot be read."""

    INPUT_PORTS: dict[str, PortInformation] = {
        "num_goals": Port(int, True, "How many of the goals to take from the input goals"),
        "input_goals": PortInformation(object, True, "Input goals list"),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "output_goals": PortInformation(object, False, "The output pruned goals list"),
    }

    def act(self) -> None:
        goals = goals_list(self.world_or_none(), self.get_input("input_goals"))
        count = max(0, int(self.get_input("num_goals")))
        self.set_output("output_goals", goals[:count])


@registry.register
class AppendGoalPoseToGoals(_PoseAction):
    """Writes ``input_goals`` with ``goal_pose`` added at the end to ``output_goals``:
    SUCCESS; FAILURE when the goals or the pose cannot be read."""

    INPUT_PORTS: dict[str, PortInformation] = {
        "goal_pose": PortInformation(object, True, "Goal pose to append to the goals"),
        "input_goals": PortInformation(object, True, "Input goals vector to append to"),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "output_goals": PortInformation(object, False, "Output goals vector appended to"),
    }

    def act(self) -> None:
        world = self.world_or_none()
        goals = goals_list(world, self.get_input("input_goals"))
        goals.append(goal_pose(world, self.get_input("goal_pose")))
        self.set_output("output_goals", goals)
