"""Nav2's result codes of its action servers (the numbers its trees compare against)."""

from __future__ import annotations

import enum


class PlannerError(enum.IntEnum):
    """ComputePathToPose / ComputePathThroughPoses result codes."""

    NONE = 0
    UNKNOWN = 200
    INVALID_PLANNER = 201
    TF_ERROR = 202
    START_OUTSIDE_MAP = 203
    GOAL_OUTSIDE_MAP = 204
    START_OCCUPIED = 205
    GOAL_OCCUPIED = 206
    TIMEOUT = 207
    NO_VALID_PATH = 208


class ControllerError(enum.IntEnum):
    """FollowPath result codes."""

    NONE = 0
    UNKNOWN = 100
    INVALID_CONTROLLER = 101
    TF_ERROR = 102
    INVALID_PATH = 103
    PATIENCE_EXCEEDED = 104
    FAILED_TO_MAKE_PROGRESS = 105
    NO_VALID_CONTROL = 106


class BehaviorError(enum.IntEnum):
    """Spin, BackUp, DriveOnHeading and Wait result codes."""

    NONE = 0
    UNKNOWN = 700
    TIMEOUT = 701
    TF_ERROR = 702
    COLLISION_AHEAD = 703


class SmootherError(enum.IntEnum):
    """SmoothPath result codes."""

    NONE = 0
    UNKNOWN = 500
    INVALID_SMOOTHER = 501
    TIMEOUT = 502
    SMOOTHED_PATH_IN_COLLISION = 503
    FAILED_TO_SMOOTH_PATH = 504
    INVALID_PATH = 505


PLANNER_RECOVERABLE = frozenset(
    {PlannerError.UNKNOWN, PlannerError.NO_VALID_PATH, PlannerError.TIMEOUT}
)
"""Planner failures that clearing the costmap may cure (WouldAPlannerRecoveryHelp)."""

CONTROLLER_RECOVERABLE = frozenset(
    {
        ControllerError.UNKNOWN,
        ControllerError.PATIENCE_EXCEEDED,
        ControllerError.FAILED_TO_MAKE_PROGRESS,
        ControllerError.NO_VALID_CONTROL,
    }
)
"""Controller failures that a recovery may cure (WouldAControllerRecoveryHelp)."""

SMOOTHER_RECOVERABLE = frozenset(
    {
        SmootherError.UNKNOWN,
        SmootherError.TIMEOUT,
        SmootherError.SMOOTHED_PATH_IN_COLLISION,
        SmootherError.FAILED_TO_SMOOTH_PATH,
    }
)
"""Smoother failures that a recovery may cure (WouldASmootherRecoveryHelp)."""
