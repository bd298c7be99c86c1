"""Following a pose plan run by run, and planning the rest again when a run ends off its pose."""

from __future__ import annotations

import math

from test_controller import DT, step
from test_lattice import room

from bt_manip.navigation.controller import FollowerOptions, FollowState, wrap
from bt_manip.navigation.costmap import clearance
from bt_manip.navigation.footprint import PlanarFootprint
from bt_manip.navigation.lattice import PosePlan, plan_poses
from bt_manip.navigation.segments import SegmentFollower


def test_a_run_that_ends_off_its_pose_plans_the_rest_again_instead_of_turning_to_it() -> None:
    """The base stands 0.3 m beside where its plan starts (it slid while turning on the spot
    with a load): the first run (a turn on the spot) ends far from its pose; the follower
    plans again from there and follows that, instead of turning toward the missed pose and
    driving to it, a manoeuvre checked against nothing."""
    grid = room()
    clear = clearance(grid)
    fp = PlanarFootprint.rectangle(0.9, 0.6, label="base")
    goal = (6.0, 2.0, 0.0)
    plan = plan_poses(grid, clear, fp, (2.0, 1.7, math.pi / 2), goal, 0.13)
    assert plan.ok and plan.moves is not None
    starts: list[tuple[float, float, float]] = []

    def replan(pose: tuple[float, float, float]) -> PosePlan:
        starts.append(pose)
        return plan_poses(grid, clear, fp, pose, goal, 0.13)

    options = FollowerOptions(pivot=0.13, xy_tolerance=0.1, yaw_tolerance=0.1)
    follower = SegmentFollower(plan, goal, options, replan=replan)
    pose, t, turned = (2.0, 2.0, math.pi / 2), 0.0, 0.0
    status = follower.update(pose, t)
    while status.state is FollowState.RUNNING and t < 60.0:
        after = step(pose, status.cmd, 0.13)
        turned += abs(wrap(after[2] - pose[2]))
        pose, t = after, t + DT
        status = follower.update(pose, t)
    assert status.state is FollowState.SUCCEEDED, status.reason
    assert math.hypot(pose[0] - goal[0], pose[1] - goal[1]) <= 0.1
    assert abs(wrap(pose[2] - goal[2])) <= 0.1
    assert follower.replans == 1
    assert math.hypot(starts[0][0] - 2.0, starts[0][1] - 2.0) < 0.05  # planned from where it was
    assert turned < 0.75 * math.pi, turned  # about the quarter turn the way needs
