"""Nav2's checks on the path being followed: ValidatePath, IsGoalNearby, PathExpiringTimer
and IsWithinPathTrackingBounds (current Nav2, the trees of its ``main`` branch and Kilted)."""

from __future__ import annotations

from typing import Any

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ROBOT_PORT, ActionFailed, WorldAccess, WorldCondition
from bt_manip.behaviours.navigate import synced_navigator
from bt_manip.bt.node import ConditionNode, PortError, SyncActionNode
from bt_manip.bt.ports import NON_NEGATIVE, Port
from bt_manip.bt.registry import registry
from bt_manip.nav2.path import Nav2Path
from bt_manip.nav2.path_local import first_beyond, nearest_pose
from bt_manip.nav2.tracking import TrackingFeedback


def _steps(poses: np.ndarray) -> np.ndarray:
    d = np.diff(poses[:, :2], axis=0)
    return np.hypot(d[:, 0], d[:, 1])


def in_collision(nav: Any, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Which ``points`` (n, 2) of the base's turning point put the robot's footprint on an
    obstacle of the navigator's costmap as it is now, or off the map; and which are on it."""
    grid = nav.costmap.grid
    rows = np.floor((points[:, 1] - grid.origin[1]) / grid.resolution).astype(int)
    cols = np.floor((points[:, 0] - grid.origin[0]) / grid.resolution).astype(int)
    r, c = grid.shape
    inside = (rows >= 0) & (rows < r) & (cols >= 0) & (cols < c)
    bad = ~inside
    bad[inside] = np.isinf(nav.cost[rows[inside], cols[inside]])
    return bad, inside


@registry.register
class ValidatePath(WorldAccess, SyncActionNode):
    """Checks ``path`` against the robot's costmap as it is now (the movable objects drawn
    where they are): the robot's footprint at each pose of the path must be free.

    - SUCCESS: no pose of the path (or of its first ``max_lookahead_distance`` metres from
      the pose nearest the robot, when that is positive) is in collision; ``collision_poses``
      is written empty;
    - FAILURE: a pose is in collision or off the map (``collision_poses`` lists them: the
      first only with ``stop_at_first_collision``, else all), or there is no path; the reason
      is in the feedback message.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "robot": ROBOT_PORT,
        "path": PortInformation(Nav2Path, True, "The global path to check for validity"),
        "max_cost": Port(int, False, "The maximum allowable cost for the path to be "
                         "considered valid", 254, NON_NEGATIVE),
        "consider_unknown_as_obstacle": PortInformation(
            bool, False, "Whether to consider unknown cost (255) as obstacle", False
        ),
        "layer_name": PortInformation(str, False, "Name of the costmap layer to check "
                                      "against (empty: the full costmap)", ""),
        "footprint": PortInformation(str, False, "Custom footprint (empty: the robot's)", ""),
        "stop_at_first_collision": PortInformation(
            bool, False, "Whether to stop validation at the first collision", True
        ),
        "max_lookahead_distance": Port(float, False, "Maximum distance ahead of the robot "
                                       "along the path to validate (m; -1: the full path)", -1.0),
        "service_name": PortInformation(str, False, "Costmap service name", "is_path_valid"),
        "server_timeout": PortInformation(float, False, "Service server timeout (ms)", 20.0),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "collision_poses": PortInformation(
            list, False, "Poses of the path that are in collision or invalid"
        ),
    }

    def update(self) -> Status:
        try:
            ok, reason = self._validate()
        except (ActionFailed, PortError) as exc:
            ok, reason = False, str(exc)
        self.feedback_message = "" if ok else reason
        return Status.SUCCESS if ok else Status.FAILURE

    def _validate(self) -> tuple[bool, str]:
        path = self.get_input("path", None)
        if not isinstance(path, Nav2Path) or len(path) == 0:
            self.set_output("collision_poses", [])
            return False, "no path to validate"
        robot = self.robot()
        nav = synced_navigator(self, robot)
        nav.refresh()
        poses = path.poses
        begin, end = 0, len(poses)
        lookahead = float(self.get_input("max_lookahead_distance"))
        if lookahead > 0:
            begin = nearest_pose(poses, self.believed_pose(robot), 0.0, 0, len(poses))
            end = first_beyond(_steps(poses), begin, lookahead)
        pts = path.shifted(nav.pivot)[begin:end]
        bad, inside = in_collision(nav, pts)
        hits = np.flatnonzero(bad)
        if bool(self.get_input("stop_at_first_collision")):
            hits = hits[:1]
        collisions = [tuple(float(v) for v in poses[begin + k]) for k in hits]
        self.set_output("collision_poses", collisions)
        if not len(hits):
            return True, ""
        k = int(hits[0])
        where = "leaves the map" if not inside[k] else "is blocked by an obstacle"
        return False, f"the path {where} at ({pts[k, 0]:.2f}, {pts[k, 1]:.2f})"


@registry.register
class IsGoalNearby(WorldCondition):
    """SUCCESS when the length of ``path`` left from the pose nearest the robot is below
    ``proximity_threshold`` (the goal is near), FAILURE otherwise or without a path.

    With a positive ``max_robot_pose_search_dist`` the nearest pose is searched from the one
    found last, only that far along the path (as long as the path is the same object).
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "robot": ROBOT_PORT,
        "path": PortInformation(Nav2Path, True, "The planned path to evaluate"),
        "proximity_threshold": Port(float, False, "The remaining path length (m) considered "
                                    "as nearby", 1.0),
        "max_robot_pose_search_dist": Port(float, False, "Maximum forward integrated distance "
                                           "along the path to bound the search for the "
                                           "closest pose to the robot (m; negative: the whole "
                                           "path)", -1.0),
        "global_frame": PortInformation(str, False, "The global reference frame", "map"),
        "robot_base_frame": PortInformation(str, False, "Robot base frame", "base_link"),
    }

    def __init__(self, name: str | None = None, **attributes: Any) -> None:
        super().__init__(name, **attributes)
        self.path: Nav2Path | None = None
        self.search_begin = 0

    def check(self) -> tuple[bool, str]:
        path = self.get_input("path", None)
        if not isinstance(path, Nav2Path) or len(path) == 0:
            return False, "no path to measure"
        search = float(self.get_input("max_robot_pose_search_dist"))
        if search < 0 or path is not self.path:
            self.path, self.search_begin = path, 0
        poses = path.poses
        steps = _steps(poses)
        end = first_beyond(steps, self.search_begin, search) if search >= 0 else len(poses)
        here = nearest_pose(poses, self.believed_pose(), 0.0, self.search_begin,
                            max(end, self.search_begin + 1))
        if search >= 0:
            self.search_begin = here
        left = float(np.sum(steps[here:]))
        threshold = float(self.get_input("proximity_threshold"))
        return left < threshold, f"{left:.2f} m of path left, not below {threshold:g} m"


