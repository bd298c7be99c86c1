"""From a start and a goal in the world to a path the base can follow, or a reason why not.

:func:`plan_path` runs A* (:mod:`bt_manip.navigation.astar`) on the cost grid inflated for the
current footprint, shortcuts the cell path (:mod:`bt_manip.navigation.smoothing`) and returns a
:class:`NavPlan`: a world-coordinate polyline from the exact start to the exact goal, its
length, and, when there is no path, an outcome and a sentence saying why:

- the start or goal is off the map, or the goal lies inside an obstacle;
- ``FOOTPRINT``: the goal has too little clearance for the footprint, or every way there is
  too narrow for it while a narrower robot could get through (checked by planning again on the
  bare occupancy grid);
- ``NO_PATH``: the goal is not connected to the start at all.

A robot standing inside the blocked band around an obstacle (after docking next to a table,
say) is not stuck: the search starts from the nearest cell with enough clearance, within
``escape_distance``.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

from bt_manip.navigation.astar import PlanStatus, plan_verbose
from bt_manip.navigation.costmap import CostMap
from bt_manip.navigation.footprint import PlanarFootprint
from bt_manip.navigation.smoothing import densify, path_length, shortcut


class PlanOutcome(enum.Enum):
    """Why a plan exists or not."""

    OK = "ok"
    START_OUTSIDE = "start outside the map"
    GOAL_OUTSIDE = "goal outside the map"
    START_BLOCKED = "start has no clearance"
    GOAL_IN_OBSTACLE = "goal inside an obstacle"
    FOOTPRINT = "footprint"
    NO_PATH = "no path"


@dataclass(frozen=True)
class PlannerOptions:
    """Options of :func:`plan_path`."""

    smooth: bool = True
    """Shortcut the grid path by line of sight."""
    spacing: float = 0.05
    """Distance (m) between the points of the returned polyline."""
    escape_distance: float = 0.7
    """How far (m) the search may start from the robot when the robot stands in the blocked
    band of the inflated grid."""


@dataclass(frozen=True)
class NavPlan:
    """A path in the world (``polyline`` (n, 2), m) or the reason there is none."""

    outcome: PlanOutcome
    reason: str
    polyline: np.ndarray | None = None
    cells: np.ndarray | None = None
    length: float = math.inf

    @property
    def ok(self) -> bool:
        return self.outcome is PlanOutcome.OK


def _nearest_free(
    cost: np.ndarray, cell: tuple[int, int], radius_cells: int
) -> tuple[int, int] | None:
    rows, cols = cost.shape
    r0, c0 = cell
    lo_r, hi_r = max(0, r0 - radius_cells), min(rows, r0 + radius_cells + 1)
    lo_c, hi_c = max(0, c0 - radius_cells), min(cols, c0 + radius_cells + 1)
    window = np.isfinite(cost[lo_r:hi_r, lo_c:hi_c])
    if not window.any():
        return None
    rr, cc = np.nonzero(window)
    rr = rr + lo_r
    cc = cc + lo_c
    d2 = (rr - r0) ** 2 + (cc - c0) ** 2
    k = int(np.argmin(d2))
    if d2[k] > radius_cells**2:
        return None
    return int(rr[k]), int(cc[k])


def plan_path(
    costmap: CostMap,
    footprint: PlanarFootprint,
    start: tuple[float, float],
    goal: tuple[float, float],
    options: PlannerOptions = PlannerOptions(),
) -> NavPlan:
    """Plan from world point ``start`` to ``goal`` (x, y) for ``footprint`` on ``costmap``."""
    grid = costmap.grid
    cost = costmap.cost_for(footprint)
    s = grid.world_to_cell(*start)
    t = grid.world_to_cell(*goal)
    if not grid.inside(s):
        return NavPlan(
            PlanOutcome.START_OUTSIDE,
            f"start ({start[0]:.2f}, {start[1]:.2f}) is outside the map {_fmt_extent(grid.extent)}",
        )
    if not grid.inside(t):
        return NavPlan(
            PlanOutcome.GOAL_OUTSIDE,
            f"goal ({goal[0]:.2f}, {goal[1]:.2f}) is outside the map {_fmt_extent(grid.extent)}",
        )
    need = footprint.half_width + costmap.options.margin
    if grid.occupied[t]:
        return NavPlan(
            PlanOutcome.GOAL_IN_OBSTACLE,
            f"goal ({goal[0]:.2f}, {goal[1]:.2f}) is inside an obstacle",
        )
    if not math.isfinite(cost[t]):
        return NavPlan(
            PlanOutcome.FOOTPRINT,
            f"goal ({goal[0]:.2f}, {goal[1]:.2f}) is too close to obstacles for the footprint: "
            f"{costmap.clearance_of_cell(t):.2f} m clearance, {footprint.describe()} needs "
            f"{need:.2f} m",
        )
    search_start = s
    if not math.isfinite(cost[s]):
        radius = max(1, math.ceil(options.escape_distance / grid.resolution))
        free = _nearest_free(cost, s, radius)
        if free is None:
            return NavPlan(
                PlanOutcome.START_BLOCKED,
                f"no cell with {need:.2f} m clearance within {options.escape_distance:.2f} m of "
                f"the start ({start[0]:.2f}, {start[1]:.2f}) for {footprint.describe()}",
            )
        search_start = free
    res = plan_verbose(cost, search_start, t)
    if res.status is not PlanStatus.FOUND:
        bare = np.where(grid.occupied, np.float32(np.inf), np.float32(1.0))
        if plan_verbose(bare, s, t).found:
            return NavPlan(
                PlanOutcome.FOOTPRINT,
                f"no way to ({goal[0]:.2f}, {goal[1]:.2f}) is wide enough for the footprint "
                f"({footprint.describe()}, {need:.2f} m clearance per side); a narrower robot "
                "could reach it",
            )
        return NavPlan(
            PlanOutcome.NO_PATH,
            f"goal ({goal[0]:.2f}, {goal[1]:.2f}) is not connected to the start on the map",
        )
    cells = res.path
    assert cells is not None
    if search_start != s:
        cells = np.vstack([np.array([s]), cells])
    corners = shortcut(cost, cells) if options.smooth else cells
    pts = grid.cells_to_world(corners)
    pts[0] = start
    pts[-1] = goal
    if len(pts) >= 2 and np.allclose(pts[0], pts[1]):
        pts = pts[1:]
    poly = densify(pts, options.spacing)
    return NavPlan(PlanOutcome.OK, "ok", poly, cells, path_length(poly))


def _fmt_extent(e: tuple[float, float, float, float]) -> str:
    return f"x {e[0]:.2f}..{e[2]:.2f}, y {e[1]:.2f}..{e[3]:.2f}"
