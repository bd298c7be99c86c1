"""Cost-optimal A* on a 2-D grid of traversal costs.

The grid is a ``float32`` array ``cost[row, col]``: ``inf`` marks a blocked cell, any finite
value (>= 1 by convention, at least > 0) is the cost per cell length of entering that cell. A
move from cell ``a`` to its neighbour ``b`` costs ``step_length(a, b) * cost[b]`` with
``step_length`` 1 for the four side neighbours and ``sqrt(2)`` for the four diagonal ones. A
diagonal move is allowed only when both cells beside it are free (no corner cutting).

:func:`plan` returns the cells of a cheapest path, start and goal included, or ``None``;
:func:`plan_verbose` also tells why there is no path (start or goal outside the grid or blocked,
or no connection), the path cost and how many cells the search expanded.

The search (:mod:`bt_manip.navigation.astar_search`) is compiled with numba, ``cache=True``:
the machine code is stored next to the module and loaded by later processes, so only the very
first query on a machine pays the compilation (a few seconds); later processes pay a fraction
of a second on their first query. Call :func:`warm_up` at start-up to move that cost out of
the first tick. The heuristic is the octile distance times the smallest cell cost (admissible
and consistent); the result is the optimum up to floating-point rounding.
"""

from __future__ import annotations

import enum
import itertools
import math
from dataclasses import dataclass

import numpy as np

from bt_manip.navigation.astar_search import (
    Scratch,
    cost_range,
    search_buckets,
    search_heap,
    trace,
)

SQRT2 = math.sqrt(2.0)


class PlanStatus(enum.Enum):
    """Outcome of one grid search."""

    FOUND = "found"
    START_OUTSIDE = "start outside the grid"
    GOAL_OUTSIDE = "goal outside the grid"
    START_BLOCKED = "start cell is blocked"
    GOAL_BLOCKED = "goal cell is blocked"
    NO_PATH = "no path between start and goal"


@dataclass(frozen=True)
class PlanResult:
    """A grid search result: ``path`` is ``(n, 2)`` rows/cols from start to goal, or ``None``."""

    status: PlanStatus
    path: np.ndarray | None
    cost: float
    expanded: int

    @property
    def found(self) -> bool:
        return self.status is PlanStatus.FOUND

    @property
    def reason(self) -> str:
        """Human-readable reason (``"found"`` when a path exists)."""
        return self.status.value


BUCKET_WIDTH = 0.25
"""Width of an f-bucket, as a fraction of the smallest cell cost."""
MAX_BUCKET_COST_RATIO = 64.0
"""Grids whose largest/smallest finite cost exceeds this use the heap search."""
HEAP_QUANTUM = 1e-11
"""Priority rounding of the heap search, relative to the start's heuristic."""
KEPT_CELLS = 1 << 22
"""Grids up to this many cells search in scratch memory kept for the next search (at most
9 bytes a cell, resident where searches went); larger ones get fresh zero pages each time, given
back when the search ends."""

_kept: list[Scratch] = []
"""The scratch kept between searches (none, or one), taken out while a search uses it."""


def _take_scratch(cells: int, rows: int) -> tuple[Scratch, bool]:
    """Scratch for a search, and whether it is to be kept (so cleaned up by the search)."""
    if cells > KEPT_CELLS:
        return Scratch.new(cells, rows), False
    try:
        kept = _kept.pop()
    except IndexError:  # none yet, or another thread holds it
        kept = None
    if kept is not None and kept.fits(cells, rows):
        return kept, True
    size = max(cells, kept.cells if kept is not None else 0)
    return Scratch.new(size, max(rows, kept.rows if kept is not None else 0), huge=True), True


def _check_grid(cost: np.ndarray) -> np.ndarray:
    if not isinstance(cost, np.ndarray) or cost.ndim != 2:
        raise ValueError("cost must be a 2-D numpy array")
    if cost.dtype != np.float32:
        raise ValueError(f"cost must be float32, got {cost.dtype}")
    return np.ascontiguousarray(cost)


def _inside(cell: tuple[int, int], shape: tuple[int, ...]) -> bool:
    return 0 <= cell[0] < shape[0] and 0 <= cell[1] < shape[1]


