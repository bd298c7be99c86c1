"""Path post-processing: line-of-sight shortcuts on the inflated cost grid.

A grid path moves in steps of 45 degrees. :func:`shortcut` keeps only the cells where the path
must turn: from an anchor cell it goes straight to the farthest later path cell it can see,
where *see* means that every cell the straight segment between the two cell centres touches
(corners included) is free, and the segment costs no more than the stretch of grid path it
replaces (cost sampled along the segment). The second rule keeps what the cost gradient
bought: a shortcut does not hug a wall where the grid path kept away from it, e.g. right after
a doorway. The result never crosses a blocked cell.

:func:`densify` turns the corner cells into a world-coordinate polyline with points every few
centimetres, which is what the path follower tracks.
"""

from __future__ import annotations

import itertools
import math

import numba
import numpy as np


@numba.njit(cache=True)
def segment_max_cost(cost: np.ndarray, r0: int, c0: int, r1: int, c1: int) -> float:
    """Largest cost among the cells the segment between two cell centres touches.

    Walks the grid along the segment (cells sharing only a corner with the segment count as
    touched, so a diagonal line cannot slip between two blocked cells). ``inf`` if blocked.
    """
    dr = r1 - r0
    dc = c1 - c0
    nr = abs(dr)
    nc = abs(dc)
    sr = 1 if dr > 0 else -1
    sc = 1 if dc > 0 else -1
    r = r0
    c = c0
    worst = cost[r, c]
    ir = 0
    ic = 0
    # compare (0.5 + ic) / nc against (0.5 + ir) / nr without division
    while ir < nr or ic < nc:
        lhs = (1 + 2 * ic) * nr
        rhs = (1 + 2 * ir) * nc
        if lhs == rhs:  # through a corner: both side cells are touched
            worst = max(worst, cost[r, c + sc], cost[r + sr, c])
            r += sr
            c += sc
            ir += 1
            ic += 1
        elif lhs < rhs:
            c += sc
            ic += 1
        else:
            r += sr
            ir += 1
        worst = max(worst, cost[r, c])
        if worst == np.inf:
            return worst  # type: ignore[no-any-return]  # numba body: cost items are floats
    return worst  # type: ignore[no-any-return]  # numba body: cost items are floats


@numba.njit(cache=True)
def segment_cost(cost: np.ndarray, r0: int, c0: int, r1: int, c1: int) -> float:
    """Cost (cell lengths x cost) of the straight move between two cell centres.

    The cost of the cells along the segment is sampled every half cell; ``inf`` if any cell
    the segment touches is blocked.
    """
    if segment_max_cost(cost, r0, c0, r1, c1) == np.inf:
        return np.inf
    length = math.hypot(r1 - r0, c1 - c0)
    n = max(1, math.ceil(2.0 * length))
    total = 0.0
    for k in range(1, n + 1):
        t = (k - 0.5) / n
        r = math.floor(r0 + 0.5 + t * (r1 - r0))
        c = math.floor(c0 + 0.5 + t * (c1 - c0))
        total += cost[r, c]
    return total * length / n


@numba.njit(cache=True)
def _shortcut(cost: np.ndarray, cells: np.ndarray, horizon: int, slack: float) -> np.ndarray:
    n = cells.shape[0]
    # cost of the grid path up to each cell
    acc = np.zeros(n)
    for k in range(1, n):
        step = (
            math.sqrt(2.0)
            if cells[k, 0] != cells[k - 1, 0] and cells[k, 1] != cells[k - 1, 1]
            else 1.0
        )
        acc[k] = acc[k - 1] + step * cost[cells[k, 0], cells[k, 1]]
    keep = np.zeros(n, np.bool_)
    keep[0] = True
    keep[n - 1] = True
    i = 0
    while i < n - 1:
        best = i + 1
        for j in range(i + 2, min(n, i + 1 + horizon)):
            line = segment_cost(cost, cells[i, 0], cells[i, 1], cells[j, 0], cells[j, 1])
            if line <= (acc[j] - acc[i]) * (1.0 + slack):
                best = j
        keep[best] = True
        i = best
    return cells[keep]


def shortcut(
    cost: np.ndarray, cells: np.ndarray, horizon: int = 400, slack: float = 0.0
) -> np.ndarray:
    """The corner cells (k, 2) of a line-of-sight shortcut of a grid path (n, 2).

    A straight segment replaces part of the path when it crosses no blocked cell and costs no
    more than that part (times ``1 + slack``); from each anchor, path cells up to ``horizon``
    steps ahead are tried.
    """
    p = np.ascontiguousarray(np.asarray(cells, dtype=np.int64))
    if len(p) <= 2:
        return p.copy()
    return _shortcut(np.ascontiguousarray(cost, dtype=np.float32), p, int(horizon), float(slack))


def densify(points: np.ndarray, spacing: float = 0.05) -> np.ndarray:
    """A polyline (n, 2) with extra points so that no two consecutive are over ``spacing`` apart."""
    pts = np.asarray(points, dtype=float)
    if len(pts) < 2:
        return pts.copy()
    out = [pts[:1]]
    for a, b in itertools.pairwise(pts):
        k = max(1, math.ceil(float(np.hypot(*(b - a))) / spacing))
        t = np.arange(1, k + 1)[:, None] / k
        out.append(a + t * (b - a))
    return np.concatenate(out)


def path_length(points: np.ndarray) -> float:
    """Length (m) of a polyline (n, 2)."""
    pts = np.asarray(points, dtype=float)
    if len(pts) < 2:
        return 0.0
    return float(np.hypot(*np.diff(pts, axis=0).T).sum())
