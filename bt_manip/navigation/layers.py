"""Costmap layers as Nav2 composes them: a static layer, an obstacle layer, and inflation.

A robot that localises (``--localize``) does not know where the movable objects are: it plans
on what its map holds and what its laser has seen. As in Nav2's ``costmap_2d``:

- the **static layer** is the occupancy grid of the world's walls and furniture (what the
  localisation's map holds), rasterised once by the
  :class:`~bt_manip.navigation.navigator.Navigator`;
- an :class:`ObstacleLayer` holds the cells the laser has *marked*: each scan first clears, by
  ray tracing, the cells each beam passed through up to its return (at most
  ``raytrace_max_range``), then marks the cell of each return nearer than
  ``obstacle_max_range``. A beam with no return clears nothing (Nav2's ``inf_is_valid: false``),
  so a mark left where nothing lies behind it (a doorway into open space) stays until a beam
  ends beyond it or a clear node forgets it. The scan is laid in the map frame from the pose
  the robot *believes* it has, so the marks carry the localisation's error, as a real robot's
  do;
- the **inflation layer** is :class:`~bt_manip.navigation.costmap.CostMap`, applied to the
  union of the static grid and the marks (:func:`compose`).

The marks are what a planar laser sees: the cut of the world at its scan plane. An object that
stays below the plane (a flat panel lying on its stand) or above it (a table top on thin legs
the beams miss) is never marked, as on a real robot with one planar laser (Nav2 users add a
depth camera's voxel layer for those).

Ray tracing walks each beam's cells with Bresenham's line in a compiled kernel: a scan of 541
beams costs a few tens of microseconds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from bt_manip.navigation.grid import OccupancyGrid


@dataclass(frozen=True)
class ObstacleLayerOptions:
    """Nav2's obstacle layer parameters (the same names and defaults)."""

    obstacle_max_range: float = 2.5
    """Returns farther than this (m) from the sensor mark nothing."""
    obstacle_min_range: float = 0.0
    """Returns nearer than this (m) mark nothing."""
    raytrace_max_range: float = 3.0
    """A beam clears the cells it crosses up to this distance (m) from the sensor."""

    def __post_init__(self) -> None:
        for name in ("obstacle_max_range", "obstacle_min_range", "raytrace_max_range"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name} must be a finite number >= 0, got {value}")


@numba.njit(cache=True)
def _clear_rays(marked: np.ndarray, r0: int, c0: int, r1: np.ndarray, c1: np.ndarray,
                out: np.ndarray) -> int:
    """Clear the cells on Bresenham's line from (r0, c0) to each (r1[k], c1[k]), both ends
    included (cells outside the grid are skipped); their flat indices are written to ``out``
    (as many as it holds), and their number returned."""
    rows, cols = marked.shape
    cleared = 0
    for k in range(r1.shape[0]):
        dr = r1[k] - r0
        dc = c1[k] - c0
        ar = abs(dr)
        ac = abs(dc)
        sr = 1 if dr > 0 else -1
        sc = 1 if dc > 0 else -1
        r = r0
        c = c0
        major = max(ar, ac)
        minor = min(ar, ac)
        err = major // 2
        for _ in range(major + 1):
            if 0 <= r < rows and 0 <= c < cols and marked[r, c]:
                marked[r, c] = False
                if cleared < out.shape[0]:
                    out[cleared] = r * cols + c
                cleared += 1
            err -= minor
            if ac >= ar:
                if err < 0:
                    r += sr
                    err += major
                c += sc
            else:
                if err < 0:
                    c += sc
                    err += major
                r += sr
    return cleared


