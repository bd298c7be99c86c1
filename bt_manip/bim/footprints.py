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

import bisect
import itertools
import math
from typing import Any

import numpy as np

from bt_manip.bim.shapes import Box, hull_box, hull_xy

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
    return strip_boxes(corners, hull_box(corners, hint_yaw), bottom, top)


def strip_boxes(corners: np.ndarray, box: Box, bottom: float, top: float) -> list[Box]:
    """:func:`hull_boxes` of a footprint whose hull ``corners`` (N x 2) and least box ``box``
    (:func:`~bt_manip.bim.shapes.hull_box` of the corners) are known already.

    GEOS's hull of the corners decides whether they fill their box and cuts the strips from
    it, unless the corners' own polygon answers: clearly full (its area beyond the threshold
    by more than rounding), or clearly not, and convex, its corners in turn (the hull of the
    corners is then that polygon, and its strips are cut in Python, their bounds within
    rounding of GEOS's).
    """
    height = top - bottom
    z = (bottom + top) / 2
    whole = Box((box.centre[0], box.centre[1], z), (box.size[0], box.size[1], height), box.yaw)
    area = box.size[0] * box.size[1]
    if area <= 1e-9:
        return [whole]
    c, s = math.cos(box.yaw), math.sin(box.yaw)
    cx, cy = box.centre[0], box.centre[1]
    uv = [((x - cx) * c + (y - cy) * s, (y - cy) * c - (x - cx) * s)
          for x, y in corners.tolist()]
    if _shoelace(uv) >= HULL_FILL * area * (1.0 + 1e-9):
        # the hull of the corners holds their polygon: clearly full, whatever GEOS's rounding
        return [whole]
    convex = _convex_area(uv)
    if convex is None or convex >= HULL_FILL * area * (1.0 - 1e-9):
        return _geos_strips(corners, box, whole)
    out: list[Box] = []
    for u0, u1, v0, v1 in _strips(uv, _strip_edges(box), box.size[1]):
        u, v = (u0 + u1) / 2, (v0 + v1) / 2
        out.append(Box((cx + c * u - s * v, cy + s * u + c * v, z),
                       (u1 - u0, v1 - v0, height), box.yaw))
    return out or [whole]


def _strip_edges(box: Box) -> np.ndarray:
    """Where the strips across a box's length begin and end, from end to end (along its
    yaw, from its centre): :data:`STRIP` apart, at most :data:`MAX_STRIPS` strips."""
    n = min(MAX_STRIPS, max(2, math.ceil(box.size[0] / STRIP)))
    return np.linspace(-box.size[0] / 2, box.size[0] / 2, n + 1)


def _geos_strips(corners: np.ndarray, box: Box, whole: Box) -> list[Box]:
    """:func:`strip_boxes` by GEOS: the hull of the corners, its area against the box's, and
    the strips cut from it."""
    import shapely

    z, height = whole.centre[2], whole.size[2]
    c, s = math.cos(box.yaw), math.sin(box.yaw)
    xy = corners - np.array(box.centre[:2])
    uv = np.column_stack([xy @ np.array([c, s]), xy @ np.array([-s, c])])
    hull = shapely.convex_hull(shapely.multipoints(uv))
    if hull.area >= HULL_FILL * box.size[0] * box.size[1]:
        return [whole]
    edges = _strip_edges(box)
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


def _strips(uv: list[tuple[float, float]], edges: np.ndarray,
            width: float) -> list[tuple[float, float, float, float]]:
    """The strips ``(u0, u1, v0, v1)`` of a polygon (corners ``uv`` in turn) between each two
    ``edges`` in u, each the bounds of the polygon's part in it (and within ``width`` of
    v = 0, as GEOS's strips reach), leaving out the strips it misses or only touches (its
    part less than 1e-6 across).

    A part's bounds are those of its corners: the polygon's corners within the strip (on its
    edges included) and the points where its sides cross the strip's edges.
    """
    cuts = edges.tolist()
    n = len(cuts) - 1
    low, high = [math.inf] * n, [-math.inf] * n

    def add(k0: int, k1: int, v: float) -> None:  # the point (u, v) lies in strips k0..k1
        for k in range(max(k0, 0), min(k1, n - 1) + 1):
            low[k] = min(low[k], v)
            high[k] = max(high[k], v)

    for (pu, pv), (qu, qv) in zip(uv, uv[1:] + uv[:1], strict=True):
        add(bisect.bisect_left(cuts, pu) - 1, bisect.bisect_right(cuts, pu) - 1, pv)
        if pu == qu:
            continue
        a, b = (pu, qu) if pu < qu else (qu, pu)
        # the strip edges strictly between the side's ends, each in the strips on its sides
        for j in range(bisect.bisect_right(cuts, a), bisect.bisect_left(cuts, b)):
            v = pv + (cuts[j] - pu) * (qv - pv) / (qu - pu)
            add(j - 1, j, v)
    out = []
    for k in range(n):
        v0, v1 = max(low[k], -width), min(high[k], width)
        if v1 - v0 < 1e-6:  # missed (no point in it, or none within the width) or touched
            continue
        out.append((cuts[k], cuts[k + 1], v0, v1))
    return out


def _shoelace(pts: list[tuple[float, float]]) -> float:
    """The signed area of the polygon through ``pts`` in turn (positive counter-clockwise):
    at most the area of their convex hull when it is simple."""
    total = 0.0
    px, py = pts[-1]
    for x, y in pts:
        total += px * y - py * x
        px, py = x, y
    return total / 2.0


def _convex_area(pts: list[tuple[float, float]]) -> float | None:
    """The area of the polygon through ``pts`` in turn when it is convex and
    counter-clockwise (every turn to the left, its sides going right, then left, once
    round): the area of the hull of its corners; else None."""
    if len(pts) < 3:
        return None
    total = 0.0
    turns = 0  # how often the sides change from going right to going left in u, and back
    (ax, ay), (bx, by) = pts[-2], pts[-1]
    going = 0.0
    for cx, cy in pts:
        if (bx - ax) * (cy - by) - (by - ay) * (cx - bx) <= 0.0:
            return None
        du = cx - bx
        if du != 0.0:
            if going != 0.0 and (du > 0.0) != (going > 0.0):
                turns += 1
            going = du
        total += bx * cy - by * cx
        (ax, ay), (bx, by) = (bx, by), (cx, cy)
    if turns > 2:
        return None
    return total / 2.0


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
