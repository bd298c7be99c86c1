"""Planning in (x, y, heading) for footprints that are long or lopsided.

The grid planner (:mod:`bt_manip.navigation.planner`) treats the robot as a disc of its half
width, which is right for a base that drives along its path but not for a base that carries a
1.2 m panel ahead of it: turning that base sweeps the panel over two metres. :func:`plan_poses`
searches over poses instead (a hybrid A*): from each pose it tries short moves -- forward or
backward, straight or along an arc, or a turn on the spot about the base's pivot point --
checks the whole footprint along each move against the clearance grid, and keeps the cheapest
pose per (x, y, heading) bin (a pose already expanded keeps its bin, so every pose of the
result is reached from the one before by one move). Backing up costs double, turning on the
spot costs ``turn_cost`` metres per radian, and changing from one kind of move to another
costs ``steer_cost``, so the result drives forward where it can and keeps a heading rather
than weaving between neighbouring ones.

The moves are checked every few centimetres of footprint travel: every outline point must keep
``min_clearance`` from obstacles (the clearance grid is a lower bound on the distance from a
cell's centre, so the point's own offset in its cell is subtracted too; the points are looked
at a group at a time where the cells around a group all keep the margin, with the same answer
as point by point, see :mod:`bt_manip.navigation.outline_check`). When no plan keeps the
margin, one keeping ``squeeze_clearance`` is looked for: a doorway only a little wider than
the base is passed with a few centimetres to spare. A start closer than
that but not touching (a robot that has just lifted a load out of a stand beside it) is
accepted: within ``tight_start`` of it, moves from a pose without the margin need only keep
the footprint off the obstacles, at three times the cost, so the plan
gets out of the tight spot first. The heuristic is the
obstacle-aware distance to the goal on the grid of cells with enough clearance for the
footprint's half width, so the search heads through the right doorways.

The result is a list of poses with the move that reaches each (:class:`PosePlan`), which
:class:`bt_manip.navigation.segments.SegmentFollower` executes. The search itself is compiled
(numba), in :mod:`bt_manip.navigation.lattice_search`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from bt_manip.navigation.costmap import CHUNK_CELLS, clearance_of
from bt_manip.navigation.footprint import PlanarFootprint
from bt_manip.navigation.grid import OccupancyGrid
from bt_manip.navigation.lattice_search import GoalField, pose_fits, search_poses
from bt_manip.navigation.outline_check import WindowMinima, point_groups, window_cells

FORWARD, BACKWARD, TURN = 0, 1, 2
"""Move kinds in :attr:`PosePlan.moves`."""


@dataclass(frozen=True)
class LatticeOptions:
    """Options of :func:`plan_poses` (SI units)."""

    step: float = 0.2
    """Length (m) of a straight or arc move."""
    turn_radius: float = 1.0
    """Radius (m) of the arc moves."""
    heading_bins: int = 32
    xy_bin: float = 0.1
    turn_step: float = math.pi / 16
    """Angle (rad) of one turn on the spot."""
    turn_cost: float = 0.6
    """Cost (m) of turning on the spot by one radian."""
    reverse_factor: float = 2.0
    min_clearance: float = 0.05
    goal_xy: float = 0.15
    goal_yaw: float = 0.2
    max_expansions: int = 400_000
    check_spacing: float = 0.05
    """Largest travel (m) of any footprint point between two collision checks."""
    steer_cost: float = 0.1
    """Cost (m) of changing from one kind of move to another (straight to arc, arc to straight
    or to the other side, driving to turning on the spot, forward to backward): the plan keeps
    a heading where it can instead of weaving between neighbouring headings, which a follower
    would cut across."""
    tight_start: float = 0.6
    """Within this distance (m) of a start that lacks ``min_clearance`` (but touches nothing),
    moves need only keep the footprint off the obstacles (see the module)."""
    squeeze_clearance: float = 0.02
    """When no sequence of moves keeps ``min_clearance`` (or the goal lacks it), the search is
    run once more keeping only this much (m) from obstacles: a base a few centimetres narrower
    than a doorway (a Husky's 0.67 m in a house's 0.885 m door) passes it with the smaller
    margin rather than not at all. No second search when it is not below ``min_clearance``."""


@dataclass(frozen=True)
class PosePlan:
    """Poses (n, 3) from start to (near) goal and the move reaching each (n - 1,) or a reason."""

    ok: bool
    reason: str
    poses: np.ndarray | None = None
    moves: np.ndarray | None = None
    length: float = math.inf
    expanded: int = 0
    margin: float = math.nan
    """The clearance (m) the plan keeps from obstacles: ``min_clearance``, or
    ``squeeze_clearance`` when only that fits (NaN without a plan)."""


def outline_samples(footprint: PlanarFootprint, spacing: float = 0.05) -> np.ndarray:
    """Points every ``spacing`` metres along the boundary of every outline (robot frame)."""
    pts = []
    for o in footprint.outlines:
        ring = o.points(48)
        edge = np.roll(ring, -1, axis=0) - ring  # from each corner to the next
        n = np.maximum(1, np.ceil(np.hypot(edge[:, 0], edge[:, 1]) / spacing)).astype(np.int64)
        of = np.repeat(np.arange(len(ring)), n)  # the edge of each sample
        k = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)  # its index on the edge
        t = k / n[of]
        pts.append(ring[of] + t[:, None] * edge[of])
    return np.concatenate(pts)


def clearance_at_least(clear: np.ndarray, res: float, threshold: float) -> np.ndarray:
    """Cells whose clearance is at least ``threshold`` (m), from a clearance grid or squared
    cell distances (converted a block of rows at a time)."""
    if clear.dtype.kind == "f":
        return clear >= threshold
    out = np.empty(clear.shape, bool)
    step = max(1, CHUNK_CELLS // max(1, clear.shape[1]))
    for a in range(0, clear.shape[0], step):
        block = clear[a : a + step]
        out[a : a + step] = clearance_of(block, block.shape, res) >= threshold
    return out


def pose_free(
    clear: np.ndarray, clear_high: np.ndarray, origin: tuple[float, float], res: float,
    pts: np.ndarray, pts_high: np.ndarray, pose: tuple[float, float, float], need: float,
) -> bool:
    """Whether the robot at ``pose`` keeps ``need`` m from obstacles as :func:`plan_poses`
    checks a goal: points ``pts`` (robot frame) on the clearance grid ``clear``, carried-object
    points ``pts_high`` on ``clear_high`` (grids of origin ``origin``, cells of ``res`` m)."""
    x0, y0 = origin
    return bool(pose_fits(clear, clear_high, x0, y0, res, pts, pts_high, *pose, need))


def plan_poses(
    grid: OccupancyGrid,
    clear: np.ndarray,
    footprint: PlanarFootprint,
    start: tuple[float, float, float],
    goal: tuple[float, float, float],
    pivot: float = 0.0,
    options: LatticeOptions = LatticeOptions(),
    carried: PlanarFootprint | None = None,
    clear_high: np.ndarray | None = None,
) -> PosePlan:
    """Poses from ``start`` to within the goal tolerances of ``goal``.

    ``footprint`` (the robot) is checked against ``clear``; ``carried`` (objects held above
    the floor) against ``clear_high``, the clearance of the obstacles tall enough to reach
    them, so a panel may pass over a low stand the wheels must avoid. Each is a clearance
    grid (m, float) or, using half the memory, the grid's squared cell distances (integers,
    :func:`bt_manip.navigation.distance.squared_distances`), which give the same clearances.

    Every pose keeps ``options.min_clearance`` from obstacles; when no plan does, or the goal
    does not, one keeping ``options.squeeze_clearance`` is searched for (the plan's
    ``margin`` says which); when neither is found, the reason is the first search's.
    """
    o = options
    pts = outline_samples(footprint, 0.05)
    if carried is not None and clear_high is not None:
        pts_high = outline_samples(carried, 0.05)
        high = clear_high
    else:
        pts_high = np.zeros((0, 2))
        high = clear
    both = np.vstack([pts, pts_high])
    whole = (
        footprint.describe()
        if carried is None
        else (
            f"{footprint.label} + {carried.label}: reaching {float(np.hypot(*both.T).max()):.2f} m"
        )
    )
    reach = float(np.hypot(both[:, 0] - pivot, both[:, 1]).max()) + abs(pivot)
    x0, y0 = grid.origin
    res = grid.resolution
    need_low = res / math.sqrt(2.0)
    start_fits = pose_fits(clear, high, x0, y0, res, pts, pts_high, *start, need_low)
    groups, groups_high = point_groups(pts), point_groups(pts_high)
    window = max(window_cells(groups, res), window_cells(groups_high, res))
    windows = WindowMinima(clear.shape, window)
    windows_high = windows if high is clear else WindowMinima(high.shape, window)

    def keeping(margin: float) -> PosePlan:
        """The plan whose every pose keeps ``margin`` from obstacles (one search)."""
        need = margin + need_low
        if not pose_fits(clear, high, x0, y0, res, pts, pts_high, *goal, need):
            return PosePlan(False, f"the footprint ({whole}) does not fit at the goal")
        if not start_fits:
            return PosePlan(False, f"the footprint ({whole}) touches obstacles at the start")
        free = clearance_at_least(clear, res, footprint.half_width + margin)
        gc = grid.world_to_cell(goal[0], goal[1])
        field = GoalField(free, gc if grid.inside(gc) else None)
        params = np.array(
            [
                o.step,
                1.0 / o.turn_radius,
                o.heading_bins,
                o.xy_bin,
                o.turn_step,
                o.turn_cost,
                o.reverse_factor,
                o.goal_xy,
                o.goal_yaw,
                o.max_expansions,
                o.check_spacing,
                pivot,
                need_low,
                o.tight_start,
                o.steer_cost,
            ]
        )
        parent, move_of, pose, end, expanded = search_poses(
            clear,
            high,
            x0,
            y0,
            res,
            pts,
            pts_high,
            reach,
            need,
            (groups.points, groups.first, groups.centre, groups.radius, groups.reach),
            (
                groups_high.points,
                groups_high.first,
                groups_high.centre,
                groups_high.radius,
                groups_high.reach,
            ),
            (windows.low, windows.done, windows.window),
            (windows_high.low, windows_high.done, windows_high.window),
            field.free,
            field.dist,
            field.heap_d,
            field.heap_i,
            field.state,
            field.frontier,
            np.asarray(start, float),
            np.asarray(goal, float),
            params,
        )
        if end < 0:
            return PosePlan(
                False,
                f"no sequence of moves fits the footprint ({whole}) from the start to the goal",
                expanded=expanded,
            )
        chain = [end]
        while parent[chain[-1]] >= 0:
            chain.append(int(parent[chain[-1]]))
        chain.reverse()
        poses = pose[chain].copy()
        kinds = np.array([FORWARD] * 3 + [BACKWARD] * 3 + [TURN] * 2)
        moves = kinds[move_of[chain[1:]]]
        length = float(np.hypot(*np.diff(poses[:, :2], axis=0).T).sum())
        return PosePlan(True, "ok", poses, moves, length, expanded, margin)

    found = keeping(o.min_clearance)
    squeeze = max(o.squeeze_clearance, 0.0)
    if found.ok or not start_fits or squeeze >= o.min_clearance:
        return found
    tight = keeping(squeeze)
    if tight.ok:
        return tight
    return replace(found, expanded=found.expanded + tight.expanded)
