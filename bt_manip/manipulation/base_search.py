"""Where to park a mobile manipulator so that its arm can take an object (PlanBaseForGrasp).

The planner (:func:`plan_base`) samples base poses around the object's grasp point, in rings:
for each distance ``d`` of :attr:`PlacementOptions.distances` (from the arm's base to the grasp
point, horizontally) and each of :attr:`PlacementOptions.bearings` directions around the grasp
point, the arm's base is put at that distance and the robot is turned to face the grasp point,
then turned further by each of :attr:`PlacementOptions.heading_offsets`. A pose is kept when:

1. the robot's footprint (as the navigator plans with it) is at least ``clearance`` from every
   obstacle of the navigator's occupancy grid (walls, furniture, movable objects where they are);
2. the way from the arm's base to the grasp point crosses no obstacle of the grid (farther than
   :data:`NEAR_GRASP` from the grasp point: the object and its support are there), so the arm
   does not reach over a wall or a cabinet;
3. the arm's IK, solved for the arm's base at that pose, reaches the pre-grasp point
   (``approach`` metres back from the grasp along the approach axis) from the named arm state
   ``arm_state`` (``home`` by default: the tree moves the arm there before reaching), and
   every point of the straight line from there to the grasp frame (the waypoints a
   straight-line move takes, each seeded by the one before, as MoveToPose does);
4. the robot can line up at the staging pose, :attr:`PlacementOptions.staging` behind it and
   facing the same way (room to turn on the spot there), and drive straight in from there
   (its footprint clear all the way): turning on the spot next to the object would sweep
   into it;
5. the navigator finds a path from where the robot is to the staging pose.

The best pose is the kept one with the lowest score (see :meth:`Candidate.score`)::

    score = carried / 0.1 m + |d - preferred_distance| / 0.1 m + |heading offset| / 0.5 rad
            + (straight distance from the robot) / 10 m

where ``carried`` is how far the object will stick out to each side of the robot once it is
held as grasped from that pose (half its longest horizontal side times the sine of the angle
between that side and the robot's heading). That is: first the narrowest robot-and-load to
carry through doorways (a 1.2 m panel held square across the robot makes it 1.2 m wide, held
at 45 deg 0.85 m), then the arm at mid reach (a base that stops a few centimetres off still
reaches), then facing the object, then near the robot. Candidates are checked in order of
their score and the first that passes every check is taken, so the work is bounded: at most
``len(distances) x bearings x len(heading_offsets)`` footprint checks,
:attr:`PlacementOptions.max_ik_candidates` IK checks (each at most ``2 + approach / 0.02``
solves) and :attr:`PlacementOptions.max_path_checks` path plans. Everything is deterministic:
the same world and robot pose give the same base pose.

The checks and their budgets are one search, :func:`search_bases`, which the search for a place
(:mod:`bt_manip.manipulation.place_search`) runs too, with its own candidates, its own IK check
and an :class:`ExtraCheck` for the load it holds.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bt_manip.manipulation.cartesian import STEP, arm_ik
from bt_manip.manipulation.errors import ManipulationError
from bt_manip.manipulation.grasps import GraspError, box_size, grasp_frame, top_face
from bt_manip.manipulation.perception import seen_pose
from bt_manip.navigation.lattice import outline_samples
from bt_manip.run.context import RobotServices

SWEEP_STEP = 0.1
"""Spacing (m) of the footprint checks along the straight drive from the staging pose."""
NEAR_GRASP = 0.1
"""Obstacles within this distance (m) of the grasp point do not block the arm's way (the
object itself and what it stands in are there)."""


class PlacementError(ManipulationError):
    """A base-pose search cannot start (an unknown arm state); the message says why."""


@dataclass(frozen=True)
class PlacementOptions:
    """How :func:`plan_base` samples and checks base poses."""

    distances: tuple[float, ...] = (0.30, 0.34, 0.38, 0.42)
    """Distances (m) from the arm's base to the grasp point, horizontally."""
    bearings: int = 24
    """Directions around the grasp point (evenly spaced, the first along world +x)."""
    heading_offsets: tuple[float, ...] = (0.0, -0.35, 0.35, -0.7, 0.7)
    """Turns (rad) of the robot away from facing the grasp point."""
    preferred_distance: float = 0.36
    """The distance (m) the score prefers: the arm at mid reach."""
    approach: float = 0.12
    """Pre-grasp point: this far (m) back from the grasp along the approach axis."""
    clearance: float = 0.1
    """Footprint clearance (m) from every obstacle of the grid: the base stops a few
    centimetres off, and the carry that follows plans with 5 cm of clearance."""
    max_ik_candidates: int = 48
    """At most this many poses get the IK check."""
    max_path_checks: int = 6
    """At most this many poses get the path check."""
    staging: float = 0.7
    """The robot lines up this far (m) behind the base pose, facing the same way, and drives
    straight in from there: turning on the spot next to the object would sweep into it."""
    arm_state: str = "home"
    """Named arm state the reach starts from (the IK's seed); empty: the arm's posture now."""
    pivot: float = 0.0
    """Where the base turns on the spot (m ahead of its frame; the navigator's)."""


