"""Nav2's ``nav2_msgs/WaypointStatus``: how far a through-poses navigation got with each of
its goals (RemovePassedGoals marks those it drops as passed)."""

from __future__ import annotations

import dataclasses
import enum
from dataclasses import dataclass
from typing import Any

Pose2D = tuple[float, float, float]


class WaypointState(enum.IntEnum):
    """``WaypointStatus.waypoint_status`` values."""

    PENDING = 0
    COMPLETED = 1
    SKIPPED = 2
    FAILED = 3


@dataclass(frozen=True)
class WaypointStatus:
    """The status of goal ``waypoint_index`` (at ``waypoint_pose``) of a navigation."""

    waypoint_index: int
    waypoint_pose: Pose2D
    waypoint_status: WaypointState = WaypointState.PENDING
    error_code: int = 0
    error_msg: str = ""


def pending_statuses(goals: list[Pose2D]) -> list[WaypointStatus]:
    """A PENDING status for each goal, indexed in order (what Nav2's navigator writes to the
    blackboard when a through-poses navigation starts)."""
    return [WaypointStatus(k, tuple(g)) for k, g in enumerate(goals)]  # type: ignore[arg-type]


def statuses_of(value: Any) -> list[WaypointStatus] | None:
    """The statuses a port holds, or None when it holds none."""
    if isinstance(value, (list, tuple)) and all(isinstance(v, WaypointStatus) for v in value):
        return list(value)
    return None


def mark_completed(statuses: list[WaypointStatus], goal: Pose2D) -> list[WaypointStatus]:
    """``statuses`` with the first PENDING one at ``goal`` marked COMPLETED."""
    out = list(statuses)
    for k, status in enumerate(out):
        if (status.waypoint_status is WaypointState.PENDING
                and tuple(status.waypoint_pose) == tuple(goal)):
            out[k] = dataclasses.replace(status, waypoint_status=WaypointState.COMPLETED)
            break
    return out
