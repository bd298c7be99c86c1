"""Convex hulls of 2D points, as footprints need them: the corners of the hull of a few
points (an obstacle's outline, a mapped shape's) and the distinct points under it.

Qhull (scipy) finds any hull, but its setup costs far more than the hull of the tens of
points a footprint has: those go through :func:`monotone_chain` in Python instead.
"""

from __future__ import annotations

import math

import numpy as np

SMALL_HULL = 256
"""Hulls of at most this many distinct points are found by :func:`monotone_chain`, larger
ones by Qhull."""


def monotone_chain(pts: np.ndarray) -> np.ndarray:
    """The corners (counter-clockwise) of the convex hull of distinct points sorted by x then
    y (Andrew's monotone chain); points on an edge, or within the rounding of one, are left
    out, as Qhull leaves them (the two may differ on a point within about 1e-15 of the
    coordinates' size of an edge)."""
    rows = pts.tolist()
    xs, ys = [r[0] for r in rows], [r[1] for r in rows]
    if math.isfinite(sum(xs) + sum(ys)):  # all finite: numpy's max and ptp, in Python
        x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
        big = max(-x0, x1, -y0, y1)  # the largest magnitude
        span = max(x1 - x0, y1 - y0)
    else:
        big, span = float(np.abs(pts).max()), float(np.ptp(pts, axis=0).max())
    # a turn this small is rounding, not a corner: about where Qhull draws the line
    eps = 1e-15 * float(big) * float(span)

    def half(points: list[list[float]]) -> list[list[float]]:
        out: list[list[float]] = []
        for p in points:
            px, py = p
            while len(out) >= 2:
                ax, ay = out[-2]
                bx, by = out[-1]
                if (bx - ax) * (py - ay) - (by - ay) * (px - ax) > eps:
                    break
                out.pop()
            out.append(p)
        return out

    lower, upper = half(rows), half(rows[::-1])
    return np.array(lower[:-1] + upper[:-1], dtype=float).reshape(-1, 2)


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


def hull_xy(xy: np.ndarray) -> np.ndarray:
    """The corners of the convex hull of 2D points (the points themselves when they are
    fewer than three or collinear)."""
    from scipy.spatial import ConvexHull, QhullError

    pts = unique_rows(np.round(xy, 9))
    if len(pts) < 3:
        return pts
    if len(pts) <= SMALL_HULL:
        chain = monotone_chain(pts)
        return chain if len(chain) >= 3 else pts
    try:
        corners: np.ndarray = pts[ConvexHull(pts).vertices]
        return corners
    except QhullError:
        return pts
