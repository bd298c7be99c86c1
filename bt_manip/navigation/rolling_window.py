"""The local costmap: an obstacle layer kept only in a square window that moves with the robot.

Nav2's local costmap is a ``rolling_window``: a grid of ``width`` x ``height`` metres (5 m by
default) centred on the robot, whose obstacle layer is fed by the same scans as the global
costmap's but holds its own marks. bt-manip keeps the window's marks on the static grid's
frame (:class:`~bt_manip.navigation.layers.ObstacleLayer`) and, after every update, forgets
those that fell outside the window round the robot's believed position: a mark the robot drove
away from is gone, as it is from Nav2's window when it rolls on. Clearing the local costmap
(ClearEntireCostmap on ``local_costmap/...``) leaves the global costmap's marks as they are.

The window is read by the path followers' "is the path ahead blocked?" checks
(:meth:`RollingWindow.first_blocked`); the planners read the global costmap.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bt_manip.navigation.layers import ObstacleLayer, ObstacleLayerOptions


@dataclass(frozen=True)
class RollingWindowOptions:
    """Nav2's local costmap size (its ``width`` and ``height``, m)."""

    width: float = 5.0
    height: float = 5.0

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"the local costmap's {name} must be a number > 0, got {value}")


class RollingWindow:
    """The local costmap's obstacle layer, kept within a window round the robot (see the
    module docstring)."""

    def __init__(self, layer: ObstacleLayer,
                 options: RollingWindowOptions = RollingWindowOptions()) -> None:
        self.layer = layer
        self.options = options
        self.centre: tuple[float, float] | None = None

    @classmethod
    def like(cls, other: ObstacleLayer, options: RollingWindowOptions = RollingWindowOptions(),
             layer_options: ObstacleLayerOptions | None = None) -> RollingWindow:
        """An empty window on ``other``'s frame (with ``other``'s options unless given)."""
        return cls(ObstacleLayer(other.origin, other.resolution, other.shape,
                                 layer_options or other.options), options)

    def bounds(self) -> tuple[slice, slice] | None:
        """The rows and columns of the window now (None before the first update)."""
        if self.centre is None:
            return None
        layer = self.layer
        res = layer.resolution
        x, y = self.centre
        rows, cols = layer.shape
        c0 = max(0, math.floor((x - self.options.width / 2 - layer.origin[0]) / res))
        c1 = min(cols, math.ceil((x + self.options.width / 2 - layer.origin[0]) / res))
        r0 = max(0, math.floor((y - self.options.height / 2 - layer.origin[1]) / res))
        r1 = min(rows, math.ceil((y + self.options.height / 2 - layer.origin[1]) / res))
        return slice(r0, max(r0, r1)), slice(c0, max(c0, c1))

    def move_to(self, x: float, y: float, reach: float = 0.0) -> None:
        """Centre the window on (x, y) and forget the marks outside it.

        Marks lie only in the window after each move, and a scan marks only within ``reach``
        (m) of (x, y): the cells looked at are those of the old window, the new one and that
        reach (the whole grid the first time), not the whole grid."""
        old = self.bounds()
        self.centre = (float(x), float(y))
        window = self.bounds()
        assert window is not None
        layer = self.layer
        rows, cols = layer.shape
        if old is None:
            around = (slice(0, rows), slice(0, cols))
        else:
            res = layer.resolution
            r0 = math.floor((y - reach - layer.origin[1]) / res)
            r1 = math.ceil((y + reach - layer.origin[1]) / res) + 1
            c0 = math.floor((x - reach - layer.origin[0]) / res)
            c1 = math.ceil((x + reach - layer.origin[0]) / res) + 1
            r0 = max(0, min(r0, old[0].start, window[0].start))
            r1 = min(rows, max(r1, old[0].stop, window[0].stop))
            c0 = max(0, min(c0, old[1].start, window[1].start))
            c1 = min(cols, max(c1, old[1].stop, window[1].stop))
            around = (slice(r0, max(r0, r1)), slice(c0, max(c0, c1)))
        sub = layer.marked[around]
        if not sub.any():
            return
        keep = np.zeros(sub.shape, bool)
        keep[window[0].start - around[0].start:window[0].stop - around[0].start,
             window[1].start - around[1].start:window[1].stop - around[1].start] = True
        drop = sub & ~keep
        if drop.any():
            sub[drop] = False  # a view of the layer's grid
            layer.version += 1

    def update(self, robot_xy: tuple[float, float], sensor: tuple[float, float, float],
               angles: np.ndarray, ranges: np.ndarray, returned: np.ndarray) -> bool:
        """Roll the window to the robot, then take the scan (see
        :meth:`ObstacleLayer.update`); True when marks were made or forgotten (the layer's
        ``version`` moved)."""
        before = self.layer.version
        self.move_to(*robot_xy)
        self.layer.update(sensor, angles, ranges, returned)
        # returns beyond the window's edge are not kept
        reach = math.hypot(sensor[0] - robot_xy[0], sensor[1] - robot_xy[1]) + (
            self.layer.options.obstacle_max_range + 2 * self.layer.resolution)
        self.move_to(*robot_xy, reach=reach)
        return self.layer.version != before

    def first_in_way(self, points: np.ndarray, half_width: float) -> int | None:
        """Index of the first of ``points`` where a footprint of ``half_width`` (m) would
        touch a marked cell: within the half width plus half a cell's diagonal of the cell's
        centre (:meth:`first_blocked`); None when none is."""
        return self.first_blocked(points, half_width + self.layer.resolution / math.sqrt(2.0))

    def first_blocked(self, points: np.ndarray, reach: float) -> int | None:
        """Index of the first of ``points`` (n, 2; map frame) within ``reach`` (m) of a marked
        cell's centre, or None when none is."""
        window = self.bounds()
        if window is None or len(points) == 0:
            return None
        sub = self.layer.marked[window]
        r, c = np.nonzero(sub)
        if r.size == 0:
            return None
        res = self.layer.resolution
        x0 = self.layer.origin[0] + (window[1].start + 0.5) * res
        y0 = self.layer.origin[1] + (window[0].start + 0.5) * res
        mx = x0 + c * res
        my = y0 + r * res
        pts = np.asarray(points, float)[:, :2]
        # the marks near the points' bounding box only (a window holds at most 10^4 cells)
        lo = pts.min(axis=0) - reach
        hi = pts.max(axis=0) + reach
        keep = (mx >= lo[0]) & (mx <= hi[0]) & (my >= lo[1]) & (my <= hi[1])
        if not keep.any():
            return None
        mx, my = mx[keep], my[keep]
        for a in range(0, len(pts), 256):
            chunk = pts[a:a + 256]
            d2 = (chunk[:, 0, None] - mx[None, :]) ** 2 + (chunk[:, 1, None] - my[None, :]) ** 2
            near = np.flatnonzero(d2.min(axis=1) <= reach * reach)
            if near.size:
                return a + int(near[0])
        return None