class ObstacleLayer:
    """Cells marked by the laser on a grid of ``shape`` cells of side ``resolution`` whose
    corner is ``origin`` (the static grid's frame: cell ``(row, col)`` as in
    :class:`~bt_manip.navigation.grid.OccupancyGrid`).

    ``version`` grows by one each time the marks change, so that a cost map built on them
    knows when to be built again.
    """

    def __init__(
        self,
        origin: tuple[float, float],
        resolution: float,
        shape: tuple[int, int],
        options: ObstacleLayerOptions = ObstacleLayerOptions(),
    ) -> None:
        self.origin = (float(origin[0]), float(origin[1]))
        self.resolution = float(resolution)
        self.options = options
        self.marked = np.zeros(shape, bool)
        self.version = 0

    @classmethod
    def like(cls, grid: OccupancyGrid,
             options: ObstacleLayerOptions = ObstacleLayerOptions()) -> ObstacleLayer:
        """An empty layer in ``grid``'s frame."""
        return cls(grid.origin, grid.resolution, grid.shape, options)

    @property
    def shape(self) -> tuple[int, int]:
        return self.marked.shape  # type: ignore[return-value]

    @property
    def count(self) -> int:
        """Marked cells."""
        return int(np.count_nonzero(self.marked))

    def _cells(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rows = np.floor((y - self.origin[1]) / self.resolution).astype(np.int64)
        cols = np.floor((x - self.origin[0]) / self.resolution).astype(np.int64)
        return rows, cols

    def update(
        self,
        sensor: tuple[float, float, float],
        angles: np.ndarray,
        ranges: np.ndarray,
        returned: np.ndarray,
    ) -> bool:
        """Take one scan: ``sensor`` is the laser's (x, y, heading) in the map frame, beam
        ``k`` points at ``angles[k]`` (rad, sensor frame) and reads ``ranges[k]`` (m);
        ``returned[k]`` is False for a beam that met nothing (it clears and marks nothing).

        Clears along every returned beam, then marks the returns within range (see the module
        docstring). True when the marks changed.
        """
        o = self.options
        sx, sy, heading = sensor
        a = np.asarray(angles, float)[returned] + heading
        r = np.asarray(ranges, float)[returned]
        ok = np.isfinite(r) & (r >= 0.0)
        a, r = a[ok], r[ok]
        cos, sin = np.cos(a), np.sin(a)
        reach = np.minimum(r, o.raytrace_max_range)
        r0, c0 = self._cells(np.array([sx]), np.array([sy]))
        er, ec = self._cells(sx + reach * cos, sy + reach * sin)
        # a cell a beam clears may be marked again by a return: what changed is what was
        # cleared and not marked again, and what was marked anew
        cells = max(1, int(np.abs(er - r0[0]).max(initial=0) + np.abs(ec - c0[0]).max(initial=0)))
        out = np.empty(len(er) * (cells + 1), np.int64)
        n = _clear_rays(self.marked, int(r0[0]), int(c0[0]), er, ec, out)
        near = (r < o.obstacle_max_range) & (r >= o.obstacle_min_range)
        mr, mc = self._cells(sx + r[near] * cos[near], sy + r[near] * sin[near])
        rows, cols = self.shape
        inside = (mr >= 0) & (mr < rows) & (mc >= 0) & (mc < cols)
        mr, mc = mr[inside], mc[inside]
        cleared = out[:n]
        was = self.marked[mr, mc] | np.isin(mr * cols + mc, cleared)
        self.marked[mr, mc] = True
        changed = bool((~was).any()) or (n > 0 and not self.marked.reshape(-1)[cleared].all())
        if changed:
            self.version += 1
        return changed

    def clear(self, where: np.ndarray | None = None) -> int:
        """Forget the marks (all of them, or those where the bool grid ``where`` is True); the
        number of marks forgotten."""
        if where is None:
            n = self.count
            self.marked[:] = False
        else:
            n = int(np.count_nonzero(self.marked & where))
            self.marked[where] = False
        if n:
            self.version += 1
        return n

    def square(self, x: float, y: float, half: float) -> np.ndarray:
        """Bool grid: the cells whose centre lies within the square of half side ``half``
        centred on (x, y)."""
        rows, cols = self.shape
        xs = self.origin[0] + (np.arange(cols) + 0.5) * self.resolution
        ys = self.origin[1] + (np.arange(rows) + 0.5) * self.resolution
        inside: np.ndarray = (np.abs(ys - y)[:, None] <= half) & (np.abs(xs - x)[None, :] <= half)
        return inside

    def points(self) -> np.ndarray:
        """The marked cells' centres (n, 2), map frame."""
        r, c = np.nonzero(self.marked)
        return np.column_stack([self.origin[0] + (c + 0.5) * self.resolution,
                                self.origin[1] + (r + 0.5) * self.resolution])


def compose(static: OccupancyGrid, layer: ObstacleLayer) -> OccupancyGrid:
    """The static grid with the layer's marks drawn in (``static`` itself when nothing is
    marked: it is never drawn on). Raises ValueError when the two frames differ."""
    if layer.shape != static.shape or layer.origin != static.origin or (
            layer.resolution != static.resolution):
        raise ValueError(
            f"the obstacle layer ({layer.shape} cells at {layer.origin}) is not in the static "
            f"grid's frame ({static.shape} cells at {static.origin})")
    if not layer.marked.any():
        return static
    return OccupancyGrid(static.origin, static.resolution, static.occupied | layer.marked,
                         static.band)
