"""Where to park a mobile manipulator so that its arm can place what it holds (PlanBaseForPlace).

Like :mod:`bt_manip.manipulation.base_search` (PlanBaseForGrasp), but for the object already
in the hand and its target pose: the grasp frame the arm must reach is the one that puts the
object, held as it is now, at the target (:func:`bt_manip.manipulation.placing.place_frames`,
both turns of the target). Base poses are tried in this order:

1. the poses from which the object, held exactly as now, would already be over its target (the
   robot stands to the target as it stands to the object now; the arm then only goes down);
2. the rings of :func:`~bt_manip.manipulation.base_search.sample` around the target's grasp
   point, those that turn the object least relative to the robot first.

A pose is kept when the robot's footprint as the navigator plans with it (the carried object
included, where it is in the hand now) is ``clearance`` from every obstacle, there is room to
line up behind it and drive straight in, the arm's way to the target crosses no obstacle, the
arm's IK reaches the pre-place point (``approach`` m above the target) from the arm's posture
now and every point of the straight line down, and the navigator finds a path to the staging
pose. The work is bounded as in PlanBaseForGrasp.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from bt_manip.manipulation.base_search import (
    REJECTIONS,
    Candidate,
    ExtraCheck,
    Placement,
    PlacementOptions,
    SearchSite,
    footprint_free,
    planar,
    sample,
    search_bases,
    staging_free,
)
from bt_manip.manipulation.cartesian import STEP, arm_ik
from bt_manip.manipulation.grasps import GraspError, box_size
from bt_manip.manipulation.perception import true_pose
from bt_manip.manipulation.placing import Target, lifted, place_frames, yaw_of_matrix
from bt_manip.navigation.lattice import LatticeOptions, outline_samples, pose_free
from bt_manip.run.context import RobotServices

STANDOFFS = (0.12, 0.16, 0.2)
"""How far (m) the poses of step 1 stand back from where the object would be over its target:
the load must stay clear of the wall it is set against until the arm moves it there."""
TURNS = (0.0, -0.15, 0.15, -0.3, 0.3)
"""Turns (rad) of the poses of step 1 about the target's grasp point."""
LOAD_CLEARANCE = 0.1
"""Clearance (m) of the carried object, where it is in the hand now, from every obstacle (the
navigator asks 5 cm and half a grid cell's diagonal)."""
PLACE_STAGING = 0.45
"""How far (m) behind the base pose the robot lines up: the last stretch is a straight drive
(DriveStraight), so it needs less room than a path follower would."""
TURN_WEIGHT = 0.2
"""Score per radian the object turns relative to the robot (rings), against the 0.1 m, 0.5 rad
units of :meth:`~bt_manip.manipulation.base_search.Candidate.score`."""


def wrap_half(angle: float) -> float:
    """``angle`` into (-pi/2, pi/2]: a box turned half a turn is the same box."""
    a = math.fmod(angle, math.pi)
    if a > math.pi / 2:
        a -= math.pi
    elif a <= -math.pi / 2:
        a += math.pi
    return a


def reach_down(
    ik: Any, arm_in_world: np.ndarray, goal: np.ndarray, approach: float, seed: np.ndarray
) -> tuple[np.ndarray | None, str]:
    """Joint values at ``goal`` when the arm (its base at ``arm_in_world``) reaches the point
    ``approach`` m above it and every waypoint of the straight line down; else None and IK's
    reason."""
    to_arm = np.linalg.inv(arm_in_world)
    pre = lifted(goal, approach)
    result = ik.full.solve(to_arm @ pre, q_seed=seed)
    if not result.success:
        return None, f"pre-place point: {result.reason}"
    q = result.q
    n = max(1, math.ceil(approach / STEP))
    for i in range(1, n + 1):
        result = ik.full.solve(to_arm @ lifted(goal, approach * (1 - i / n)), q_seed=q)
        if not result.success:
            return None, f"line down: {result.reason}"
        q = result.q
    return np.asarray(q, dtype=float), ""


def mirrored(
    target: Target, object_now: np.ndarray, base_now: np.ndarray, goal_xy: np.ndarray
) -> list[Candidate]:
    """Base poses from which the object, held as now, is over each turn of the target, each
    moved back by each of :data:`STANDOFFS` and turned about the target's grasp point by each
    of :data:`TURNS` (the arm turns the object back by as much)."""
    out = []
    x0, y0 = float(base_now[0, 3]), float(base_now[1, 3])
    gx, gy = float(goal_xy[0]), float(goal_xy[1])
    for back in STANDOFFS:
        for turn in TURNS:
            for flip in (False, True):
                base = target.matrix(flip) @ np.linalg.inv(object_now) @ base_now
                yaw = yaw_of_matrix(base)
                x = float(base[0, 3]) - back * math.cos(yaw)
                y = float(base[1, 3]) - back * math.sin(yaw)
                c, s = math.cos(turn), math.sin(turn)
                x, y = gx + c * (x - gx) - s * (y - gy), gy + s * (x - gx) + c * (y - gy)
                out.append(Candidate(x, y, yaw + turn, 0.0, turn, math.hypot(x - x0, y - y0)))
    return out


