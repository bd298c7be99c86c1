"""The footprint helpers' fast paths give what their plain versions give.

The hull of a few points is found by a monotone chain, the distinct points without
``np.unique``, and an obstacle's strips from its known hull and box: each is checked here
against Qhull, ``np.unique`` and :func:`~bt_manip.bim.footprints.hull_boxes` on shapes like
the ones footprints are made of (boxes, polygons, round profiles, scattered points).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("scipy")
pytest.importorskip("shapely")

from hull_reference import textbook_chain
from scipy.spatial import ConvexHull

from bt_manip.bim.footprints import hull_boxes, strip_boxes
from bt_manip.bim.hulls import hull_xy, monotone_chain, unique_rows
from bt_manip.bim.shapes import footprint_box


def _shapes(seed: int) -> list[np.ndarray]:
    """Footprint-like point sets: turned boxes (with points along their sides), 32-gons,
    scattered points, in metres and in millimetres."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(40):
        a, b = rng.uniform(0.1, 5.0, 2)
        yaw = rng.uniform(-math.pi, math.pi)
        rot = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
        box = np.array([[0, 0], [a, 0], [a, b], [0, b], [a / 2, b / 2], [a / 4, b / 3]])
        out.append(box @ rot.T + rng.uniform(-50, 50, 2))
        out.append(np.array([[0, 0], [a, 0], [a, b], [0, b], [0.3 * a, b / 2]]) * 1000.0
                   + np.round(rng.uniform(-1e4, 1e4, 2)))
        angles = (np.arange(32) + 0.5) * (2 * math.pi / 32)
        r = rng.uniform(0.05, 1.0)
        out.append(np.column_stack([r * np.cos(angles), r * np.sin(angles)])
                   + rng.uniform(-20, 20, 2))
        out.append(rng.normal(size=(int(rng.integers(3, 80)), 2)) * rng.uniform(0.1, 100))
    return out


def test_unique_rows_is_np_unique() -> None:
    rng = np.random.default_rng(0)
    for n in (0, 1, 2, 7, 60):
        xy = np.round(rng.normal(size=(n, 2)), 1)
        xy = np.vstack([xy, xy[: n // 2], -0.0 * xy[:1]])
        assert np.array_equal(unique_rows(xy), np.unique(xy, axis=0))


def test_monotone_chain_finds_qhulls_corners() -> None:
    for xy in _shapes(1):
        pts = unique_rows(np.round(xy, 9))
        chain = monotone_chain(pts)
        qhull = pts[ConvexHull(pts).vertices]
        assert {tuple(p) for p in chain} == {tuple(p) for p in qhull}
        # counter-clockwise: every turn is to the left
        a = np.roll(chain, -1, axis=0) - chain
        b = np.roll(a, -1, axis=0)
        assert (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0] > 0).all()


def test_hull_of_collinear_or_few_points_is_the_points() -> None:
    line = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [0.5, 0.5]])
    assert np.array_equal(hull_xy(line), np.unique(line, axis=0))
    two = np.array([[1.0, 0.0], [0.0, 0.0], [1.0, 0.0]])
    assert np.array_equal(hull_xy(two), np.array([[0.0, 0.0], [1.0, 0.0]]))


def test_strip_boxes_are_hull_boxes() -> None:
    for xy in _shapes(2):
        points = np.column_stack([xy, np.zeros(len(xy))])
        corners = hull_xy(xy)
        box = footprint_box(np.column_stack([corners, np.zeros(len(corners))]), 0.3)
        assert strip_boxes(corners, box, 0.0, 1.0) == hull_boxes(points, 0.0, 1.0, 0.3)


def test_least_box_without_qhull_is_qhulls(monkeypatch: pytest.MonkeyPatch) -> None:
    """footprint_box takes its candidate angles from the monotone chain, whose corners start
    elsewhere than Qhull's: the boxes are Qhull's to the last bit, ties included (squares and
    regular polygons, whose least boxes along different edges are equally small, go to
    Qhull's order)."""
    import bt_manip.bim.shapes as shapes

    ties = []
    for n in (4, 6, 8, 12):  # regular polygons, turned: boxes along different edges tie
        angles = np.arange(n) * (2 * math.pi / n) + 0.3
        ties.append(np.column_stack([np.cos(angles), np.sin(angles)]) * 2.0 + [5.0, -3.0])
    sets = [*_shapes(3), *ties, np.array([[0, 0], [2, 0], [2, 1], [0, 1.0]])]
    asked: list[int] = []
    qhull_angles = shapes._candidate_angles
    monkeypatch.setattr(shapes, "_candidate_angles",
                        lambda xy: asked.append(len(xy)) or qhull_angles(xy))
    fast = [footprint_box(np.column_stack([xy, np.zeros(len(xy))]), 0.4) for xy in sets]
    assert 0 < len(asked) < len(sets)  # Qhull's order asked for the ties only
    monkeypatch.setattr(shapes, "_chain_hull", lambda xy: None)  # Qhull's order always
    assert fast == [footprint_box(np.column_stack([xy, np.zeros(len(xy))]), 0.4)
                    for xy in sets]


def test_full_footprints_without_geos_are_geos(monkeypatch: pytest.MonkeyPatch) -> None:
    """A hull that clearly fills its box is found full from its corners' polygon; GEOS's
    hull gives the same boxes for every shape (boxes, polygons, round and scattered ones)."""
    import bt_manip.bim.footprints as footprints

    cases = []
    for xy in _shapes(4):
        corners = hull_xy(xy)
        cases.append((corners, footprint_box(np.column_stack([corners, np.zeros(len(corners))]),
                                             0.2)))
    fast = [strip_boxes(corners, box, 0.0, 1.0) for corners, box in cases]
    assert sum(len(boxes) == 1 for boxes in fast) > len(cases) // 4  # full ones among them
    monkeypatch.setattr(footprints, "_shoelace", lambda pts: -math.inf)  # GEOS decides
    assert fast == [strip_boxes(corners, box, 0.0, 1.0) for corners, box in cases]


def test_monotone_chain_is_the_textbook_chain() -> None:
    rng = np.random.default_rng(5)
    for xy in [*_shapes(5), *(np.round(rng.normal(size=(40, 2)) * 10, d) for d in range(4))]:
        pts = unique_rows(np.round(xy, 9))
        assert np.array_equal(monotone_chain(pts), textbook_chain(pts))
