"""Overlays: what behaviours want drawn on top of the world (planned paths, target frames).

Behaviours do not know whether anyone is watching. They call::

    from bt_manip.viz.overlay import overlay_for

    overlay_for(world).show_path("base_plan", [(x0, y0), (x1, y1), ...])
    overlay_for(world).show_frame("ik_target", T_world_target)   # 4x4
    overlay_for(world).clear("ik_target")

:func:`overlay_for` returns the :class:`Overlay` of a world (made on first use) or, without a
world, a throwaway one. An overlay only stores the latest item under each name and counts
changes; the live viewer and the recorder read it after each tick. Storing costs a dict write,
so the calls are free when nothing is viewing, and they never change the run.
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
class FrameItem:
    """A triad (x red, y green, z blue) at a 4x4 pose, axes ``size`` metres long."""

    matrix: np.ndarray
    size: float = 0.15


@dataclass
class Overlay:
    """Named paths and frames to draw, the latest of each; ``version`` counts changes."""

    items: dict[str, PathItem | FrameItem] = field(default_factory=dict)
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


def overlay_for(world: Any) -> Overlay:
    """The overlay of ``world`` (made on first use); a throwaway one when ``world`` is None."""
    if world is None:
        return Overlay()
    overlay = getattr(world, "overlay", None)
    if not isinstance(overlay, Overlay):
        overlay = Overlay()
        world.overlay = overlay
    return overlay


def item_json(item: PathItem | FrameItem) -> dict[str, Any]:
    """A three.js object JSON (plain lists, no binary) drawing an overlay item."""
    import uuid

    from bt_manip.viz.scene import colour_int, column_major

    geom_id, mat_id = str(uuid.uuid4()), str(uuid.uuid4())
    if isinstance(item, PathItem):
        positions = item.points.astype(np.float32).flatten().tolist()
        attributes: dict[str, Any] = {
            "position": {"itemSize": 3, "type": "Float32Array", "array": positions,
                         "normalized": False}
        }
        material = {"uuid": mat_id, "type": "LineBasicMaterial", "color": colour_int(item.rgba),
                    "linewidth": 3, "vertexColors": 0}
        kind, matrix = "Line", np.eye(4)
    else:
        s = item.size
        positions = [0, 0, 0, s, 0, 0, 0, 0, 0, 0, s, 0, 0, 0, 0, 0, 0, s]
        colours = [1, 0, 0, 1, 0, 0, 0, 0.8, 0, 0, 0.8, 0, 0, 0, 1, 0, 0, 1]
        attributes = {
            "position": {"itemSize": 3, "type": "Float32Array", "array": positions,
                         "normalized": False},
            "color": {"itemSize": 3, "type": "Float32Array", "array": colours,
                      "normalized": False},
        }
        material = {"uuid": mat_id, "type": "LineBasicMaterial", "color": 0xFFFFFF,
                    "linewidth": 3, "vertexColors": 2}
        kind, matrix = "LineSegments", item.matrix
    return {
        "metadata": {"version": 4.5, "type": "Object"},
        "geometries": [{"uuid": geom_id, "type": "BufferGeometry",
                        "data": {"attributes": attributes}}],
        "materials": [material],
        "object": {"uuid": str(uuid.uuid4()), "type": kind, "geometry": geom_id,
                   "material": mat_id, "matrix": column_major(matrix)},
    }
