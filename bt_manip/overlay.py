"""The overlay model: what behaviours want drawn on top of the world (planned paths, target
frames).

Behaviours do not know whether anyone is watching. They write to the overlay of their run
(:attr:`bt_manip.run.context.RunContext.overlay`)::

    overlay.show_path("base_plan", [(x0, y0), (x1, y1), ...])
    overlay.show_frame("ik_target", T_world_target)   # 4x4
    overlay.show_points("laser_scan", [(x0, y0), ...], z=0.25)
    overlay.clear("ik_target")

An overlay only stores the latest item under each name and counts changes; the live viewer and
the recorder (:mod:`bt_manip.viz`) read it after each tick. Storing costs a dict write, so the
calls are free when nothing is viewing, and they never change the run.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

PATH_COLOUR = (0.1, 0.85, 0.3, 1.0)
PATH_HEIGHT = 0.03
"""Height (m) above the floor at which a planar path is drawn."""


@dataclass(frozen=True)
class PathItem:
    """A polyline in the world frame: rows (x, y, z)."""

    points: np.ndarray
    rgba: tuple[float, float, float, float] = PATH_COLOUR


@dataclass(frozen=True)
class PointsItem:
    """Points in the world frame, rows (x, y, z), each drawn as a dot ``size`` metres wide."""

    points: np.ndarray
    rgba: tuple[float, float, float, float] = PATH_COLOUR
    size: float = 0.04


@dataclass(frozen=True)
class FrameItem:
    """A triad (x red, y green, z blue) at a 4x4 pose, axes ``size`` metres long."""

    matrix: np.ndarray
    size: float = 0.15


@dataclass
class Overlay:
    """Named paths and frames to draw, the latest of each; ``version`` counts changes."""

    items: dict[str, PathItem | FrameItem | PointsItem] = field(default_factory=dict)
    version: int = 0

    def show_path(
        self,
        name: str,
        xy_points: Iterable[Sequence[float]],
        z: float = PATH_HEIGHT,
        rgba: tuple[float, float, float, float] = PATH_COLOUR,
    ) -> None:
        """Draw a planar path (x, y) a little above the floor; (x, y, z) points keep their z."""
        rows = []
        for p in xy_points:
            rows.append((float(p[0]), float(p[1]), float(p[2]) if len(p) > 2 else z))
        if len(rows) < 2:
            self.clear(name)
            return
        self.items[name] = PathItem(np.array(rows), rgba)
        self.version += 1

    def show_points(
        self,
        name: str,
        xy_points: Any,
        z: float = PATH_HEIGHT,
        rgba: tuple[float, float, float, float] = PATH_COLOUR,
        size: float = 0.04,
    ) -> None:
        """Draw points (rows x, y) at height ``z``: a laser's returns, a filter's particles."""
        xy = np.asarray(xy_points, dtype=float).reshape(-1, 2)
        if len(xy) == 0:
            self.clear(name)
            return
        points = np.column_stack([xy, np.full(len(xy), float(z))])
        self.items[name] = PointsItem(points, rgba, float(size))
        self.version += 1

    def show_frame(self, name: str, matrix: Any, size: float = 0.15) -> None:
        """Draw a coordinate frame (4x4 homogeneous transform in the world frame)."""
        m = np.array(matrix, dtype=float)
        if m.shape != (4, 4):
            raise ValueError(f"show_frame needs a 4x4 matrix, got shape {m.shape}")
        self.items[name] = FrameItem(m, float(size))
        self.version += 1

    def clear(self, name: str | None = None) -> None:
        """Remove one item, or every item when ``name`` is None."""
        if name is None:
            if self.items:
                self.items.clear()
                self.version += 1
        elif self.items.pop(name, None) is not None:
            self.version += 1


def run_overlay(tree: Any) -> Overlay | None:
    """The overlay of the run that ``tree`` ticks in (the ``overlay`` of its context, a
    :class:`~bt_manip.run.context.RunContext`); None when its context has none."""
    overlay = getattr(getattr(tree, "context", None), "overlay", None)
    return overlay if isinstance(overlay, Overlay) else None