@dataclass(frozen=True)
class Candidate:
    """One sampled base pose."""

    x: float
    y: float
    yaw: float
    distance: float
    heading_offset: float
    travel: float
    carried: float = 0.0
    """How far (m) the object reaches out to each side of the robot's heading once it is
    held as grasped here: half its long side times the sine of the angle between that side
    and the heading."""

    def score(self, preferred_distance: float) -> float:
        """Lower is better (see the module docstring)."""
        return (
            self.carried / 0.1
            + abs(self.distance - preferred_distance) / 0.1
            + abs(self.heading_offset) / 0.5
            + self.travel / 10.0
        )


@dataclass
class Placement:
    """What :func:`plan_base` found: a base pose and the grasp frame for it, or why none."""

    ok: bool
    reason: str
    base_pose: tuple[float, float, float] | None = None
    staging_pose: tuple[float, float, float] | None = None
    grasp: np.ndarray | None = None
    q_grasp: np.ndarray | None = None
    counts: dict[str, int] = field(default_factory=dict)


def planar(x: float, y: float, yaw: float) -> np.ndarray:
    """4x4 transform of a planar pose (z = 0)."""
    t = np.eye(4)
    c, s = math.cos(yaw), math.sin(yaw)
    t[:2, :2] = [[c, -s], [s, c]]
    t[0, 3], t[1, 3] = x, y
    return t


def left_of(yaw: float) -> tuple[float, float]:
    """The horizontal direction to the left of a heading."""
    return (-math.sin(yaw), math.cos(yaw))


def object_grasp(
    world: Any, faults: Any, robot: Any, name: str, kind: str, heading: float
) -> np.ndarray:
    """The grasp frame ``kind`` of object ``name`` as the robot perceives it (``faults``: the
    run's fault injector, or None), for a robot base heading ``heading``; GraspError with the
    reason when the object cannot be grasped so, PerceptionError when there is no such object."""
    try:
        size = box_size(world, name)
        pose = seen_pose(world, faults, name)
        return grasp_frame(
            kind, size, pose, left_of(heading), robot.description.gripper.max_opening
        )
    except GraspError as exc:
        raise GraspError(f"cannot grasp '{name}': {exc}") from None


def long_side(world: Any, faults: Any, name: str) -> np.ndarray:
    """Half the longest horizontal side of the box ``name`` as the robot sees it, as a world
    vector (x, y)."""
    try:
        size = box_size(world, name)
    except GraspError as exc:
        raise GraspError(f"cannot grasp '{name}': {exc}") from None
    pose = seen_pose(world, faults, name)
    up_axis, _ = top_face(size, pose)
    axis = max((i for i in range(3) if i != up_axis), key=lambda i: (size[i], -i))
    return np.asarray(pose[:2, axis] * size[axis] / 2.0, dtype=float)


def sample(
    grasp_xy: np.ndarray,
    arm_offset: np.ndarray,
    robot_xy: np.ndarray,
    options: PlacementOptions,
    long_side: np.ndarray | None = None,
) -> list[Candidate]:
    """The base poses of the rings around ``grasp_xy``, best score first. ``arm_offset`` is
    where the arm's base sits in the robot's planar frame (x forward, y left); ``long_side``
    is the object's longest horizontal half side (x, y in the world; m), for the
    ``carried`` width of each pose."""
    half = np.zeros(2) if long_side is None else np.asarray(long_side, dtype=float)
    out = []
    for d in options.distances:
        for k in range(options.bearings):
            bearing = 2.0 * math.pi * k / options.bearings
            ax = grasp_xy[0] + d * math.cos(bearing)
            ay = grasp_xy[1] + d * math.sin(bearing)
            facing = bearing + math.pi
            for off in options.heading_offsets:
                yaw = math.atan2(math.sin(facing + off), math.cos(facing + off))
                c, s = math.cos(yaw), math.sin(yaw)
                x = ax - (c * arm_offset[0] - s * arm_offset[1])
                y = ay - (s * arm_offset[0] + c * arm_offset[1])
                travel = math.hypot(x - robot_xy[0], y - robot_xy[1])
                carried = abs(float(half[0] * -s + half[1] * c))
                out.append(Candidate(x, y, yaw, d, off, travel, carried))
    out.sort(key=lambda cand: cand.score(options.preferred_distance))
    return out


