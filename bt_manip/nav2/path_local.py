"""Nav2's TruncatePathLocal: the stretch of a path around the robot.

The pose of the path nearest the robot (distance in the plane, plus ``angular_distance_weight``
times the heading difference) is found; the output keeps the poses from there back along the
path while their distance along it stays within ``distance_backward``, and forward while it
stays within ``distance_forward``. With a finite ``max_robot_pose_search_dist`` the search
for the nearest pose starts where the last one was found and looks only that far ahead
along the path (so a path that loops back near itself is followed in order), as long as the
path stays the same one.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ROBOT_PORT, ActionFailed, WorldAccess
from bt_manip.bt.node import PortError, SyncActionNode
from bt_manip.bt.ports import NON_NEGATIVE_OR_INF, Accepts, Port
from bt_manip.bt.registry import registry
from bt_manip.nav2.path import Nav2Path, Pose2D, goal_pose


def _steps(poses: np.ndarray) -> np.ndarray:
    d = np.diff(poses[:, :2], axis=0)
    return np.hypot(d[:, 0], d[:, 1])


def first_beyond(steps: np.ndarray, start: int, distance: float) -> int:
    """Index of the first pose after ``start`` whose distance along the path from ``start``
    exceeds ``distance`` (the number of poses when none does). ``steps[k]`` is the length
    from pose k to pose k + 1."""
    run = np.cumsum(steps[start:])
    beyond = np.flatnonzero(run > distance)
    return start + 1 + int(beyond[0]) if len(beyond) else len(steps) + 1


def first_before(steps: np.ndarray, start: int, distance: float) -> int:
    """Index of the first pose kept going back from ``start``: the earliest pose whose
    distance along the path back to ``start`` is within ``distance``."""
    back = np.cumsum(steps[:start][::-1])  # back[k]: from pose start - 1 - k to start
    within = int(np.count_nonzero(back <= distance)) if len(back) else 0
    # back is increasing, so the poses within are the first `within` steps back
    return start - within


def nearest_pose(poses: np.ndarray, pose: Pose2D, weight: float, begin: int, end: int) -> int:
    """Index in ``begin:end`` of the pose nearest ``pose`` (the first of equals)."""
    part = poses[begin:end]
    dx = part[:, 0] - pose[0]
    dy = part[:, 1] - pose[1]
    da = weight * np.abs(np.remainder(part[:, 2] - pose[2] + math.pi, math.tau) - math.pi)
    return begin + int(np.argmin(dx * dx + dy * dy + da * da))


@registry.register
class TruncatePathLocal(WorldAccess, SyncActionNode):
    """Writes the part of ``input_path`` around the robot (or ``pose``) to ``output_path``:
    from ``distance_backward`` metres behind the nearest pose to ``distance_forward`` ahead of
    it, measured along the path (module docstring).

    - SUCCESS: ``output_path`` written (an empty path is written as it is);
    - FAILURE: ``input_path`` is not a path, or the robot's pose cannot be read (no world,
      unknown robot) and no ``pose`` is given; the reason is in the feedback message.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "robot": ROBOT_PORT,
        "input_path": PortInformation(Nav2Path, True, "Original Path"),
        "distance_forward": Port(float, False, "Distance in forward direction (m); negative: "
                                 "the whole path ahead", 8.0),
        "distance_backward": Port(float, False, "Distance in backward direction (m)", 4.0,
                                  Accepts(low=0)),
        "robot_frame": PortInformation(str, False, "Robot base frame id", "base_link"),
        "transform_tolerance": Port(float, False, "Transform lookup tolerance (s)", 0.2,
                                    Accepts(low=0)),
        "pose": PortInformation(object, False, "Manually specified pose to be used "
                                "if overriding current robot pose"),
        "angular_distance_weight": Port(float, False, "Weight of angular distance relative to "
                                        "positional distance when finding which path pose is "
                                        "closest to robot", 0.0, Accepts(low=0)),
        "max_robot_pose_search_dist": Port(float, False, "Maximum forward integrated distance "
                                           "along the path (starting from the last detected "
                                           "pose) to bound the search for the closest pose to "
                                           "the robot (m)", math.inf, NON_NEGATIVE_OR_INF),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "output_path": PortInformation(Nav2Path, False, "Truncated Path"),
    }

    def __init__(self, name: str | None = None, **attributes: Any) -> None:
        super().__init__(name, **attributes)
        self.path: Nav2Path | None = None
        self.search_begin = 0

    def _pose(self) -> Pose2D:
        given = self.get_input("pose", None)
        if given is not None:
            # text may name a pose of the world; a pose tuple needs no world
            return goal_pose(self.world if isinstance(given, str) else None, given)
        pose: Pose2D = self.believed_pose()
        return pose

    def update(self) -> Status:
        try:
            path = self.get_input("input_path", None)
            if not isinstance(path, Nav2Path):
                raise ActionFailed(f"no path to truncate (got {path!r})")
            search = float(self.get_input("max_robot_pose_search_dist"))
            pruning = math.isfinite(search)
            if not pruning or path is not self.path:
                self.path = path
                self.search_begin = 0
            pose = self._pose()
        except (ActionFailed, PortError) as exc:
            self.feedback_message = str(exc)
            return Status.FAILURE
        self.feedback_message = ""
        if len(path) == 0:
            self.set_output("output_path", path)
            return Status.SUCCESS
        poses = path.poses
        steps = _steps(poses)
        end = first_beyond(steps, self.search_begin, search) if pruning else len(poses)
        weight = float(self.get_input("angular_distance_weight"))
        here = nearest_pose(poses, pose, weight, self.search_begin, max(end, self.search_begin + 1))
        if pruning:
            self.search_begin = here
        forward = float(self.get_input("distance_forward"))
        stop = len(poses) if forward < 0 else first_beyond(steps, here, forward)
        start = first_before(steps, here, float(self.get_input("distance_backward")))
        kept = poses[start:stop].copy()
        length = float(np.sum(_steps(kept))) if len(kept) > 1 else 0.0
        self.set_output("output_path", Nav2Path(kept, path.frame_id, path.planner_id, length))
        return Status.SUCCESS
