"""Placements on a design grid: an element placed where two grid axes cross (IfcGridPlacement).

Structural exports place columns this way: the element's origin is the crossing of two axes
of an IfcGrid (:class:`IfcVirtualGridIntersection`), each axis moved sideways by its offset
distance first (to the left of the axis as it runs, the sense of an offset curve; the axis
runs along its curve, or against it when its ``SameSense`` is false), and lifted by the third
offset, if any. The element's x axis runs along the first axis there, or towards the crossing
named by ``PlacementRefDirection``, or along the direction it gives. Everything is in the
grid's coordinate system, whose placement is that of the IfcGrid the axes belong to (or, in
IFC4.3, the placement's ``PlacementRelTo`` when no grid is found).

Straight axes are read: IfcPolyline, IfcLine, and an IfcTrimmedCurve of a line. Anything else
(a circular grid's arcs) is :class:`UnreadGrid`, with its reason.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from typing import Any

import numpy as np

PARALLEL = 1e-9
"""Below this sine of the angle between them, two axes are taken as parallel."""


class UnreadGrid(Exception):
    """A grid placement that is not read; the message says why."""


def grid_placement_matrix(placement: Any, placement_of: Callable[[Any], np.ndarray]) -> np.ndarray:
    """The 4x4 matrix (file units) of an IfcGridPlacement; ``placement_of`` gives that of the
    grid's own placement."""
    try:
        return _grid_placement(placement, placement_of)
    except (AttributeError, TypeError, IndexError) as exc:  # an attribute left empty
        raise UnreadGrid(f"it is incomplete ({exc})") from None


def _grid_placement(placement: Any, placement_of: Callable[[Any], np.ndarray]) -> np.ndarray:
    location = placement.PlacementLocation
    if location is None:
        raise UnreadGrid("it names no grid intersection")
    origin, along = crossing(location)
    ref = placement.PlacementRefDirection
    if ref is None:
        x = along
    elif ref.is_a("IfcDirection"):
        ratios = [float(v) for v in ref.DirectionRatios]
        x = np.array([*ratios, 0.0, 0.0][:2])
    else:  # IfcVirtualGridIntersection: towards that crossing
        x = crossing(ref)[0][:2] - origin[:2]
    norm = math.hypot(x[0], x[1])
    if norm == 0.0:
        raise UnreadGrid("its reference direction has no length in the grid's plane")
    c, s = x[0] / norm, x[1] / norm
    local = np.eye(4)
    local[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    local[:3, 3] = origin
    return _grid_frame(placement, location, placement_of) @ local


def crossing(intersection: Any) -> tuple[np.ndarray, np.ndarray]:
    """Where the two axes of an IfcVirtualGridIntersection cross, after their offsets (x, y, z
    in the grid's coordinates), and the first axis' unit direction there (x, y)."""
    axes = list(intersection.IntersectingAxes or ())
    offsets = [float(v) for v in (intersection.OffsetDistances or ())]
    if len(axes) != 2:
        raise UnreadGrid(f"its grid intersection names {len(axes)} axes, not 2")
    offsets += [0.0] * (3 - len(offsets))
    first, second = (_offset_segments(axis, offsets[k]) for k, axis in enumerate(axes))
    for i, (p, d) in enumerate(first):
        for j, (q, e) in enumerate(second):
            hit = _meet(p, d, q, e)
            if hit is None:
                continue
            t, u = hit
            if _within(t, i == 0, i == len(first) - 1) and \
                    _within(u, j == 0, j == len(second) - 1):
                point = p + t * d
                return np.array([point[0], point[1], offsets[2]]), d / math.hypot(*d)
    names = " and ".join(f"'{a.AxisTag or '#' + str(a.id())}'" for a in axes)
    raise UnreadGrid(f"grid axes {names} do not cross")


def _within(t: float, first: bool, last: bool) -> bool:
    """Whether parameter ``t`` lies on a segment (0 to 1), or beyond the open end of the
    polyline's first or last segment (an axis drawn a little short still crosses)."""
    eps = 1e-9
    return (first or t >= -eps) and (last or t <= 1.0 + eps)


def _meet(p: np.ndarray, d: np.ndarray, q: np.ndarray, e: np.ndarray) -> tuple[float, float] | None:
    """Parameters (t, u) where the lines p + t d and q + u e meet; None when parallel."""
    det = d[0] * -e[1] - d[1] * -e[0]
    scale = math.hypot(*d) * math.hypot(*e)
    if scale == 0.0 or abs(det) <= PARALLEL * scale:
        return None
    r = q - p
    t = (r[0] * -e[1] - r[1] * -e[0]) / det
    u = (d[0] * r[1] - d[1] * r[0]) / det
    return float(t), float(u)


def _offset_segments(axis: Any, offset: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """The axis as (start, vector) segments in its running sense, moved ``offset`` to its
    left."""
    points = _axis_points(axis)
    if axis.SameSense is False:
        points = points[::-1]
    out = []
    for a, b in itertools.pairwise(points):
        d = b - a
        n = math.hypot(*d)
        if n == 0.0:
            continue
        left = np.array([-d[1], d[0]]) / n
        out.append((a + offset * left, d))
    if not out:
        raise UnreadGrid(f"grid axis '{axis.AxisTag or '#' + str(axis.id())}' has no length")
    return out


def _axis_points(axis: Any) -> np.ndarray:
    """Two or more points (x, y) along a straight grid axis, in its curve's sense."""
    curve = axis.AxisCurve
    name = axis.AxisTag or f"#{axis.id()}"
    if curve is None:
        raise UnreadGrid(f"grid axis '{name}' has no curve")
    if curve.is_a("IfcTrimmedCurve") and curve.BasisCurve.is_a("IfcLine"):
        curve = curve.BasisCurve  # the crossing may lie anywhere along the line
    if curve.is_a("IfcPolyline"):
        pts = [tuple(float(v) for v in p.Coordinates[:2]) for p in curve.Points]
        if len(pts) < 2:
            raise UnreadGrid(f"grid axis '{name}' is a polyline of {len(pts)} point(s)")
        return np.array(pts)
    elif curve.is_a("IfcLine"):
        start = np.array([float(v) for v in curve.Pnt.Coordinates[:2]])
        vector = curve.Dir
        ratios = np.array([float(v) for v in vector.Orientation.DirectionRatios[:2]])
        return np.array([start, start + ratios * float(vector.Magnitude or 1.0)])
    raise UnreadGrid(f"grid axis '{name}' is an {curve.is_a()}: only straight grid axes "
                     "(polylines and lines) are read")


def _grid_frame(placement: Any, location: Any, placement_of: Callable[[Any], np.ndarray]
                ) -> np.ndarray:
    """The matrix of the grid's coordinate system: the placement of the IfcGrid the first
    axis belongs to, else the placement's PlacementRelTo (IFC4.3), else the identity."""
    axis = location.IntersectingAxes[0]
    for inverse in ("PartOfU", "PartOfV", "PartOfW"):
        for grid in getattr(axis, inverse, None) or ():
            if grid.ObjectPlacement is not None:
                return placement_of(grid.ObjectPlacement)
    relative = getattr(placement, "PlacementRelTo", None)
    if relative is not None:
        return placement_of(relative)
    return np.eye(4)
