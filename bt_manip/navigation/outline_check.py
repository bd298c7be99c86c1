"""Whether outline points placed at a pose keep a clearance: point by point, or a group at once.

The pose search (:mod:`bt_manip.navigation.lattice`) asks, for every pose it reaches, whether
every outline point of the robot, placed at that pose, lies on a grid cell whose clearance is
at least ``need``. :func:`_points_free` answers by looking at the cell under each point.
:func:`_groups_free` gives the same answer with fewer looks: the points are grouped in the
robot's frame (:func:`point_groups`), and a group whose whole neighbourhood on the grid is
known to pass is accepted without looking at its points.

Why a group can be accepted (exact, whatever the grid holds):

- A group's points lie within ``radius`` of its centre ``q`` in the robot's frame, so at a
  pose they lie within ``radius`` of ``q`` placed at that pose (a rotation keeps distances),
  up to the rounding of the few float operations that place a point, far below the
  :data:`PLACEMENT_MARGIN` added to ``radius``. So every point's x lies between the floats
  ``qx - radius`` and ``qx + radius`` (likewise y).
- Finding a point's cell (``- x0``, ``/ res``, ``floor``) is monotone in float arithmetic, so
  every point of the group falls in the box of cells from the cell of ``(qx - radius,
  qy - radius)`` to that of ``(qx + radius, qy + radius)``. The box spans at most
  ``floor(2 radius / res) + 2`` cells a side (one more if rounding lands on a cell's edge),
  which is the ``window`` of :func:`window_cells`.
- On a pose whose groups all lie within ``reach`` of it, and that far from the grid's edges
  (the same monotone argument), every box is on the grid, so no point of a group is off it.
- :class:`WindowMinima` holds, for each cell, the smallest clearance (the same
  ``_clearance_value`` the point check reads) of the ``window`` x ``window`` cells from it up
  and right. If that of the box's lowest cell is at least ``need``, every cell of the box
  passes the point check ``not (clearance < need)``, so every point of the group does: the
  group is accepted.

Any other group is checked point by point as :func:`_points_free` does (off the grid or short
of ``need``: not free). A group is never refused on its window alone, and the answer does not
depend on the order of the points, so it is that of :func:`_points_free` exactly. (A cell
whose value is NaN passes the point check; the window minimum leaves NaN out, so it passes
here too.)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from numba import types
from numba.extending import overload

TILE_CELLS = 32
"""Side (cells) of the tiles of grid whose window minima are found at once."""

GROUP_SIZE = 0.2
"""Side (m) of the squares of the robot's frame whose points form one group."""

PLACEMENT_MARGIN = 1e-6
"""Added to a group's radius (m): far more than the rounding of placing a point at a pose."""


def _clearance_value(value: float | int, res: float) -> float:
    """A cell's clearance (m) from its entry in a clearance grid (m) or in a grid of squared
    cell distances (integers, :func:`bt_manip.navigation.distance.squared_distances`)."""
    if isinstance(value, float | np.floating):
        return float(value)
    return math.sqrt(float(value)) * res - res / math.sqrt(2.0)


@overload(_clearance_value, jit_options={"cache": True})  # type: ignore[typeddict-unknown-key]  # numba stubs: jit_options lack "cache"
def _clearance_value_jit(value, res):  # type: ignore[no-untyped-def]  # numba wants them bare
    """The compiled :func:`_clearance_value` for the cell type of the grid."""
    if isinstance(value, types.Float):
        return lambda value, res: value
    # the float64 operations of costmap.clearance_of, so the same value to the last bit
    return lambda value, res: math.sqrt(float(value)) * res - res / math.sqrt(2.0)


@numba.njit(cache=True)
def _points_free(
    clear: np.ndarray,
    x0: float,
    y0: float,
    res: float,
    pts: np.ndarray,
    x: float,
    y: float,
    th: float,
    need: float,
) -> bool:
    """Whether every point of ``pts`` (robot frame) placed at pose (x, y, th) lies on a cell of
    ``clear`` (origin (x0, y0), cells of ``res`` m) with a clearance of at least ``need``."""
    rows, cols = clear.shape
    c = math.cos(th)
    s = math.sin(th)
    for k in range(pts.shape[0]):
        px = x + c * pts[k, 0] - s * pts[k, 1]
        py = y + s * pts[k, 0] + c * pts[k, 1]
        col = math.floor((px - x0) / res)
        row = math.floor((py - y0) / res)
        if row < 0 or row >= rows or col < 0 or col >= cols:
            return False
        if _clearance_value(clear[row, col], res) < need:
            return False
    return True


@dataclass(frozen=True)
class PointGroups:
    """Outline points sorted into groups (robot frame): the points of group ``j`` are
    ``points[first[j]:first[j + 1]]``, within ``radius[j]`` of ``centre[j]``; ``reach`` is
    the largest ``|centre| + radius``."""

    points: np.ndarray
    first: np.ndarray
    centre: np.ndarray
    radius: np.ndarray
    reach: float


