"""Convex hulls of 2D points, as footprints need them: the corners of the hull of a few
points (an obstacle's outline, a mapped shape's) and the distinct points under it.

Qhull (scipy) finds any hull, but its setup costs far more than the hull of the tens of
points a footprint has: those go through :func:`monotone_chain` in Python instead, and their
distinct points are sorted as Python tuples (:func:`sorted_rows`) rather than by numpy.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TypeVar

import numpy as np

SMALL_HULL = 256
"""Hulls of at most this many distinct points are found by :func:`monotone_chain`, larger
ones by Qhull."""
SMALL_SORT = 128
"""Point sets of at most this many rows are sorted and made distinct in Python (beyond, numpy's
sort is the quicker)."""

Row = tuple[float, float]
"""A point's x and y."""
P = TypeVar("P", bound=Sequence[float])
"""A point as a sequence of its x and y (a tuple, or a list from ``tolist``)."""


def monotone_chain(pts: np.ndarray) -> np.ndarray:
    """The corners (counter-clockwise) of the convex hull of distinct points sorted by x then
    y (Andrew's monotone chain); points on an edge, or within the rounding of one, are left
    out, as Qhull leaves them (the two may differ on a point within about 1e-15 of the
    coordinates' size of an edge)."""
    rows = pts.tolist()
    chain = chain_rows(rows) if finite_rows(rows) else _chain(rows, _tolerance_np(pts))
    return np.array(chain, dtype=float).reshape(-1, 2)


def chain_rows(rows: Sequence[P]) -> list[P]:
    """:func:`monotone_chain` of distinct finite points sorted by x then y, given and returned
    as Python rows (the same corners, without the arrays)."""
    xs = [r[0] for r in rows]
    ys = [r[1] for r in rows]
    x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
    big = max(-x0, x1, -y0, y1)  # the largest magnitude: numpy's max of the absolute values
    span = max(x1 - x0, y1 - y0)  # numpy's largest ptp
    # a turn this small is rounding, not a corner: about where Qhull draws the line
    return _chain(rows, 1e-15 * big * span)


def _tolerance_np(pts: np.ndarray) -> float:
    """The chain's rounding tolerance from numpy's extent (points that are not all finite)."""
    return 1e-15 * float(np.abs(pts).max()) * float(np.ptp(pts, axis=0).max())


def finite_rows(rows: Sequence[Sequence[float]]) -> bool:
    """Whether every coordinate of the rows is finite (their sum is, unless it overflows:
    then the rows are taken for not finite, which only costs numpy's way)."""
    return math.isfinite(sum(map(sum, rows)))


def _chain(rows: Sequence[P], eps: float) -> list[P]:
    """The lower chain of the sorted rows, then the upper one, each without its last corner,
    a turn of at most ``eps`` dropping its middle point."""
    lower = _half(rows, eps)
    upper = _half(rows[::-1], eps)
    return lower[:-1] + upper[:-1]


def _half(rows: Sequence[P], eps: float) -> list[P]:
    """One half of the monotone chain: the rows in turn, each dropping the last ones the
    chain would not turn left (by more than ``eps``) after."""
    out: list[P] = []
    n = 0
    for p in rows:
        px, py = p
        while n >= 2:
            ax, ay = out[n - 2]
            bx, by = out[n - 1]
            if (bx - ax) * (py - ay) - (by - ay) * (px - ax) > eps:
                break
            out.pop()
            n -= 1
        out.append(p)
        n += 1
    return out


def sorted_rows(xy: np.ndarray) -> list[Row] | None:
    """The distinct rows of a small N x 2 array of finite numbers, sorted by x then y, as
    Python tuples (:func:`unique_rows`: of rows equal but for the sign of a zero, the first
    one kept); None for a large array or one not all finite (numpy's way then)."""
    if len(xy) > SMALL_SORT:
        return None
    rows = xy.tolist()
    if not finite_rows(rows):
        return None
    # a set keeps the first of equal tuples (0.0 == -0.0 and their hashes are the same), as
    # unique_rows's stable sort does; tuples sort by x, then y
    return sorted(set(map(tuple, rows)))  # type: ignore[arg-type]


def unique_rows(xy: np.ndarray) -> np.ndarray:
    """The distinct rows of an N x 2 array, sorted by x then y (``np.unique(xy, axis=0)``,
    without its structured-array round trip)."""
    if len(xy) == 0:
        return np.empty((0, 2), dtype=float)
    ordered = xy[np.lexsort((xy[:, 1], xy[:, 0]))]
    keep = np.ones(len(ordered), dtype=bool)
    keep[1:] = (ordered[1:] != ordered[:-1]).any(axis=1)
    out: np.ndarray = ordered[keep]
    return out


def next_rows(a: np.ndarray) -> np.ndarray:
    """The rows of ``a`` each replaced by the next, the last by the first (a polygon's next
    corners): ``np.roll(a, -1, axis=0)``, without its generic setup."""
    return np.concatenate((a[1:], a[:1]))


def distinct_chain(rounded: np.ndarray) -> tuple[list[Row] | np.ndarray, np.ndarray | None]:
    """The distinct rows of ``rounded`` (N x 2) sorted by x then y (Python tuples for a few
    finite ones, :func:`sorted_rows`, else an array, :func:`unique_rows`), and their monotone
    chain (:func:`monotone_chain`) when there are 3 to :data:`SMALL_HULL` of them, else None
    (too few, or Qhull's case)."""
    rows = sorted_rows(rounded)
    if rows is not None:  # a few finite points: sorted and chained in Python
        chain = np.array(chain_rows(rows), dtype=float).reshape(-1, 2) if len(rows) >= 3 else None
        return rows, chain
    pts = unique_rows(rounded)
    return pts, (monotone_chain(pts) if 3 <= len(pts) <= SMALL_HULL else None)


def hull_xy(xy: np.ndarray) -> np.ndarray:
    """The corners of the convex hull of 2D points (the points themselves when they are
    fewer than three or collinear)."""
    rounded = np.round(xy, 9)
    distinct, chain = distinct_chain(rounded)
    if chain is not None and len(chain) >= 3:
        return chain
    pts = np.asarray(distinct, dtype=rounded.dtype).reshape(-1, 2)
    if len(pts) <= SMALL_HULL:
        return pts
    from scipy.spatial import ConvexHull, QhullError

    try:
        corners: np.ndarray = pts[ConvexHull(pts).vertices]
        return corners
    except QhullError:
        return pts
