"""The floor as an occupancy grid: free spots for the robot and the stock, and routes.

Walls (between their passages), window sills and lintels, furniture and the stock's stands are
painted as blocked cells of a 5 cm grid over the building's extent (with a margin around it).
A robot that is ``w`` wide (with what it carries) can be in a cell whose distance to the
nearest blocked cell is at least ``w / 2``, so it passes a door exactly when the door is wider
than ``w``; two places are joined when such cells connect them. Results are as fine as the
grid (5 cm).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from bt_manip.errors import InputError

RESOLUTION = 0.05
"""Cell size (m)."""
MARGIN = 2.0
"""Free floor (m) around the building's extent (a robot may go round the outside)."""
NEAR_TRIES = 8
"""Cells :meth:`FloorGrid.nearest_clear` tries one by one before computing clearances."""
_UNDECIDED = object()
MAX_CELLS = 25_000_000
"""Cells at most, as for navigation grids (250 m x 250 m at 5 cm)."""


@dataclass(frozen=True)
class Rect:
    """A rectangle on the floor: centre, length along ``yaw``, width across it."""

    x: float
    y: float
    length: float
    width: float
    yaw: float = 0.0

    def grown(self, d: float) -> Rect:
        return Rect(self.x, self.y, self.length + 2 * d, self.width + 2 * d, self.yaw)


