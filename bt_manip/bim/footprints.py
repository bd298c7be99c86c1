"""Obstacles that are not plain boxes, as the boxes a world holds, and holes in wall bodies.

:func:`hull_boxes` turns an element's points into its footprint: the convex hull of the points
projected on the floor. A hull that fills its least box (see :data:`HULL_FILL`) is that box;
any other (a round column, a curved desk, a stair's landing) is cut into strips
:data:`STRIP` m wide across its length, each strip the box round the hull's part in it, so the
obstacle keeps its outline to within a strip's corner.

:func:`wall_gaps` reads the holes of a straight wall whose body has them cut already (doors and
windows carved into the solid, as some exporters write walls): the wall's triangles are
projected on its vertical mid-plane, and the parts of the wall's elevation (its length by its
height) that no triangle covers are its openings.
"""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np

from bt_manip.bim.hulls import next_rows
from bt_manip.bim.shapes import Box, footprint_box, hull_xy

HULL_FILL = 0.85
"""A hull filling at least this share of its least box is the box itself."""
STRIP = 0.1
"""Width (m) of the strips a rounder footprint is cut into."""
MAX_STRIPS = 60
"""Strips per obstacle at most (wider strips beyond)."""
MIN_GAP = 0.05
"""Holes narrower or lower than this (m) are left closed."""


def hull_boxes(points: np.ndarray, bottom: float, top: float,
               hint_yaw: float | None = None) -> list[Box]:
    """The boxes (from ``bottom`` to ``top``, m) covering the hull of ``points``' footprint."""
    corners = hull_xy(points[:, :2])
    box = footprint_box(np.column_stack([corners, np.zeros(len(corners))]), hint_yaw)
    return strip_boxes(corners, box, bottom, top)


def strip_boxes(corners: np.ndarray, box: Box, bottom: float, top: float) -> list[Box]:
    """:func:`hull_boxes` of a footprint whose hull ``corners`` (N x 2) and least box ``box``
    (:func:`~bt_manip.bim.shapes.footprint_box` of the corners) are known already."""
    import shapely

    height = top - bottom
    z = (bottom + top) / 2
    whole = Box((box.centre[0], box.centre[1], z), (box.size[0], box.size[1], height), box.yaw)
    area = box.size[0] * box.size[1]
    if area <= 1e-9:
        return [whole]
    c, s = math.cos(box.yaw), math.sin(box.yaw)
    xy = corners - np.array(box.centre[:2])
    uv = np.column_stack([xy @ np.array([c, s]), xy @ np.array([-s, c])])
    if _shoelace(uv) >= HULL_FILL * area * (1.0 + 1e-9):
        # the hull of the corners holds their polygon: clearly full, whatever GEOS's rounding
        return [whole]
    hull = shapely.convex_hull(shapely.multipoints(uv))
    if hull.area >= HULL_FILL * area:
        return [whole]
    n = min(MAX_STRIPS, max(2, math.ceil(box.size[0] / STRIP)))
    edges = np.linspace(-box.size[0] / 2, box.size[0] / 2, n + 1)
    # the strips cut from the hull all at once (one call into GEOS for all of them)
    strips = shapely.box(edges[:-1], -box.size[1], edges[1:], box.size[1])
    parts = shapely.intersection(hull, strips)
    empty = shapely.is_empty(parts)
    bounds = shapely.bounds(parts)
    out: list[Box] = []
    for k, (u0, u1) in enumerate(itertools.pairwise(edges)):
        if empty[k]:
            continue
        v0, v1 = float(bounds[k][1]), float(bounds[k][3])
        if v1 - v0 < 1e-6:
            continue
        u, v = (u0 + u1) / 2, (v0 + v1) / 2
        out.append(Box((box.centre[0] + c * u - s * v, box.centre[1] + s * u + c * v, z),
                       (u1 - u0, v1 - v0, height), box.yaw))
    return out or [whole]


def _shoelace(pts: np.ndarray) -> float:
    """The signed area of the polygon through ``pts`` in turn (positive counter-clockwise):
    at most the area of their convex hull when it is simple."""
    x, y = pts[:, 0], pts[:, 1]
    return float(np.dot(x, next_rows(y)) - np.dot(y, next_rows(x))) / 2.0


def wall_gaps(
    verts: np.ndarray, faces: np.ndarray, start: tuple[float, float], yaw: float,
    length: float, bottom: float, top: float,
) -> list[tuple[float, float, float, float]]:
    """Openings ``(start, end, bottom, top)`` (m along the wall from ``start``, m in z) that
    go through the wall's body: the uncovered parts of its elevation."""
    from shapely.geometry import Polygon
    from shapely.geometry import box as rect
    from shapely.ops import unary_union

    c, s = math.cos(yaw), math.sin(yaw)
    u = (verts[:, 0] - start[0]) * c + (verts[:, 1] - start[1]) * s
    z = verts[:, 2]
    tri_u, tri_z = u[faces], z[faces]
    area = 0.5 * np.abs((tri_u[:, 1] - tri_u[:, 0]) * (tri_z[:, 2] - tri_z[:, 0])
                        - (tri_u[:, 2] - tri_u[:, 0]) * (tri_z[:, 1] - tri_z[:, 0]))
    keep = area > 1e-8
    triangles = [Polygon(list(zip(tu, tz, strict=True)))
                 for tu, tz in zip(tri_u[keep], tri_z[keep], strict=True)]
    if not triangles:
        return []
    cover = unary_union(triangles).buffer(1e-4)
    rest: Any = rect(0.0, bottom, length, top).difference(cover)
    pieces = list(getattr(rest, "geoms", [rest]))
    gaps = []
    for piece in pieces:
        if piece.is_empty:
            continue
        u0, z0, u1, z1 = piece.bounds
        if u1 - u0 < MIN_GAP or z1 - z0 < MIN_GAP or piece.area < 0.6 * (u1 - u0) * (z1 - z0):
            continue
        gaps.append((max(u0, 0.0), min(u1, length), z0, z1))
    return sorted(gaps)