def footprint_free(
    clear: np.ndarray, origin: np.ndarray, res: float, pts: np.ndarray, cand: Candidate,
    need: float,
) -> bool:
    """Whether every footprint point (robot frame) at ``cand`` has ``need`` clearance."""
    c, s = math.cos(cand.yaw), math.sin(cand.yaw)
    px = cand.x + c * pts[:, 0] - s * pts[:, 1]
    py = cand.y + s * pts[:, 0] + c * pts[:, 1]
    cols = np.floor((px - origin[0]) / res).astype(int)
    rows = np.floor((py - origin[1]) / res).astype(int)
    if rows.min() < 0 or cols.min() < 0 or rows.max() >= clear.shape[0]:
        return False
    if cols.max() >= clear.shape[1]:
        return False
    return bool(np.all(clear[rows, cols] >= need))


def staging(cand: Candidate, options: PlacementOptions) -> tuple[float, float, float]:
    """The staging pose of a candidate: :attr:`PlacementOptions.staging` behind it, facing
    the same way."""
    back = options.staging
    return (cand.x - back * math.cos(cand.yaw), cand.y - back * math.sin(cand.yaw), cand.yaw)


def staging_free(
    clear: np.ndarray, origin: np.ndarray, res: float, pts: np.ndarray, cand: Candidate,
    options: PlacementOptions, turning: float,
) -> bool:
    """Whether the robot can line up at the staging pose (room to turn on the spot there:
    ``turning`` m of clearance around its pivot) and drive straight from there to the
    candidate (the footprint clear every :data:`SWEEP_STEP` metres of the way)."""
    sx, sy, yaw = staging(cand, options)
    pivot = (sx + options.pivot * math.cos(yaw), sy + options.pivot * math.sin(yaw))
    col = math.floor((pivot[0] - origin[0]) / res)
    row = math.floor((pivot[1] - origin[1]) / res)
    if not (0 <= row < clear.shape[0] and 0 <= col < clear.shape[1]):
        return False
    if clear[row, col] < turning:
        return False
    n = max(1, math.ceil(options.staging / SWEEP_STEP))
    for i in range(n):
        t = i / n
        x = sx + (cand.x - sx) * t
        y = sy + (cand.y - sy) * t
        if not footprint_free(
            clear, origin, res, pts, Candidate(x, y, yaw, 0.0, 0.0, 0.0), options.clearance
        ):
            return False
    return True


def way_clear(
    occupied: np.ndarray, origin: np.ndarray, res: float, start: np.ndarray, grasp: np.ndarray
) -> bool:
    """Whether the straight way from ``start`` to ``grasp`` (x, y) crosses no occupied cell
    farther than :data:`NEAR_GRASP` from the grasp point."""
    length = float(np.hypot(*(grasp - start)))
    if length <= NEAR_GRASP:
        return True
    n = max(2, math.ceil((length - NEAR_GRASP) / (res / 2.0)) + 1)
    t = np.linspace(0.0, (length - NEAR_GRASP) / length, n)
    pts = start[None, :] + t[:, None] * (grasp - start)[None, :]
    cols = np.clip(np.floor((pts[:, 0] - origin[0]) / res).astype(int), 0, occupied.shape[1] - 1)
    rows = np.clip(np.floor((pts[:, 1] - origin[1]) / res).astype(int), 0, occupied.shape[0] - 1)
    return not bool(np.any(occupied[rows, cols]))