class FloorGrid:
    """Blocked cells, door cells and clearances over ``extent`` (xmin, ymin, xmax, ymax)."""

    def __init__(
        self, extent: tuple[float, float, float, float], resolution: float = RESOLUTION
    ) -> None:
        xmin, ymin, xmax, ymax = extent
        self.res = resolution
        self.x0 = xmin - MARGIN
        self.y0 = ymin - MARGIN
        nx = math.ceil((xmax - xmin + 2 * MARGIN) / resolution)
        ny = math.ceil((ymax - ymin + 2 * MARGIN) / resolution)
        if nx * ny > MAX_CELLS:
            raise InputError.single(
                "bt-manip bim",
                None,
                f"the building spans {xmax - xmin:.1f} m x {ymax - ymin:.1f} m: its floor grid "
                f"would have {nx * ny} cells of {resolution} m, more than the limit of {MAX_CELLS}",
            )
        self.blocked = np.zeros((ny, nx), dtype=bool)
        self.doors = np.zeros((ny, nx), dtype=np.int32)
        self._clearance: np.ndarray | None = None
        self._labels: dict[float, np.ndarray] = {}
        self._trees: dict[tuple[float, ...], tuple[np.ndarray, np.ndarray]] = {}

    # -- painting --------------------------------------------------------------------------
    def cells(self, rect: Rect) -> tuple[np.ndarray, np.ndarray]:
        """Row and column indices of the cells whose centres lie in ``rect``."""
        found = self._window(rect)
        if found is None:
            return np.zeros(0, dtype=int), np.zeros(0, dtype=int)
        j0, i0, inside = found
        rows, cols = np.nonzero(inside)
        return rows + j0, cols + i0

    def _window(self, rect: Rect) -> tuple[int, int, np.ndarray] | None:
        """The first row and column of the grid's window round ``rect``, and which cells of
        the window have their centres in ``rect``; None when the window is empty."""
        c, s = math.cos(rect.yaw), math.sin(rect.yaw)
        ex = abs(c) * rect.length / 2 + abs(s) * rect.width / 2
        ey = abs(s) * rect.length / 2 + abs(c) * rect.width / 2
        ny, nx = self.blocked.shape
        i0 = max(math.floor((rect.x - ex - self.x0) / self.res), 0)
        i1 = min(math.ceil((rect.x + ex - self.x0) / self.res), nx)
        j0 = max(math.floor((rect.y - ey - self.y0) / self.res), 0)
        j1 = min(math.ceil((rect.y + ey - self.y0) / self.res), ny)
        if i0 >= i1 or j0 >= j1:
            return None
        xs = self.x0 + (np.arange(i0, i1) + 0.5) * self.res - rect.x
        ys = self.y0 + (np.arange(j0, j1) + 0.5) * self.res - rect.y
        gx, gy = xs[np.newaxis, :], ys[:, np.newaxis]  # broadcast to the window's cells
        u = gx * c + gy * s
        v = -gx * s + gy * c
        inside = (np.abs(u) <= rect.length / 2) & (np.abs(v) <= rect.width / 2)
        return j0, i0, inside

    def block(self, rect: Rect) -> None:
        found = self._window(rect)
        if found is not None:
            j0, i0, inside = found
            self.blocked[j0:j0 + inside.shape[0], i0:i0 + inside.shape[1]] |= inside
        self._clearance = None
        self._labels.clear()
        self._trees.clear()

    def mark_door(self, rect: Rect, index: int) -> None:
        """Label the cells of door ``index`` (0-based) so routes can name the doors they use."""
        rows, cols = self.cells(rect)
        self.doors[rows, cols] = index + 1

    def is_free(self, rect: Rect) -> bool:
        """No blocked cell in ``rect``, and ``rect`` lies on the grid."""
        if not self._inside(rect):
            return False
        rows, cols = self.cells(rect)
        return len(rows) > 0 and not bool(self.blocked[rows, cols].any())

    def _inside(self, rect: Rect) -> bool:
        ny, nx = self.blocked.shape
        c, s = math.cos(rect.yaw), math.sin(rect.yaw)
        ex = abs(c) * rect.length / 2 + abs(s) * rect.width / 2
        ey = abs(s) * rect.length / 2 + abs(c) * rect.width / 2
        return (
            rect.x - ex >= self.x0
            and rect.y - ey >= self.y0
            and rect.x + ex <= self.x0 + nx * self.res
            and rect.y + ey <= self.y0 + ny * self.res
        )

    # -- clearances and routes ---------------------------------------------------------------
    def clearance(self) -> np.ndarray:
        """Distance (m) from each cell to the nearest blocked cell's edge (0 when blocked)."""
        if self._clearance is None:
            from scipy.ndimage import distance_transform_edt

            d = distance_transform_edt(~self.blocked) * self.res - self.res / 2
            self._clearance = np.maximum(d, 0.0)
        return self._clearance

    def centre(self, row: int, col: int) -> tuple[float, float]:
        return (self.x0 + (col + 0.5) * self.res, self.y0 + (row + 0.5) * self.res)

    def nearest_clear(
        self, x: float, y: float, half_width: float, within: Rect | None = None
    ) -> tuple[float, float] | None:
        """The cell centre nearest (x, y) with ``half_width`` of clearance (inside ``within``).

        Before the grid's clearances are needed for anything else, the cells of ``within``
        are tried nearest first, each against the blocked cells round it only
        (:meth:`_clear_at`), rather than computing every cell's clearance."""
        if self._clearance is None and within is not None and half_width > 0:
            found = self._nearest_clear_within(x, y, half_width, within)
            if found is not _UNDECIDED:
                return found if isinstance(found, tuple) else None
        ok = self.clearance() >= half_width
        if within is not None:
            mask = np.zeros_like(ok)
            rows, cols = self.cells(within)
            mask[rows, cols] = True
            ok &= mask
        rows, cols = np.nonzero(ok)
        if len(rows) == 0:
            return None
        xs = self.x0 + (cols + 0.5) * self.res
        ys = self.y0 + (rows + 0.5) * self.res
        k = int(np.argmin((xs - x) ** 2 + (ys - y) ** 2))
        return (float(xs[k]), float(ys[k]))

    def _nearest_clear_within(
        self, x: float, y: float, half_width: float, within: Rect
    ) -> tuple[float, float] | object | None:
        """:meth:`nearest_clear` inside ``within`` without the whole grid's clearances: the
        same cell (the nearest, the first in row order among equally near ones); or
        ``_UNDECIDED`` on a grid without a blocked cell (where the distance transform has no
        answer to match) or for a point that is not finite.

        The nearest :data:`NEAR_TRIES` cells are tried one by one (:meth:`_clear_at`), then
        the cells of ever wider discs round (x, y) all at once (:meth:`_clear_cells`)."""
        found = self._window(within)
        if found is None:
            return None
        if not self.blocked.any() or not (math.isfinite(x) and math.isfinite(y)):
            return _UNDECIDED
        j0, i0, inside = found
        rows, cols = np.nonzero(inside)
        rows, cols = rows + j0, cols + i0
        xs = self.x0 + (cols + 0.5) * self.res
        ys = self.y0 + (rows + 0.5) * self.res
        near = (xs - x) ** 2 + (ys - y) ** 2
        # a blocked cell this many cells away (or farther) leaves a cell clear
        reach = math.ceil((half_width + self.res) / self.res) + 2
        for k in _nearest_first(near, NEAR_TRIES):
            if self._clear_at(int(rows[k]), int(cols[k]), reach) >= half_width:
                return (float(xs[k]), float(ys[k]))
        # then discs round (x, y) growing twice as wide each time, up to the whole rectangle:
        # the nearest clear cell of a disc is the rectangle's, as every cell outside the disc
        # is farther
        radius = (reach + 4) * self.res
        while True:
            some = np.flatnonzero(near <= radius * radius)
            whole = len(some) == len(near)
            ok = some[self._clear_cells(rows[some], cols[some], half_width, reach)]
            if len(ok):
                k = int(ok[int(np.argmin(near[ok]))])
                return (float(xs[k]), float(ys[k]))
            if whole:
                return None
            radius *= 2

    def _clear_cells(self, rows: np.ndarray, cols: np.ndarray, half_width: float,
                     reach: int) -> np.ndarray:
        """Which of the cells have ``half_width`` of clearance, as :meth:`clearance` tells,
        from the clearances of their bounding window grown by ``reach`` cells (a blocked cell
        beyond it leaves every one of them clear, one within it is as near as on the whole
        grid)."""
        if len(rows) == 0:
            return np.zeros(0, dtype=bool)
        ny, nx = self.blocked.shape
        r0, c0 = max(int(rows.min()) - reach, 0), max(int(cols.min()) - reach, 0)
        sub = self.blocked[r0:min(int(rows.max()) + reach + 1, ny),
                           c0:min(int(cols.max()) + reach + 1, nx)]
        if not sub.any():
            return np.ones(len(rows), dtype=bool)
        from scipy.ndimage import distance_transform_edt

        d = distance_transform_edt(~sub) * self.res - self.res / 2
        clear: np.ndarray = np.maximum(d, 0.0)[rows - r0, cols - c0] >= half_width
        return clear

    def _clear_at(self, row: int, col: int, reach: int) -> float:
        """The cell's clearance as :meth:`clearance` gives it (the same operations on the
        same squared distance to the nearest blocked cell), when it is less than ``reach``
        cells; else at least that."""
        ny, nx = self.blocked.shape
        r0, c0 = max(row - reach, 0), max(col - reach, 0)
        near = self.blocked[r0:min(row + reach + 1, ny), c0:min(col + reach + 1, nx)]
        br, bc = np.nonzero(near)
        if len(br) == 0:
            return reach * self.res
        d2 = int(((br + (r0 - row)) ** 2 + (bc + (c0 - col)) ** 2).min())
        if d2 > reach * reach:
            return reach * self.res  # a farther blocked cell, outside the window, may be nearer
        return max(math.sqrt(float(d2)) * self.res - self.res / 2, 0.0)

    def _near(
        self, x: float, y: float, reach: float, ok: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        rows, cols = self.cells(Rect(x, y, 2 * reach, 2 * reach))
        cx = self.x0 + (cols + 0.5) * self.res - x
        cy = self.y0 + (rows + 0.5) * self.res - y
        keep = (cx * cx + cy * cy <= reach * reach) & ok[rows, cols]
        return rows[keep], cols[keep]

    def joined(
        self, a: tuple[float, float], b: tuple[float, float], half_width: float, reach: float
    ) -> bool:
        """Whether a robot ``2 * half_width`` wide can go from within ``reach`` of ``a`` to
        within ``reach`` of ``b``."""
        from scipy.ndimage import label

        key = round(half_width, 4)
        ok = self.clearance() >= half_width
        if key not in self._labels:
            self._labels[key] = label(ok)[0]
        labels = self._labels[key]
        ra, ca = self._near(a[0], a[1], reach, ok)
        rb, cb = self._near(b[0], b[1], reach, ok)
        return bool(set(labels[ra, ca].tolist()) & set(labels[rb, cb].tolist()))

    def _route_tree(
        self, a: tuple[float, float], half_width: float, reach: float, ok: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Breadth-first search from the cells within ``reach`` of ``a``: each cell's parent
        (-1 for a start, -2 not reached) and distance in steps (-1 not reached); the last
        search is kept for the next route from the same start with the same width."""
        key = (round(a[0], 4), round(a[1], 4), round(half_width, 4), round(reach, 4))
        if key in self._trees:
            return self._trees[key]
        ny, nx = ok.shape
        flat_ok = ok.ravel()
        parent = np.full(ny * nx, -2, dtype=np.int32)  # at most 25 million cells
        dist = np.full(ny * nx, -1, dtype=np.int32)
        ra, ca = self._near(a[0], a[1], reach, ok)
        queue: deque[int] = deque()
        for idx in (ra * nx + ca).tolist():
            parent[idx] = -1
            dist[idx] = 0
            queue.append(idx)
        while queue:
            idx = queue.popleft()
            r, c = divmod(idx, nx)
            d = dist[idx] + 1
            for nb, valid in ((idx - nx, r > 0), (idx + nx, r < ny - 1),
                              (idx - 1, c > 0), (idx + 1, c < nx - 1)):
                if valid and flat_ok[nb] and parent[nb] == -2:
                    parent[nb] = idx
                    dist[nb] = d
                    queue.append(nb)
        self._trees = {key: (parent, dist)}  # the last search only: it takes 8 bytes a cell
        return parent, dist

    def doors_on_route(
        self, a: tuple[float, float], b: tuple[float, float], half_width: float, reach: float,
        start_reach: float | None = None,
    ) -> list[int] | None:
        """Doors (0-based indices) crossed by a shortest route (in cells) from near ``a``
        (within ``start_reach``, default ``reach``) to near ``b`` (within ``reach``) for a robot
        ``2 * half_width`` wide, in order; None if there is none. The search from ``a`` is kept
        for the next route from there with the same width."""
        ok = self.clearance() >= half_width
        near_a = reach if start_reach is None else start_reach
        parent, dist = self._route_tree(a, half_width, near_a, ok)
        rb, cb = self._near(b[0], b[1], reach, ok)
        if len(rb) == 0:
            return None
        nx = ok.shape[1]
        ends = rb * nx + cb
        ends = ends[dist[ends] >= 0]
        if len(ends) == 0:
            return None
        found = int(ends[np.argmin(dist[ends])])
        doors = self.doors.ravel()
        out: list[int] = []
        idx = found
        while idx >= 0:
            d = int(doors[idx])
            if d and (not out or out[-1] != d - 1):
                out.append(d - 1)
            idx = int(parent[idx])
        return out[::-1]


def _nearest_first(values: np.ndarray, count: int) -> list[int]:
    """The indices of the ``count`` least of ``values``, least first, equal ones in index
    order: the start of ``np.argsort(values, kind="stable")`` without sorting them all."""
    if len(values) <= count:
        return [int(k) for k in np.argsort(values, kind="stable")]
    bound = np.partition(values, count - 1)[count - 1]
    few = np.flatnonzero(values <= bound)
    return [int(k) for k in few[np.argsort(values[few], kind="stable")][:count]]
