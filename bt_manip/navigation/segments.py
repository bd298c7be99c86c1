"""Following a pose plan: runs of forward, backward and on-the-spot moves, one after another.

A :class:`~bt_manip.navigation.lattice.PosePlan` is cut into runs of the same kind of move.
Each run is handed to a :class:`~bt_manip.navigation.controller.PathFollower`: forward and
backward runs follow the pivot point's path through the run's poses and end on the run's last
pose (heading included, within the loose tolerances), a turn on the spot turns to the run's
last heading, and a last run brings the base exactly onto the goal with the follower's
tolerances. Intermediate runs end within ``waypoint_tolerance`` (and 0.2 rad) without
settling. All runs share one :class:`~bt_manip.navigation.pivot.PivotEstimate`: the point
the base really turns about is learnt while it turns (a carried load moves it).

An intermediate run that ends off its last pose (by more than 1.5 ``waypoint_tolerance``, where
the follower would turn toward the pose and drive there: a manoeuvre planned against nothing,
which with a long load sweeps it round) is not finished that way when a ``replan`` is given:
the rest of the way is planned again from where the base stands (at most ``max_replans``
times), and the new plan's runs follow.

:meth:`SegmentFollower.update` has the same contract as :meth:`PathFollower.update`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from bt_manip.navigation.controller import (
    FollowerOptions,
    FollowState,
    FollowStatus,
    PathFollower,
    Pose2D,
)
from bt_manip.navigation.lattice import BACKWARD, TURN, PosePlan
from bt_manip.navigation.pivot import PivotEstimate
from bt_manip.navigation.smoothing import densify


def _runs(moves: np.ndarray) -> list[tuple[int, int, int]]:
    """(kind, first pose index, last pose index) of each run of equal moves."""
    out: list[tuple[int, int, int]] = []
    start = 0
    for i in range(1, len(moves) + 1):
        if i == len(moves) or moves[i] != moves[start]:
            out.append((int(moves[start]), start, i))
            start = i
    return out


class SegmentFollower:
    """Drives through the runs of ``plan`` and ends on ``goal`` (x, y, yaw)."""

    def __init__(
        self,
        plan: PosePlan,
        goal: Pose2D,
        options: FollowerOptions | None = None,
        waypoint_tolerance: float = 0.15,
        pivot_estimate: PivotEstimate | None = None,
        replan: Callable[[Pose2D], PosePlan] | None = None,
        max_replans: int = 3,
    ) -> None:
        options = options or FollowerOptions()
        if not plan.ok or plan.poses is None or plan.moves is None:
            raise ValueError("a pose plan that found a way is needed")
        self.options = options
        self.goal = goal
        self.pivot_estimate = (
            pivot_estimate if pivot_estimate is not None else PivotEstimate(options.pivot)
        )
        """Where the base turns about, learnt while it turns and shared by the runs."""
        self._loose = dataclasses.replace(
            options, xy_tolerance=waypoint_tolerance, yaw_tolerance=0.2, settle_time=0.0
        )
        self.replan = replan
        self.max_replans = max_replans
        self.replans = 0
        """How many times the rest of the way was planned again."""
        self._queue: list[tuple[int, np.ndarray]] = []
        self._current: PathFollower | None = None
        self._final = False
        self._done: FollowStatus | None = None
        self.runs = 0
        self._take(plan)

    def _take(self, plan: PosePlan) -> None:
        """Queue the runs of ``plan`` (an ok plan) in place of those left."""
        assert plan.poses is not None and plan.moves is not None
        poses = plan.poses
        self._queue = [(kind, poses[a : b + 1]) for kind, a, b in _runs(plan.moves)]
        self.runs = len(self._queue)

    @property
    def pivot(self) -> float:
        """The point (m ahead of the base frame) whose paths the runs track while driving."""
        return self.options.pivot

    def _pivot_path(self, poses: np.ndarray) -> np.ndarray:
        p = self.pivot
        pts = np.column_stack(
            [poses[:, 0] + p * np.cos(poses[:, 2]), poses[:, 1] + p * np.sin(poses[:, 2])]
        )
        return densify(pts, 0.05)

    def _next(self, pose: Pose2D) -> PathFollower:
        if not self._queue:
            self._final = True
            x, y, yaw = pose
            here = (x + self.pivot * math.cos(yaw), y + self.pivot * math.sin(yaw))
            gx, gy, gyaw = self.goal
            there = (gx + self.pivot * math.cos(gyaw), gy + self.pivot * math.sin(gyaw))
            return PathFollower(
                densify(np.array([here, there]), 0.05), self.goal, self.options,
                pivot_estimate=self.pivot_estimate,
            )
        kind, poses = self._queue.pop(0)
        end = poses[-1]
        if kind == TURN:
            turn_path = self._pivot_path(poses[-1:])
            return PathFollower(
                turn_path, (end[0], end[1], end[2]), self._loose,
                pivot_estimate=self.pivot_estimate,
            )
        # the run ends on its last pose, heading included: without a heading the follower
        # would steer the pivot to a point ahead of the goal along the heading it has now,
        # which moves as the base turns, and a base a little off its run could circle it
        return PathFollower(
            self._pivot_path(poses), (end[0], end[1], end[2]), self._loose,
            reverse=kind == BACKWARD,
            pivot_estimate=self.pivot_estimate,
        )

    def update(self, pose: Pose2D, now: float) -> FollowStatus:
        """One tick; see :meth:`PathFollower.update`."""
        if self._done is not None:
            return self._done
        left = self.runs + 2  # each pass ends a run, or plans again (and adds its runs)
        while left > 0:
            left -= 1
            if self._current is None:
                self._current = self._next(pose)
            status = self._current.update(pose, now)
            if status.phase == "approach" and not self._final and self._plan_again(pose):
                self._current = None  # follow the new plan's first run in the same tick
                left += self.runs + 1
                continue
            if status.state is FollowState.RUNNING:
                return status
            if status.state is FollowState.FAILED or self._final:
                self._done = status
                return status
            self._current = None  # this run is done: start the next one in the same tick
        self._done = FollowStatus(FollowState.FAILED, "pose plan could not be followed", (0, 0))
        return self._done

    def _plan_again(self, pose: Pose2D) -> bool:
        """Plan the rest of the way from ``pose``; whether a new plan was taken."""
        if self.replan is None or self.replans >= self.max_replans:
            return False
        self.replans += 1
        plan = self.replan(pose)
        if not plan.ok or plan.moves is None or len(plan.moves) == 0:
            return False
        self._take(plan)
        return True
