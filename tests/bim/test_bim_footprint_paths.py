"""An obstacle's footprint by its quick paths is the footprint of the plain computation.

The plain computation is kept here as the reference: the hull of the rounded distinct points
by numpy's sort and a monotone chain over arrays, the least box measured by numpy for every
candidate angle at once, and the strips cut from GEOS's hull by GEOS. The quick paths (Python
rows for a few points, the least box of known hull corners, strips cut in Python from a convex
hull) must give the same hulls and boxes to the last bit, and strips within 1e-9 m of GEOS's,
on convex and scattered point sets, degenerate ones (collinear, repeated, two points, one
point, tiny and huge coordinates), L-shapes and round footprints cut into strips.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

pytest.importorskip("scipy")
pytest.importorskip("shapely")

import shapely
from hull_reference import textbook_chain

from bt_manip.bim.footprints import HULL_FILL, MAX_STRIPS, STRIP, hull_boxes, strip_boxes
from bt_manip.bim.hulls import hull_xy, unique_rows
from bt_manip.bim.shapes import (
    TIE,
    Box,
    _box_along,
    _candidate_angles,
    footprint_box,
    hull_box,
)


def _plain_hull(xy: np.ndarray) -> np.ndarray:
    from scipy.spatial import ConvexHull, QhullError

    pts = unique_rows(np.round(xy, 9))
    if len(pts) < 3:
        return pts
    if len(pts) <= 256:
        chain = textbook_chain(pts)
        return chain if len(chain) >= 3 else pts
    try:
        corners: np.ndarray = pts[ConvexHull(pts).vertices]
        return corners
    except QhullError:
        return pts


def _plain_least(xy: np.ndarray,
                 angles: list[float]) -> tuple[float, np.ndarray, np.ndarray, bool]:
    c = np.array([math.cos(a) for a in angles])
    s = np.array([math.sin(a) for a in angles])
    x, y = xy[:, :1], xy[:, 1:2]
    u = x * c + y * s
    v = y * c - x * s
    lows = np.stack([u.min(axis=0), v.min(axis=0)], axis=1)
    highs = np.stack([u.max(axis=0), v.max(axis=0)], axis=1)
    areas = (highs[:, 0] - lows[:, 0]) * (highs[:, 1] - lows[:, 1])
    near = [angles[k] for k in np.flatnonzero(areas <= areas.min() + 2 * TIE)]
    pick = 0
    for k in range(1, len(angles)):
        if areas[k] < areas[pick] - TIE:
            pick = k
    return angles[pick], lows[pick], highs[pick], all(a == near[0] for a in near)


def _plain_box(points: np.ndarray, hint_yaw: float | None) -> Box:
    xy = points[:, :2]
    z0, z1 = float(points[:, 2].min()), float(points[:, 2].max())
    pts = unique_rows(np.round(xy, 6))
    found = None
    if 3 <= len(pts) <= 256:
        chain = textbook_chain(pts)
        if len(chain) >= 3:
            edges = np.roll(chain, -1, axis=0) - chain
            angles = [a % (math.pi / 2) for a in np.arctan2(edges[:, 1], edges[:, 0]).tolist()]
            found = _plain_least(xy, angles)
    if found is None or not found[3]:
        found = _plain_least(xy, _candidate_angles(xy))
    angle, lo, hi, _ = found
    return _box_along(angle, (float(lo[0]), float(lo[1])), (float(hi[0]), float(hi[1])),
                      hint_yaw, z0, z1)


def _geos_strips(corners: np.ndarray, box: Box, bottom: float, top: float) -> list[Box]:
    height, z = top - bottom, (bottom + top) / 2
    whole = Box((box.centre[0], box.centre[1], z), (box.size[0], box.size[1], height), box.yaw)
    area = box.size[0] * box.size[1]
    if area <= 1e-9:
        return [whole]
    c, s = math.cos(box.yaw), math.sin(box.yaw)
    xy = corners - np.array(box.centre[:2])
    uv = np.column_stack([xy @ np.array([c, s]), xy @ np.array([-s, c])])
    hull = shapely.convex_hull(shapely.multipoints(uv))
    if hull.area >= HULL_FILL * area:
        return [whole]
    n = min(MAX_STRIPS, max(2, math.ceil(box.size[0] / STRIP)))
    edges = np.linspace(-box.size[0] / 2, box.size[0] / 2, n + 1)
    parts = shapely.intersection(hull, shapely.box(edges[:-1], -box.size[1], edges[1:],
                                                   box.size[1]))
    empty, bounds = shapely.is_empty(parts), shapely.bounds(parts)
    out = []
    for k, (u0, u1) in enumerate(itertools.pairwise(edges)):
        v0, v1 = float(bounds[k][1]), float(bounds[k][3])
        if empty[k] or v1 - v0 < 1e-6:
            continue
        u, v = (u0 + u1) / 2, (v0 + v1) / 2
        out.append(Box((box.centre[0] + c * u - s * v, box.centre[1] + s * u + c * v, z),
                       (u1 - u0, v1 - v0, height), box.yaw))
    return out or [whole]


def _turned(xy: np.ndarray, rng: np.random.Generator, offset: float) -> np.ndarray:
    yaw = rng.uniform(-math.pi, math.pi)
    rot = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
    out: np.ndarray = xy @ rot.T + rng.uniform(-offset, offset, 2)
    return out


def _point_sets(seed: int) -> list[np.ndarray]:
    """Convex and scattered sets, round and L-shaped footprints, and degenerate ones."""
    rng = np.random.default_rng(seed)
    out: list[np.ndarray] = []
    for _ in range(25):
        n = int(rng.integers(3, 70))
        angles = np.sort(rng.uniform(0, 2 * math.pi, n))
        r = rng.uniform(0.05, 3.0)
        out.append(_turned(np.column_stack([r * np.cos(angles), r * np.sin(angles)]), rng, 30))
        k = int(rng.integers(8, 65))  # a round footprint, regular, top and bottom rings
        ring = (np.arange(k) + 0.5) * (2 * math.pi / k)
        disc = np.column_stack([np.cos(ring), np.sin(ring)]) * rng.uniform(0.1, 2.0)
        out.append(np.vstack([disc, disc]) + rng.uniform(-40, 40, 2))
        ellipse = np.column_stack([rng.uniform(1, 6) * np.cos(ring), np.sin(ring)])
        out.append(_turned(ellipse, rng, 10))
        out.append(rng.normal(size=(int(rng.integers(1, 120)), 2)) * rng.uniform(0.01, 50))
        a, b, t = rng.uniform(0.5, 5.0), rng.uniform(0.5, 5.0), rng.uniform(0.1, 0.4)
        ell = np.array([[0, 0], [a, 0], [a, t], [t, t], [t, b], [0, b]])  # an L-shape
        out.append(_turned(ell, rng, 20))
        out.append(_turned(np.array([[0, 0], [a, 0], [a, b], [0, b]]), rng, 20))
        out.append(np.round(rng.uniform(-3, 3, (int(rng.integers(2, 40)), 2)), 1))  # repeats
    line = np.linspace(0, 1, 7)[:, None] * np.array([[3.0, 1.0]]) + [2.0, -1.0]
    out += [
        line, np.vstack([line, line[::-1]]), np.array([[1.0, 2.0]]),
        np.array([[1.0, 2.0], [1.0, 2.0], [4.0, 6.0]]), np.array([[0.0, 0.0], [0.0, 0.0]]),
        np.array([[0.0, 0.0], [-0.0, 1.0], [1.0, -0.0], [-0.0, -0.0], [1.0, 1.0]]),
        np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]]),  # about the origin
        rng.uniform(-1, 1, (30, 2)) * 1e-7, rng.uniform(-1, 1, (30, 2)) * 1e-4,
        rng.uniform(-1, 1, (30, 2)) + 1e6, rng.uniform(-1, 1, (30, 2)) * 1e5 + [3e7, -2e7],
        rng.uniform(-1, 1, (400, 2)) * 5.0,  # numpy's sort and Qhull
        rng.uniform(-1, 1, (200, 2)) * 5.0,  # numpy's sort, a chain of arrays
        np.column_stack([np.cos(np.arange(180) / 28.65), np.sin(np.arange(180) / 28.65)]),
    ]
    for n in (4, 6, 8, 12, 32):  # regular polygons: boxes along different edges tie
        ring = np.arange(n) * (2 * math.pi / n) + 0.3
        out.append(np.column_stack([np.cos(ring), np.sin(ring)]) * 2.0 + [5.0, -3.0])
    return out


def _same_boxes(a: list[Box], b: list[Box]) -> bool:
    return len(a) == len(b) and all(
        np.allclose(p.centre, q.centre, rtol=0.0, atol=1e-9)
        and np.allclose(p.size, q.size, rtol=0.0, atol=1e-9) and p.yaw == q.yaw
        for p, q in zip(a, b, strict=True))


@pytest.mark.parametrize("seed", [0, 1])
def test_hulls_are_the_plain_hulls(seed: int) -> None:
    for xy in _point_sets(seed):
        fast, plain = hull_xy(xy), _plain_hull(xy)
        assert fast.shape == plain.shape and fast.dtype == plain.dtype
        assert np.array_equal(fast, plain)
        assert [math.copysign(1.0, v) for v in fast.ravel()] == \
            [math.copysign(1.0, v) for v in plain.ravel()]  # zeros of the same sign


@pytest.mark.parametrize("seed", [2, 3])
def test_boxes_are_the_plain_boxes(seed: int) -> None:
    """The least box of known hull corners, and of any points, to the last bit."""
    rng = np.random.default_rng(seed)
    for xy in _point_sets(seed):
        corners = hull_xy(xy)
        flat = np.column_stack([corners, np.zeros(len(corners))])
        for hint in (None, 0.3, -2.5):
            assert hull_box(corners, hint) == _plain_box(flat, hint)
        points = np.column_stack([xy, rng.uniform(-1, 3, len(xy))])
        assert footprint_box(points, 1.1) == _plain_box(points, 1.1)


@pytest.mark.parametrize("seed", [4, 5])
def test_strips_are_geos_strips(seed: int) -> None:
    """The same number of strips as GEOS cuts, each within 1e-9 m of its own."""
    cut = 0
    for xy in _point_sets(seed):
        corners = hull_xy(xy)
        for hint in (None, 0.7):
            box = hull_box(corners, hint)
            fast = strip_boxes(corners, box, 0.5, 2.0)
            assert _same_boxes(fast, _geos_strips(corners, box, 0.5, 2.0))
            assert fast == hull_boxes(np.column_stack([xy, np.zeros(len(xy))]), 0.5, 2.0, hint)
            cut += len(fast) > 1
    assert cut > 40  # round footprints and L-shapes among them are cut into strips


def test_strips_of_a_polygon_that_is_not_its_hull_are_geos() -> None:
    """Corners that are not a convex polygon in turn (here: out of turn) go to GEOS."""
    ring = np.arange(24) * (2 * math.pi / 24)
    corners = np.column_stack([3.0 * np.cos(ring), np.sin(ring)])
    box = hull_box(corners, None)
    shuffled = corners[np.random.default_rng(6).permutation(len(corners))]
    boxes = strip_boxes(shuffled, box, 0.0, 1.0)
    assert len(boxes) > 1
    assert boxes == _geos_strips(shuffled, box, 0.0, 1.0)
    assert _same_boxes(boxes, strip_boxes(corners, box, 0.0, 1.0))
