"""Nav2's nodes that work on a path already planned: TruncatePath and PathLongerOnApproach;
and InitialPoseReceived, which reads the blackboard."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.bt.node import BtNode, ConditionNode, DecoratorNode, PortError, SyncActionNode
from bt_manip.bt.ports import NON_NEGATIVE, POSITIVE, Port
from bt_manip.bt.registry import registry
from bt_manip.bt.status import NodeStatus
from bt_manip.nav2.path import Nav2Path

IDLE = NodeStatus.IDLE
RUNNING = NodeStatus.RUNNING
SUCCESS = NodeStatus.SUCCESS
FAILURE = NodeStatus.FAILURE


def _length(poses: np.ndarray) -> float:
    d = np.diff(poses[:, :2], axis=0)
    return float(np.sum(np.hypot(d[:, 0], d[:, 1]))) if len(d) else 0.0


def truncated(path: Nav2Path, distance: float) -> Nav2Path:
    """``path`` without its poses closer than ``distance`` to its last pose; the new last pose
    faces the old one. A path entirely within ``distance`` keeps its first pose only."""
    poses = path.poses
    goal = poses[-1]
    far = np.hypot(poses[:, 0] - goal[0], poses[:, 1] - goal[1]) >= distance
    keep = int(np.flatnonzero(far)[-1]) + 1 if far.any() else 1
    out = poses[:keep].copy()
    out[-1, 2] = math.atan2(goal[1] - out[-1, 1], goal[0] - out[-1, 0])
    return Nav2Path(out, path.frame_id, path.planner_id, _length(out))


@registry.register
class TruncatePath(SyncActionNode):
    """Writes ``input_path`` without its end within ``distance`` of the goal to
    ``output_path``, the new last pose facing the goal (to stop short of it). SUCCESS; FAILURE
    when ``input_path`` is not a path."""

    INPUT_PORTS: dict[str, PortInformation] = {
        "input_path": PortInformation(Nav2Path, True, "Original path"),
        "distance": Port(float, False, "Distance to truncate from the goal (m)", 1.0,
                         NON_NEGATIVE),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {
        "output_path": PortInformation(Nav2Path, False, "Truncated path"),
    }

    def update(self) -> Status:
        try:
            path = self.get_input("input_path", None)
        except PortError as exc:
            path, self.feedback_message = None, str(exc)
        if not isinstance(path, Nav2Path) or len(path) == 0:
            self.feedback_message = self.feedback_message or "no path to truncate"
            return Status.FAILURE
        self.set_output("output_path", truncated(path, float(self.get_input("distance"))))
        return Status.SUCCESS


@registry.register
class PathLongerOnApproach(DecoratorNode):
    """Ticks its child when, near the goal, a new path is much longer than the previous one
    (something now blocks the way, so the robot may rather wait than go round).

    It compares ``path`` with the path it saw at its last tick. The child is ticked when the
    path has changed, the previous path was shorter than ``prox_len`` (the robot was near the
    goal) and the new one is longer than ``length_factor`` times it; not on the first tick
    after a reset. Then it returns the child's status (the new path becomes the one to compare
    with once the child finished). Otherwise it remembers the new path and returns SUCCESS.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "path": PortInformation(Nav2Path, True, "Planned Path"),
        "prox_len": Port(float, False, "Proximity length (m) for the path to be longer on "
                         "approach", 3.0, POSITIVE),
        "length_factor": Port(float, False, "Length multiplication factor to check if the "
                              "path is significantly longer", 2.0, POSITIVE),
    }

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self.old: Nav2Path | None = None
        self.first_time = True

    def tick_node(self) -> NodeStatus:
        new = self.get_input("path", None)
        if self.bt_status in (IDLE, NodeStatus.SKIPPED):
            self.first_time = True
        self.bt_status = RUNNING
        self.status = RUNNING.to_py_trees()
        old = self.old
        longer = (
            isinstance(new, Nav2Path) and isinstance(old, Nav2Path) and new is not old
            and old.length < float(self.get_input("prox_len"))
            and new.length > float(self.get_input("length_factor")) * old.length
        )
        if (longer and not self.first_time) or self.child.bt_status is RUNNING:
            status = self.child.execute_tick()
            if status is not RUNNING:
                self.old = new
            return status
        self.old = new
        self.first_time = False
        return SUCCESS


@registry.register
class InitialPoseReceived(ConditionNode):
    """SUCCESS when the blackboard entry ``initial_pose_received`` is true (the robot knows
    where it is), FAILURE otherwise."""

    def update(self) -> Status:
        try:
            received = self.blackboard.get("initial_pose_received")
        except KeyError:
            received = False
        ok = received is True or str(received).lower() == "true"
        self.feedback_message = "" if ok else "no initial pose received"
        return Status.SUCCESS if ok else Status.FAILURE