def reach(
    ik: Any, arm_in_world: np.ndarray, grasp: np.ndarray, approach: float, seed: np.ndarray
) -> tuple[np.ndarray | None, str]:
    """Joint values at the grasp frame when the arm (its base at ``arm_in_world``) reaches
    the pre-grasp point and then every waypoint of the straight line to the grasp; else None
    and IK's reason."""
    to_arm = np.linalg.inv(arm_in_world)
    pre = grasp.copy()
    pre[:3, 3] -= approach * grasp[:3, 2]
    result = ik.full.solve(to_arm @ pre, q_seed=seed)
    if not result.success:
        return None, f"pre-grasp point: {result.reason}"
    q = result.q
    n = max(1, math.ceil(approach / STEP))
    for i in range(1, n + 1):
        point = grasp.copy()
        point[:3, 3] = pre[:3, 3] + (grasp[:3, 3] - pre[:3, 3]) * (i / n)
        result = ik.full.solve(to_arm @ point, q_seed=q)
        if not result.success:
            return None, f"approach line: {result.reason}"
        q = result.q
    return np.asarray(q, dtype=float), ""


@dataclass(frozen=True)
class SearchSite:
    """What a base-pose search checks its candidates against: the navigator's grid and the
    robot's footprint on it, where the robot stands now and where its arm sits on the base."""

    nav: Any
    """The robot's navigator: its grid planner gives the path check (``plan_to``)."""
    clear: np.ndarray
    """Clearance (m) of each cell of the navigator's occupancy grid."""
    occupied: np.ndarray
    origin: np.ndarray
    res: float
    pts: np.ndarray
    """Points (x, y; robot frame) round the footprint the poses are checked with."""
    turning: float
    """Clearance (m) around the pivot the robot needs to turn on the spot at a staging pose."""
    pose: tuple[float, float, float]
    """Where the robot stands now (x, y, yaw)."""
    arm_in_base: np.ndarray
    """The arm's base in the robot's planar frame (4x4)."""

    @classmethod
    def of(cls, nav: Any, robot: Any, footprint: Any) -> SearchSite:
        """The site of ``robot`` on its (refreshed) navigator ``nav``, checked with
        ``footprint`` (a PlanarFootprint)."""
        grid = nav.costmap.grid
        x0, y0, yaw0 = robot.base_pose2d()
        arm = robot.link_transform(robot.description.arm.base_link)
        return cls(
            nav, nav.costmap.clear, grid.occupied, np.asarray(grid.origin, dtype=float),
            float(grid.resolution), outline_samples(footprint), float(footprint.circumradius),
            (x0, y0, yaw0), np.linalg.inv(planar(x0, y0, yaw0)) @ arm,
        )


@dataclass(frozen=True)
class ExtraCheck:
    """A check a base-pose search makes besides its own (PlanBaseForPlace: the held load)."""

    key: str
    """What a pose :attr:`at_pose` turns down is counted as (a key of the search's labels)."""
    at_pose: Callable[[Candidate], bool]
    """Whether the pose passes; asked right after the footprint check."""
    lines_up: Callable[[Candidate, tuple[float, float, float]], bool]
    """Whether the robot lines up at the staging pose (the second argument) and drives in to
    the pose; asked with the footprint's line-up check, turned down as "no room to line up"."""


Reach = Callable[[Candidate, np.ndarray], tuple[np.ndarray | None, np.ndarray | None, str]]
"""The IK check of a search: for a candidate and where the arm's base is then (4x4, world),
the joint values and the frame the arm reaches (None, None when it reaches none) and the last
IK failure on the way ("" when there was none)."""


