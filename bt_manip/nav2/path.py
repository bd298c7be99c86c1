"""Poses and paths as Nav2's trees pass them on the blackboard.

A goal is a :class:`Pose2D` tuple ``(x, y, yaw)`` in the world frame; trees may also give it as
text (``x;y;yaw`` or a named pose of the world, as ``--bb goal=...`` does). A path is a
:class:`Nav2Path`: the planned poses of the base frame, the last one being the goal.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bt_manip.behaviours.base import ActionFailed
from bt_manip.behaviours.navigate import parse_goal

Pose2D = tuple[float, float, float]


@dataclass(frozen=True, eq=False)
class Nav2Path:
    """Poses (n, 3: x, y, yaw) of the base frame along a planned path, in ``frame_id``.

    Headings along the way point along the path; the last pose is the goal itself. Two paths
    are the same path only if they are the same object (a new plan is a new path).
    """

    poses: np.ndarray
    frame_id: str = "map"
    planner_id: str = ""
    length: float = field(default=0.0)

    @property
    def goal(self) -> Pose2D:
        x, y, yaw = self.poses[-1]
        return (float(x), float(y), float(yaw))

    def shifted(self, ahead: float) -> np.ndarray:
        """The (n, 2) points ``ahead`` metres in front of each pose (the base's turning point
        when ``ahead`` is its pivot offset)."""
        p = self.poses
        x = p[:, 0] + ahead * np.cos(p[:, 2])
        return np.column_stack([x, p[:, 1] + ahead * np.sin(p[:, 2])])

    def __len__(self) -> int:
        return len(self.poses)

    def __str__(self) -> str:
        if len(self.poses) == 0:
            return "empty path"
        return f"path of {len(self.poses)} poses, {self.length:.2f} m, to {self.goal_text()}"

    def goal_text(self) -> str:
        x, y, yaw = self.goal
        return f"{x:.3f};{y:.3f};{yaw:.3f}"


def path_from_points(points: np.ndarray, goal: Pose2D, ahead: float) -> Nav2Path:
    """The base-frame path whose points ``ahead`` metres in front lie on ``points`` (n, 2),
    ending on ``goal``; headings follow the path."""
    pts = np.asarray(points, dtype=float)
    d = np.diff(pts, axis=0)
    headings = np.arctan2(d[:, 1], d[:, 0]) if len(d) else np.zeros(0)
    yaw = np.concatenate([headings, [goal[2]]]) if len(headings) else np.array([goal[2]])
    base = np.column_stack([pts[:, 0] - ahead * np.cos(yaw), pts[:, 1] - ahead * np.sin(yaw), yaw])
    base[-1] = goal
    length = float(np.sum(np.hypot(d[:, 0], d[:, 1]))) if len(d) else 0.0
    return Nav2Path(base, length=length)


def goal_pose(world: Any, value: Any) -> Pose2D:
    """A goal read from a port: a pose tuple, ``x;y;yaw`` or a named pose of the world."""
    if isinstance(value, Nav2Path):
        return value.goal
    if isinstance(value, (tuple, list, np.ndarray)) and len(value) == 3:
        x, y, yaw = (float(v) for v in value)
        if all(math.isfinite(v) for v in (x, y, yaw)):
            return (x, y, yaw)
        raise ActionFailed(f"goal {value!r} is not three finite numbers")
    if isinstance(value, str):
        return parse_goal(world, value.strip())
    raise ActionFailed(f"goal {value!r} is neither x;y;yaw nor a named pose")
