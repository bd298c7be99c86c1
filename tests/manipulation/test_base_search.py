"""The candidate search PlanBaseForGrasp and PlanBaseForPlace share (search_bases): its checks
in their order, the pluggable extra check, its budgets and the reason it gives."""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from bt_manip.manipulation.base_search import (
    REJECTIONS,
    Candidate,
    ExtraCheck,
    PlacementOptions,
    SearchSite,
    search_bases,
)
from bt_manip.manipulation.place_search import PLACE_REJECTIONS

RES = 0.05
ORIGIN = np.array([-2.0, -2.0])


class PathsTo:
    """A navigator whose grid planner finds a path to every goal but those at ``blocked_y``."""

    def __init__(self, blocked_y: float) -> None:
        self.blocked_y = blocked_y
        self.goals: list[tuple[float, float, float]] = []

    def plan_to(self, start: Any, goal: tuple[float, float, float]) -> SimpleNamespace:
        self.goals.append(goal)
        return SimpleNamespace(ok=not math.isclose(goal[1], self.blocked_y))


def site(nav: PathsTo) -> SearchSite:
    """A 4 m x 4 m open floor (1 m clearance everywhere) with one occupied cell at (0.5, 0),
    a 0.1 m square robot standing at (-1, -1) with its arm over its frame."""
    clear = np.ones((80, 80))
    occupied = np.zeros((80, 80), dtype=bool)
    occupied[40, 50] = True  # the cell of (0.5, 0.0)
    pts = np.array([[-0.05, -0.05], [0.05, -0.05], [0.05, 0.05], [-0.05, 0.05]])
    return SearchSite(nav, clear, occupied, ORIGIN, RES, pts, 0.1, (-1.0, -1.0, 0.0), np.eye(4))


def at(x: float, y: float) -> Candidate:
    return Candidate(x, y, 0.0, 0.3, 0.0, 0.0)


def reach_unless_y(fails_y: float) -> Any:
    """An IK check that reaches every candidate but those at ``fails_y``; it records the arm
    base poses it was asked about."""
    asked: list[np.ndarray] = []

    def reach(cand: Candidate, arm_world: np.ndarray) -> tuple[Any, Any, str]:
        asked.append(arm_world[:2, 3].copy())
        if math.isclose(cand.y, fails_y):
            return None, None, "pre-grasp point: too far"
        frame = np.eye(4)
        frame[:2, 3] = (1.0, 0.0)
        return np.array([0.1, 0.2]), frame, ""

    reach.asked = asked  # type: ignore[attr-defined]
    return reach


OPTIONS = PlacementOptions(staging=0.2)
LOAD = ExtraCheck(
    "load collides",
    at_pose=lambda cand: not math.isclose(cand.y, -1.0),
    lines_up=lambda cand, staged: not math.isclose(cand.y, -0.5),
)


def test_each_check_turns_down_its_pose_in_order_and_the_first_that_passes_is_taken() -> None:
    nav = PathsTo(blocked_y=1.0)
    reach = reach_unless_y(0.5)
    candidates = [
        at(3.0, 0.0),  # off the grid: collides
        at(0.0, -1.0),  # the extra check turns it down
        at(0.0, -0.5),  # the extra check says it cannot line up
        at(0.0, 0.0),  # the arm's way to (1, 0) crosses the occupied cell
        at(0.0, 0.5),  # out of reach
        at(0.0, 1.0),  # no path to its staging pose
        at(0.0, 1.5),  # passes
        at(0.0, -1.5),  # never looked at
    ]
    found = search_bases(candidates, site(nav), OPTIONS, np.array([1.0, 0.0]), reach,
                         PLACE_REJECTIONS, LOAD)
    assert found.ok, found.reason
    assert found.base_pose == (0.0, 1.5, 0.0)
    assert found.staging_pose == pytest.approx((-0.2, 1.5, 0.0))
    assert found.q_grasp is not None and found.q_grasp.tolist() == [0.1, 0.2]
    assert found.grasp is not None and found.grasp[:2, 3].tolist() == [1.0, 0.0]
    assert found.counts == {
        "sampled": 8, "collide": 1, "load collides": 1, "no room to line up": 1,
        "reach over": 1, "IK": 1, "no path": 1,
    }
    # IK was asked about the three poses past the grid checks, with the arm where the base is
    assert [a.tolist() for a in reach.asked] == [[0.0, 0.5], [0.0, 1.0], [0.0, 1.5]]
    # paths were planned from where the robot stands to the staging poses
    assert [g[:2] for g in nav.goals] == [pytest.approx((-0.2, 1.0)), pytest.approx((-0.2, 1.5))]


def test_the_reason_counts_each_check_and_the_spent_budget() -> None:
    nav = PathsTo(blocked_y=1.0)
    candidates = [at(3.0, 0.0), at(0.0, 0.5), at(0.0, 1.0), at(0.0, 1.5)]
    options = PlacementOptions(staging=0.2, max_path_checks=1)
    found = search_bases(candidates, site(nav), options, np.array([1.0, 0.0]),
                         reach_unless_y(0.5), REJECTIONS)
    assert not found.ok
    assert found.base_pose is None
    # (0, 1.5) would pass, but the one path check is spent
    assert found.reason == (
        "4 poses sampled; 1 too close to an obstacle; 1 out of the arm's reach; "
        "1 with no path to them; check budget spent; last IK failure: pre-grasp point: too far"
    )