def search_bases(
    candidates: list[Candidate],
    site: SearchSite,
    options: PlacementOptions,
    goal_xy: np.ndarray,
    reach: Reach,
    labels: dict[str, str],
    extra: ExtraCheck | None = None,
) -> Placement:
    """The first of ``candidates`` that passes every check, in this order: the footprint's
    clearance, ``extra``'s check of the pose, room to line up at the staging pose (the
    footprint's and ``extra``'s), the arm's way to ``goal_xy`` clear of obstacles, ``reach``
    (at most :attr:`PlacementOptions.max_ik_candidates` times) and a path from where the robot
    stands to the staging pose (at most :attr:`PlacementOptions.max_path_checks` times).
    Otherwise a Placement that is not ok, whose reason counts the poses turned down under
    each key of ``labels`` (the checks' keys: "collide", "no room to line up", "reach over",
    "IK", "no path" and ``extra``'s)."""
    counts = {"sampled": len(candidates), **dict.fromkeys(labels, 0)}
    s = site
    x0, y0, yaw0 = s.pose
    pivot = options.pivot
    ik_checks = path_checks = 0
    last_ik = ""
    for cand in candidates:
        if not footprint_free(s.clear, s.origin, s.res, s.pts, cand, options.clearance):
            counts["collide"] += 1
            continue
        if extra is not None and not extra.at_pose(cand):
            counts[extra.key] += 1
            continue
        sx, sy, syaw = staging(cand, options)
        if not staging_free(s.clear, s.origin, s.res, s.pts, cand, options, s.turning) or (
            extra is not None and not extra.lines_up(cand, (sx, sy, syaw))
        ):
            counts["no room to line up"] += 1
            continue
        arm_world = planar(cand.x, cand.y, cand.yaw) @ s.arm_in_base
        if not way_clear(s.occupied, s.origin, s.res, arm_world[:2, 3], goal_xy):
            counts["reach over"] += 1
            continue
        if ik_checks >= options.max_ik_candidates:
            break
        ik_checks += 1
        q, frame, why = reach(cand, arm_world)
        if why:
            last_ik = why
        if q is None:
            counts["IK"] += 1
            continue
        if path_checks >= options.max_path_checks:
            break
        path_checks += 1
        start = (x0 + pivot * math.cos(yaw0), y0 + pivot * math.sin(yaw0), yaw0)
        goal = (sx + pivot * math.cos(syaw), sy + pivot * math.sin(syaw), syaw)
        if not s.nav.plan_to(start, goal).ok:
            counts["no path"] += 1
            continue
        return Placement(True, "", (cand.x, cand.y, cand.yaw), (sx, sy, syaw), frame, q, counts)
    budget_spent = (ik_checks >= options.max_ik_candidates
                    or path_checks >= options.max_path_checks)
    return Placement(False, rejections_text(counts, labels, budget_spent, last_ik),
                     counts=counts)


def plan_base(
    nav: Any,
    services: RobotServices,
    faults: Any,
    name: str,
    kind: str,
    options: PlacementOptions,
) -> Placement:
    """A base pose from which the arm of ``services``' robot takes object ``name`` with grasp
    ``kind`` (see the module docstring); ``nav`` is the robot's navigator, synced with the
    world, and ``faults`` the run's fault injector (or None)."""
    world, robot = services.world, services.robot
    nav.refresh()
    options = dataclasses.replace(options, pivot=float(nav.pivot))
    site = SearchSite.of(nav, robot, nav.footprint)
    x0, y0, yaw0 = site.pose
    ik = arm_ik(services, robot.description.grasp_frame)
    seed = robot.arm_positions()
    if options.arm_state:
        states = robot.description.states
        if options.arm_state not in states:
            raise PlacementError(
                f"unknown arm state '{options.arm_state}'; known: {', '.join(states)}"
            )
        seed = np.asarray(states[options.arm_state], dtype=float)
    grasp0 = object_grasp(world, faults, robot, name, kind, yaw0)
    grasp_xy = grasp0[:2, 3]
    candidates = sample(
        grasp_xy, site.arm_in_base[:2, 3], np.array([x0, y0]), options,
        long_side(world, faults, name),
    )

    def reach_grasp(
        cand: Candidate, arm_world: np.ndarray
    ) -> tuple[np.ndarray | None, np.ndarray | None, str]:
        grasp = object_grasp(world, faults, robot, name, kind, cand.yaw)
        q, why = reach(ik, arm_world, grasp, options.approach, seed)
        return q, (grasp if q is not None else None), why

    return search_bases(candidates, site, options, grasp_xy, reach_grasp, REJECTIONS)


REJECTIONS = {
    "collide": "too close to an obstacle",
    "no room to line up": "with no room to line up behind them",
    "reach over": "would reach over an obstacle",
    "IK": "out of the arm's reach",
    "no path": "with no path to them",
}
"""Why sampled base poses were turned down, by their key in a search's counts."""


def rejections_text(
    counts: dict[str, int], labels: dict[str, str], budget_spent: bool, last_ik: str
) -> str:
    """The reason a base-pose search found nothing: how many poses it sampled, how many it
    turned down for each reason in ``labels`` (in their order), whether its check budget ran
    out, and the last IK failure."""
    parts = [f"{counts['sampled']} poses sampled"]
    parts += [f"{counts[k]} {text}" for k, text in labels.items() if counts[k]]
    if budget_spent:
        parts.append("check budget spent")
    if last_ik:
        parts.append(f"last IK failure: {last_ik}")
    return "; ".join(parts)