def plan_verbose(
    cost: np.ndarray,
    start: tuple[int, int],
    goal: tuple[int, int],
    diagonal: bool = True,
) -> PlanResult:
    """Cheapest path from ``start`` to ``goal`` (both ``(row, col)``) with the reason if none.

    Raises ``ValueError`` when ``cost`` is not a 2-D float32 array or holds NaN or values
    that are not positive; out-of-grid or blocked end cells are reported in the result.
    """
    grid = _check_grid(cost)
    s = (int(start[0]), int(start[1]))
    t = (int(goal[0]), int(goal[1]))
    if not _inside(s, grid.shape):
        return PlanResult(PlanStatus.START_OUTSIDE, None, math.inf, 0)
    if not _inside(t, grid.shape):
        return PlanResult(PlanStatus.GOAL_OUTSIDE, None, math.inf, 0)
    if not math.isfinite(grid[s]):
        return PlanResult(PlanStatus.START_BLOCKED, None, math.inf, 0)
    if not math.isfinite(grid[t]):
        return PlanResult(PlanStatus.GOAL_BLOCKED, None, math.inf, 0)
    hmin, hmax = cost_range(grid)
    cols = grid.shape[1]
    si = s[0] * cols + s[1]
    ti = t[0] * cols + t[1]
    if si == ti:
        return PlanResult(PlanStatus.FOUND, np.array([s], dtype=np.int64), 0.0, 0)
    work, keep = _take_scratch(grid.size, grid.shape[0])
    arrays = (work.g, work.parent, work.lo, work.hi, keep)
    if hmax <= MAX_BUCKET_COST_RATIO * hmin:
        delta = BUCKET_WIDTH * hmin
        # largest f increase along one move: step x (cost + hmin), step <= sqrt 2
        span = math.ceil(SQRT2 * (hmax + hmin) / delta) + 3
        g_goal, expanded = search_buckets(
            grid, si, ti, bool(diagonal), float(hmin), delta, span, *arrays
        )
    else:
        dr, dc = abs(s[0] - t[0]), abs(s[1] - t[1])
        h0 = (max(dr, dc) + (SQRT2 - 1.0) * min(dr, dc)) if diagonal else float(dr + dc)
        quantum = HEAP_QUANTUM * h0 * float(hmin)
        g_goal, expanded = search_heap(grid, si, ti, bool(diagonal), float(hmin), quantum, *arrays)
    path = trace(work.parent, si, ti, cols) if math.isfinite(g_goal) else None
    if keep and not _kept:  # the search left it clean (one that raised is left to the collector)
        _kept.append(work)
    if path is None:
        return PlanResult(PlanStatus.NO_PATH, None, math.inf, int(expanded))
    return PlanResult(PlanStatus.FOUND, path, float(g_goal), int(expanded))


def plan(
    cost: np.ndarray,
    start: tuple[int, int],
    goal: tuple[int, int],
    diagonal: bool = True,
) -> np.ndarray | None:
    """Cells ``(n, 2)`` of a cheapest path from ``start`` to ``goal``, or ``None``.

    Use :func:`plan_verbose` to learn why there is no path.
    """
    return plan_verbose(cost, start, goal, diagonal).path


def path_cost(cost: np.ndarray, path: np.ndarray) -> float:
    """Cost of a cell path under the step definition above (corner rule not checked).

    Raises ``ValueError`` if two consecutive cells are not 8-neighbours.
    """
    p = np.asarray(path, dtype=np.int64)
    if len(p) < 2:
        return 0.0
    d = np.abs(np.diff(p, axis=0))
    if (d.max(axis=1) != 1).any():
        raise ValueError("consecutive path cells must be neighbours")
    steps = np.where(d.sum(axis=1) == 2, SQRT2, 1.0)
    entered = cost[p[1:, 0], p[1:, 1]].astype(np.float64)
    return float(np.sum(steps * entered))


def corner_cuts(cost: np.ndarray, path: np.ndarray) -> int:
    """Number of diagonal steps of ``path`` that pass a blocked side cell."""
    p = np.asarray(path, dtype=np.int64)
    n = 0
    for (r0, c0), (r1, c1) in itertools.pairwise(p):
        if (
            r0 != r1
            and c0 != c1
            and (not math.isfinite(cost[r1, c0]) or not math.isfinite(cost[r0, c1]))
        ):
            n += 1
    return n


def warm_up() -> None:
    """Load (or compile) the search once, e.g. at start-up, so the first query is fast."""
    grid = np.ones((3, 3), np.float32)
    plan_verbose(grid, (0, 0), (2, 2))
