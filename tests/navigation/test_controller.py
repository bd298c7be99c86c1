"""Path follower on a kinematic skid-steer model that turns about a pivot ahead of its frame."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_manip.navigation.controller import (
    FollowerOptions,
    FollowState,
    FollowStatus,
    PathFollower,
    wrap,
)
from bt_manip.navigation.smoothing import densify

DT = 0.05  # tick period (20 Hz)


Pose = tuple[float, float, float]


def step(pose: Pose, cmd: tuple[float, float], pivot: float) -> Pose:
    """Move for one tick: the pivot point drives at v, the heading turns at w about it."""
    x, y, th = pose
    v, w = cmd
    for _ in range(10):
        h = DT / 10
        px, py = x + pivot * math.cos(th), y + pivot * math.sin(th)
        px += v * h * math.cos(th)
        py += v * h * math.sin(th)
        th += w * h
        x, y = px - pivot * math.cos(th), py - pivot * math.sin(th)
    return x, y, th


def run(
    follower: PathFollower, pose: Pose, pivot: float, limit: float = 60.0
) -> tuple[FollowStatus, Pose, float, list[tuple[float, float]]]:
    t = 0.0
    cmds = []
    while t < limit:
        status = follower.update(pose, t)
        cmds.append(status.cmd)
        if status.state is not FollowState.RUNNING:
            return status, pose, t, cmds
        pose = step(pose, status.cmd, pivot)
        t += DT
    raise AssertionError("follower did not finish")


@pytest.mark.parametrize("pivot", [0.0, 0.13])
def test_follows_an_l_path_and_ends_on_the_goal_pose(pivot: float) -> None:
    corners = np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 2.0]])
    goal = (3.0, 2.0, math.pi)  # arrives heading north, must end facing west
    follower = PathFollower(densify(corners), goal, FollowerOptions(pivot=pivot))
    # with pivot 0 the planned path is the base frame's own path
    status, pose, t, cmds = run(follower, (0.0, 0.0, 0.0), pivot)
    assert status.state is FollowState.SUCCEEDED, status.reason
    assert math.hypot(pose[0] - 3.0, pose[1] - 2.0) <= 0.10 + 0.13 * (pivot > 0)
    assert abs(wrap(pose[2] - math.pi)) <= 0.10
    opts = follower.options
    v = np.array(cmds)
    assert np.abs(v[:, 0]).max() <= opts.max_speed + 1e-9
    assert np.abs(np.diff(v[:, 0])).max() <= opts.max_accel * DT + 1e-9
    assert np.abs(np.diff(v[:, 1])).max() <= opts.max_yaw_accel * DT + 1e-9
    # 5 m of path at 0.8 m/s plus the turns: well within 1.5 x + 5 s
    assert t < 1.5 * 5.0 / opts.max_speed + 5.0


def test_pivot_offset_keeps_the_base_on_the_goal_while_turning() -> None:
    pivot = 0.13
    goal = (2.0, 0.0, math.pi / 2)
    # the navigator plans the pivot's path: from the pivot now to where it must end
    path = densify(np.array([[pivot, 0.0], [2.0, pivot]]))
    follower = PathFollower(path, goal, FollowerOptions(pivot=pivot))
    status, pose, _, _ = run(follower, (0.0, 0.0, 0.0), pivot)
    assert status.state is FollowState.SUCCEEDED
    assert math.hypot(pose[0] - 2.0, pose[1]) <= 0.10
    assert abs(wrap(pose[2] - math.pi / 2)) <= 0.10


def test_reverse_follows_backwards_without_turning_round() -> None:
    path = densify(np.array([[0.0, 0.0], [-1.5, 0.0]]))
    follower = PathFollower(path, (-1.5, 0.0), FollowerOptions(), reverse=True)
    status, pose, _, cmds = run(follower, (0.0, 0.0, 0.0), 0.0)
    assert status.state is FollowState.SUCCEEDED
    assert pose[0] == pytest.approx(-1.5, abs=0.1)
    assert abs(wrap(pose[2])) < 0.2  # still facing +x
    assert min(c[0] for c in cmds) < -0.3  # it did back up


def test_stuck_base_fails_with_reason() -> None:
    follower = PathFollower(densify(np.array([[0.0, 0.0], [2.0, 0.0]])), (2.0, 0.0, 0.0))
    t = 0.0
    status = follower.update((0.0, 0.0, 0.0), t)
    while status.state is FollowState.RUNNING and t < 20:
        t += DT
        status = follower.update((0.0, 0.0, 0.0), t)  # the base never moves
    assert status.state is FollowState.FAILED
    assert status.reason.startswith("stuck") and "2.00 m from the goal" in status.reason
    assert t == pytest.approx(follower.options.stuck_time, abs=0.2)
    assert status.cmd == (0.0, 0.0)


def test_blocked_path_triggers_replanning() -> None:
    straight = densify(np.array([[0.0, 0.0], [3.0, 0.0]]))
    detour = densify(np.array([[0.0, 0.0], [1.5, 1.0], [3.0, 0.0]]))
    asked: list[tuple[float, float, float]] = []
    blocked = {"now": False}

    def path_blocked(ahead: np.ndarray) -> bool:
        # an object appears on the straight path at x = 2 after the first second
        return blocked["now"] and bool(np.any(np.hypot(ahead[:, 0] - 2.0, ahead[:, 1]) < 0.1))

    def replan(pose: tuple[float, float, float]) -> np.ndarray:
        asked.append(pose)
        return np.vstack([[pose[0], pose[1]], detour[detour[:, 0] > pose[0] + 0.3]])

    follower = PathFollower(straight, (3.0, 0.0, 0.0), path_blocked=path_blocked, replan=replan)
    pose = (0.0, 0.0, 0.0)
    t = 0.0
    while t < 40:
        blocked["now"] = t > 1.0
        status = follower.update(pose, t)
        if status.state is not FollowState.RUNNING:
            break
        pose = step(pose, status.cmd, 0.0)
        t += DT
    assert status.state is FollowState.SUCCEEDED
    assert follower.replans == 1 and len(asked) == 1
    assert 0.2 < asked[0][0] < 2.0  # replanned from where it was when the block appeared


def test_no_new_path_fails_with_the_planners_reason() -> None:
    follower = PathFollower(
        densify(np.array([[0.0, 0.0], [3.0, 0.0]])),
        (3.0, 0.0, 0.0),
        path_blocked=lambda ahead: True,
        replan=lambda pose: "goal is not connected",
    )
    status = follower.update((0.0, 0.0, 0.0), 0.0)
    assert status.state is FollowState.FAILED
    assert status.reason == "path blocked and no new path: goal is not connected"


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_a_goal_a_few_centimetres_to_the_side_is_reached_without_swinging_round(
    side: float,
) -> None:
    """The path ends 12 cm beside the goal (a tight pregrasp pose next to the object it is
    for): the base backs up along its heading and drives in at a small angle, instead of
    turning on the spot by up to 90 deg toward the goal and back, which swept the arm
    into the object."""
    pivot = 0.2
    goal = (0.0, side * 0.12, 0.3 * side)
    here = (pivot, 0.0)
    there = (goal[0] + pivot * math.cos(goal[2]), goal[1] + pivot * math.sin(goal[2]))
    path = densify(np.array([here, here]))  # the path ended where the base stands
    options = FollowerOptions(pivot=pivot, xy_tolerance=0.03, yaw_tolerance=0.03)
    follower = PathFollower(path, goal, options)
    pose: Pose = (0.0, 0.0, 0.0)
    headings = [0.0]
    t = 0.0
    status = follower.update(pose, t)
    while status.state is FollowState.RUNNING and t < 30.0:
        pose = step(pose, status.cmd, pivot)
        headings.append(pose[2])
        t += DT
        status = follower.update(pose, t)
    assert status.state is FollowState.SUCCEEDED, status.reason
    assert math.hypot(pose[0] - goal[0], pose[1] - goal[1]) <= 0.03
    assert abs(wrap(pose[2] - goal[2])) <= 0.03
    assert math.hypot(there[0] - here[0], there[1] - here[1]) < options.sidestep_distance
    # never turned far beyond the start and goal headings (without backing up first it turned
    # by 2 rad the wrong way round)
    lo, hi = sorted((0.0, goal[2]))
    assert min(headings) >= lo - 0.8 and max(headings) <= hi + 0.8