def point_groups(pts: np.ndarray, size: float = GROUP_SIZE) -> PointGroups:
    """The points ``pts`` (n, 2) grouped by the ``size`` m square of the robot's frame they lie
    in, groups and the points in each in the order of the points' first appearance; a group's
    centre is the middle of its points' bounding box and its radius the largest distance from
    there to one of its points, plus :data:`PLACEMENT_MARGIN`."""
    pts = np.asarray(pts, dtype=np.float64).reshape(-1, 2)
    if len(pts) == 0:
        empty = np.zeros((0, 2))
        return PointGroups(empty, np.zeros(1, np.int64), empty, np.zeros(0), 0.0)
    square = np.floor(pts / size).astype(np.int64)
    _, first_seen, label = np.unique(square, axis=0, return_index=True, return_inverse=True)
    rank = np.argsort(np.argsort(first_seen, kind="stable"), kind="stable")[label.reshape(-1)]
    order = np.argsort(rank, kind="stable")
    points = np.ascontiguousarray(pts[order])
    counts = np.bincount(rank)
    first = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    centre = np.empty((len(counts), 2))
    radius = np.empty(len(counts))
    for j in range(len(counts)):
        group = points[first[j] : first[j + 1]]
        centre[j] = 0.5 * (group.min(axis=0) + group.max(axis=0))
        radius[j] = float(np.hypot(*(group - centre[j]).T).max()) + PLACEMENT_MARGIN
    reach = float((np.hypot(*centre.T) + radius).max()) + PLACEMENT_MARGIN
    return PointGroups(points, first, centre, radius, reach)


def window_cells(groups: PointGroups, res: float) -> int:
    """Side (cells) of a window that holds the box of cells of any group at any pose: a box
    spans at most ``floor(2 radius / res) + 2`` cells a side, one more if rounding lands on a
    cell's edge."""
    if len(groups.radius) == 0:
        return 1
    return math.floor(2.0 * float(groups.radius.max()) / res) + 3


class WindowMinima:
    """For each cell (r, c) of a grid, the smallest clearance of the ``window`` x ``window``
    cells from it up and right (rows r.., columns c.., cut at the grid's edges), found a tile
    of :data:`TILE_CELLS` cells a side at a time when first asked for (:func:`_fill_tile`).
    ``low`` is allocated lazily by the system, so a large map costs memory only where the
    search looks."""

    def __init__(self, shape: tuple[int, int], window: int) -> None:
        rows, cols = shape
        self.window = window
        self.low = np.empty((max(1, rows), max(1, cols)))
        self.done = np.zeros((-(-max(1, rows) // TILE_CELLS), -(-max(1, cols) // TILE_CELLS)),
                             np.bool_)


@numba.njit(cache=True)
def _fill_tile(
    clear: np.ndarray, res: float, low: np.ndarray, window: int, tr: int, tc: int
) -> None:
    """Fill the window minima (see :class:`WindowMinima`) of tile (tr, tc): minima along rows
    over ``window`` columns, then of those along columns. NaN cells are left out (a window of
    NaN only gets ``inf``), since a NaN cell passes the point check."""
    rows, cols = clear.shape
    r0 = tr * TILE_CELLS
    c0 = tc * TILE_CELLS
    r1 = min(rows, r0 + TILE_CELLS)
    c1 = min(cols, c0 + TILE_CELLS)
    r_end = min(rows, r1 + window - 1)
    along = np.empty((r_end - r0, c1 - c0))
    for r in range(r0, r_end):
        for c in range(c0, c1):
            least = np.inf
            for k in range(c, min(cols, c + window)):
                v = _clearance_value(clear[r, k], res)
                if v < least:
                    least = v
            along[r - r0, c - c0] = least
    for r in range(r0, r1):
        for c in range(c0, c1):
            least = np.inf
            for k in range(r, min(rows, r + window)):
                v = along[k - r0, c - c0]
                if v < least:
                    least = v
            low[r, c] = least


@numba.njit(cache=True)
def _groups_free(
    clear: np.ndarray,
    x0: float,
    y0: float,
    res: float,
    points: np.ndarray,
    first: np.ndarray,
    centre: np.ndarray,
    radius: np.ndarray,
    reach: float,
    low: np.ndarray,
    done: np.ndarray,
    window: int,
    x: float,
    y: float,
    c: float,
    s: float,
    need: float,
) -> bool:
    """:func:`_points_free` of ``points`` at pose (x, y) with heading cosine ``c`` and sine
    ``s`` (``math.cos``/``math.sin`` of the heading), the same answer with fewer looks: on a
    pose whose groups all lie on the grid (within ``reach`` of (x, y)), a group whose window of
    cells keeps ``need`` is accepted whole (see the module); the others are checked point by
    point."""
    rows, cols = clear.shape
    inside = (
        math.floor((x - reach - x0) / res) >= 0
        and math.floor((y - reach - y0) / res) >= 0
        and math.floor((x + reach - x0) / res) < cols
        and math.floor((y + reach - y0) / res) < rows
    )
    for j in range(first.shape[0] - 1):
        if inside:
            qx = x + c * centre[j, 0] - s * centre[j, 1]
            qy = y + s * centre[j, 0] + c * centre[j, 1]
            c_lo = math.floor((qx - radius[j] - x0) / res)
            r_lo = math.floor((qy - radius[j] - y0) / res)
            tr = r_lo // TILE_CELLS
            tc = c_lo // TILE_CELLS
            if not done[tr, tc]:
                _fill_tile(clear, res, low, window, tr, tc)
                done[tr, tc] = True
            if low[r_lo, c_lo] >= need:
                continue
        for k in range(first[j], first[j + 1]):
            px = x + c * points[k, 0] - s * points[k, 1]
            py = y + s * points[k, 0] + c * points[k, 1]
            col = math.floor((px - x0) / res)
            row = math.floor((py - y0) / res)
            if row < 0 or row >= rows or col < 0 or col >= cols:
                return False
            if _clearance_value(clear[row, col], res) < need:
                return False
    return True