@registry.register
class PathExpiringTimer(ConditionNode):
    """SUCCESS once every ``seconds`` of sim time, counted from when ``path`` last changed.

    The first tick starts the timer and returns FAILURE; a new path (another object on the
    blackboard) restarts it. FAILURE until the time is up, then SUCCESS, and the timer starts
    again.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "seconds": Port(float, False, "Time to check if expired (s)", 1.0, NON_NEGATIVE),
        "path": PortInformation(Nav2Path, True, "Check if path has been updated to enable "
                                "timer reset"),
    }

    def __init__(self, name: str | None = None, **attributes: Any) -> None:
        super().__init__(name, **attributes)
        self.started: float | None = None
        self.path: Any = None

    def update(self) -> Status:
        now = self.now()
        path = self.get_input("path", None)
        if self.started is None:
            self.started, self.path = now, path
            self.feedback_message = "timer started"
            return Status.FAILURE
        if path is not self.path:
            self.started, self.path = now, path
        seconds = float(self.get_input("seconds"))
        if now - self.started < seconds - 1e-9:
            self.feedback_message = f"{now - self.started:.2f} of {seconds:g} s"
            return Status.FAILURE
        self.started = now
        self.feedback_message = ""
        return Status.SUCCESS


@registry.register
class IsWithinPathTrackingBounds(ConditionNode):
    """SUCCESS while ``tracking_feedback`` (written by FollowPath) puts the robot within
    ``max_error_left`` / ``max_error_right`` of its path (by the side it is on) and within
    ``max_error_heading`` of the path's direction; FAILURE when it is out of bounds, with the
    errors in the feedback message. Before any feedback is written the errors count as zero
    (SUCCESS), as in Nav2. Negative bounds are taken as their absolute value.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "max_error_left": Port(float, False, "Maximum allowable tracking error (m) on the left "
                               "side of the path", 0.5),
        "max_error_right": Port(float, False, "Maximum allowable tracking error (m) on the "
                                "right side of the path", 0.5),
        "max_error_heading": Port(float, False, "Maximum allowable heading error (rad)", 3.14),
        "tracking_feedback": PortInformation(TrackingFeedback, False, "The feedback message of "
                                             "the controller, with the tracking error"),
    }

    def update(self) -> Status:
        feedback = self.get_input("tracking_feedback", None)
        if not isinstance(feedback, TrackingFeedback):
            feedback = TrackingFeedback()
        error = feedback.position_tracking_error
        side = "max_error_left" if error >= 0 else "max_error_right"
        within = abs(error) <= abs(float(self.get_input(side)))
        heading = feedback.heading_tracking_error
        within_heading = abs(heading) <= abs(float(self.get_input("max_error_heading")))
        if within and within_heading:
            self.feedback_message = ""
            return Status.SUCCESS
        self.feedback_message = (f"out of path tracking bounds: position error {error:.2f} m, "
                                 f"heading error {heading:.2f} rad")
        return Status.FAILURE


