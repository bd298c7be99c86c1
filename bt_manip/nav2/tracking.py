"""How closely the base follows its path: the :class:`TrackingFeedback` that FollowPath
writes to ``tracking_feedback`` each tick, as Nav2's controller server publishes it."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

Pose2D = tuple[float, float, float]


@dataclass(frozen=True)
class TrackingFeedback:
    """Nav2's ``nav2_msgs/TrackingFeedback``: where the robot is relative to its path.

    ``position_tracking_error`` is the signed distance (m) from the path: positive when the
    robot is to the left of it, negative to the right. ``heading_tracking_error`` (rad) is the
    robot's heading minus the path's direction there.
    """

    current_path_index: int = 0
    position_tracking_error: float = 0.0
    heading_tracking_error: float = 0.0
    distance_to_goal: float = 0.0
    remaining_path_length: float = 0.0
    robot_pose: Pose2D = (0.0, 0.0, 0.0)


def tracking_feedback(points: np.ndarray, goal: Pose2D, here: tuple[float, float],
                      pose: Pose2D) -> TrackingFeedback:
    """The feedback for a robot whose tracked point is ``here`` and whose base is at ``pose``,
    following the polyline ``points`` (n, 2) to ``goal``."""
    pts = np.asarray(points, dtype=float)
    p = np.asarray(here, dtype=float)
    to_goal = math.hypot(goal[0] - pose[0], goal[1] - pose[1])
    if len(pts) < 2:
        return TrackingFeedback(0, 0.0, 0.0, to_goal, 0.0, pose)
    a, b = pts[:-1], pts[1:]
    d = b - a
    seg_len2 = np.maximum(np.einsum("ij,ij->i", d, d), 1e-12)
    t = np.clip(np.einsum("ij,ij->i", p - a, d) / seg_len2, 0.0, 1.0)
    proj = a + d * t[:, None]
    dist = np.hypot(*(proj - p).T)
    k = int(np.argmin(dist))
    seg = d[k]
    cross = float(seg[0] * (p[1] - a[k, 1]) - seg[1] * (p[0] - a[k, 0]))
    error = math.copysign(float(dist[k]), cross) if dist[k] > 0 else 0.0
    heading = math.atan2(float(seg[1]), float(seg[0]))
    heading_error = math.remainder(pose[2] - heading, math.tau)
    lengths = np.sqrt(seg_len2)
    remaining = float(lengths[k] * (1.0 - t[k]) + np.sum(lengths[k + 1:]))
    return TrackingFeedback(k, error, heading_error, to_goal, remaining, pose)