def load_samples(size: tuple[float, float, float], object_in_base: np.ndarray) -> np.ndarray:
    """Points (x, y; robot frame) every 5 cm round the horizontal outline of the held box."""
    hx, hy = size[0] / 2, size[1] / 2
    corners = [(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)]
    pts = []
    for (ax, ay), (bx, by) in zip(corners, corners[1:] + corners[:1], strict=True):
        n = max(1, math.ceil(math.hypot(bx - ax, by - ay) / 0.05))
        pts += [(ax + (bx - ax) * i / n, ay + (by - ay) * i / n) for i in range(n)]
    local = np.array([[x, y, 0.0, 1.0] for x, y in pts])
    out: np.ndarray = (object_in_base @ local.T).T[:, :2]
    return out


def carry_fits(nav: Any) -> Callable[[Candidate], bool] | None:
    """A test of whether the carrying robot fits at a candidate pose as the navigator checks a
    goal when it plans over poses with a load (its own layers and clearance), or None when the
    navigator has no load layers."""
    carry = nav.carry_layers()  # the layers hold the movable objects where they are now
    if carry is None:
        return None
    low_fp, high_fp, low, clear_low, clear_high = carry
    pts = outline_samples(low_fp, 0.05)
    pts_high = outline_samples(high_fp, 0.05)
    need = LatticeOptions().min_clearance + low.resolution / math.sqrt(2.0)

    def fits(cand: Candidate) -> bool:
        return pose_free(clear_low, clear_high, low.origin, low.resolution, pts, pts_high,
                         (cand.x, cand.y, cand.yaw), need)

    return fits


def load_check(
    site: SearchSite, load: np.ndarray, options: PlacementOptions,
    fits: Callable[[Candidate], bool] | None,
) -> ExtraCheck:
    """The held load's check: its outline ``load`` (robot frame) :data:`LOAD_CLEARANCE` from
    every obstacle of the grid at the pose and all the way in from the staging pose, and the
    robot with its load fitting at both as the navigator plans a carry (``fits``)."""
    load_options = dataclasses.replace(options, clearance=LOAD_CLEARANCE)

    def at_pose(cand: Candidate) -> bool:
        return footprint_free(site.clear, site.origin, site.res, load, cand, LOAD_CLEARANCE) and (
            fits is None or fits(cand)
        )

    def lines_up(cand: Candidate, staged: tuple[float, float, float]) -> bool:
        return staging_free(site.clear, site.origin, site.res, load, cand, load_options, 0.0) and (
            fits is None or fits(Candidate(*staged, 0.0, 0.0, 0.0))
        )

    return ExtraCheck("load collides", at_pose, lines_up)


def plan_place_base(
    nav: Any, services: RobotServices, body: int, name: str, target: Target,
    options: PlacementOptions, gap: float,
) -> Placement:
    """A base pose from which the arm of ``services``' robot places the object ``name`` (PyBullet
    body ``body``) it holds at ``target``, set down ``gap`` m above it (see the module
    docstring); ``nav`` is the robot's navigator, synced with the world."""
    world, robot = services.world, services.robot
    nav.refresh()
    options = dataclasses.replace(options, pivot=float(nav.pivot))
    site = SearchSite.of(nav, robot, nav.base_footprint)
    x0, y0, yaw0 = site.pose
    base_now = planar(x0, y0, yaw0)
    tip = robot.description.grasp_frame
    ik = arm_ik(services, tip)
    seed = robot.arm_positions()
    hand = robot.link_transform(tip)
    object_now = true_pose(world, body)
    try:
        size = box_size(world, name)
    except GraspError as exc:
        raise GraspError(f"cannot place '{name}': {exc}") from None
    load = load_samples(size, np.linalg.inv(base_now) @ object_now)
    extra = load_check(site, load, options, carry_fits(nav))
    frames = [lifted(f, gap) for f in place_frames(target, np.linalg.inv(hand) @ object_now, hand)]
    goal_xy = frames[0][:2, 3]
    relative_now = yaw_of_matrix(object_now) - yaw0

    def turn(cand: Candidate) -> float:
        return abs(wrap_half(target.yaw - cand.yaw - relative_now))

    rings = sample(goal_xy, site.arm_in_base[:2, 3], np.array([x0, y0]), options)
    rings.sort(key=lambda c: c.score(options.preferred_distance) + turn(c) / TURN_WEIGHT)
    candidates = mirrored(target, object_now, base_now, goal_xy) + rings

    def reach_place(
        cand: Candidate, arm_world: np.ndarray
    ) -> tuple[np.ndarray | None, np.ndarray | None, str]:
        last = ""
        for frame in frames:
            q, why = reach_down(ik, arm_world, frame, options.approach, seed)
            if q is not None:
                return q, frame, last
            last = why
        return None, None, last

    return search_bases(candidates, site, options, goal_xy, reach_place, PLACE_REJECTIONS, extra)


PLACE_REJECTIONS = {
    "collide": REJECTIONS["collide"],
    "load collides": "with the load too close to an obstacle",
    **{key: text for key, text in REJECTIONS.items() if key != "collide"},
}
"""A grasp search's reasons, and the held load's clearance."""
