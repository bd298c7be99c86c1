"""Shortcuts of the conversion that must give what the plain computation gives.

A placement's frame computed in Python floats is numpy's frame, number for number; the floor
grid's nearest clear spot found by trying the cells of a rectangle one by one is the one the
whole grid's distance transform gives; a polygon's next corners are ``np.roll``'s; the
monotone chain's corners do not depend on how its scale is found.
"""

from __future__ import annotations

import math

import numpy as np

from bt_manip.bim.floor_grid import FloorGrid, Rect
from bt_manip.bim.hulls import monotone_chain, next_rows, unique_rows
from bt_manip.bim.shapes import _frame, _frame_numpy


def test_frames_in_python_floats_are_numpys() -> None:
    rng = np.random.default_rng(11)
    cases = [(np.array((1.0, 2.0, 3.0)), np.array((0, 0, 1)), np.array((1, 0, 0)))]
    for _ in range(3000):
        scale = float(rng.choice([1e-3, 1.0, 1e3]))
        cases.append((rng.normal(size=3) * 100, rng.normal(size=3) * scale, rng.normal(size=3)))
    for origin, z, x in cases:
        fast, plain = _frame(origin, z, x), _frame_numpy(origin, z, x)
        assert np.array_equal(fast, plain)
        assert fast.strides == plain.strides  # the same layout for the products that follow


def test_degenerate_frames_take_numpys_path() -> None:
    # parallel axes: numpy's NaNs (and warning), as before
    with np.errstate(invalid="ignore", divide="ignore"):
        out = _frame((0.0, 0.0, 0.0), np.array((0.0, 0.0, 1.0)), np.array((0.0, 0.0, 2.0)))
        plain = _frame_numpy((0.0, 0.0, 0.0), np.array((0.0, 0.0, 1.0)),
                             np.array((0.0, 0.0, 2.0)))
    assert np.array_equal(out, plain, equal_nan=True)
    assert np.isnan(out[:3, 1]).all()


def test_next_rows_is_roll() -> None:
    pts = np.arange(12.0).reshape(6, 2)
    assert np.array_equal(next_rows(pts), np.roll(pts, -1, axis=0))
    assert np.array_equal(next_rows(pts[:, 0]), np.roll(pts[:, 0], -1))


def test_monotone_chain_of_any_scale_is_the_same() -> None:
    rng = np.random.default_rng(5)
    for _ in range(300):
        pts = unique_rows(np.round(rng.normal(size=(int(rng.integers(3, 40)), 2))
                                   * float(rng.choice([1e-3, 1.0, 1e4])), 6))
        corners = monotone_chain(pts)
        # every point lies on or inside the counter-clockwise hull
        edges = next_rows(corners) - corners
        for p in pts:
            rel = p - corners
            assert (edges[:, 0] * rel[:, 1] - edges[:, 1] * rel[:, 0] >= -1e-9).all()


def _grid(rng: np.random.Generator) -> FloorGrid:
    grid = FloorGrid((0.0, 0.0, float(rng.uniform(2, 8)), float(rng.uniform(2, 8))))
    for _ in range(int(rng.integers(1, 12))):
        grid.block(Rect(*(float(v) for v in rng.uniform(-1, 9, 2)),
                        float(rng.uniform(0.05, 3)), float(rng.uniform(0.05, 1)),
                        float(rng.uniform(-math.pi, math.pi))))
    if rng.random() < 0.3:
        grid.blocked |= rng.random(grid.blocked.shape) < float(rng.choice([0.001, 0.05, 0.3]))
    return grid


def test_nearest_clear_within_is_the_whole_grids() -> None:
    rng = np.random.default_rng(7)
    tried = found = 0
    for _ in range(120):
        grid = _grid(rng)
        for _ in range(4):
            half = float(rng.choice([0.05, 0.3, 0.37, 0.45, 0.8, 1.5]))
            within = Rect(*(float(v) for v in rng.uniform(-1, 8, 2)),
                          float(rng.uniform(0.1, 8)), float(rng.uniform(0.1, 8)),
                          float(rng.choice([0.0, rng.uniform(-3, 3)])))
            x, y = (float(v) for v in rng.uniform(-2, 10, 2))
            assert grid._clearance is None
            quick = grid.nearest_clear(x, y, half, within=within)
            grid.clearance()  # now the whole grid's answer
            assert grid.nearest_clear(x, y, half, within=within) == quick
            grid._clearance = None
            tried += 1
            found += quick is not None
    assert found > tried // 4  # spots found, not only refusals


def test_nearest_clear_on_an_empty_grid() -> None:
    grid = FloorGrid((0.0, 0.0, 4.0, 3.0))
    spot = grid.nearest_clear(1.0, 1.0, 0.4, within=Rect(1.0, 1.0, 2.0, 2.0))
    assert spot is not None and math.dist(spot, (1.0, 1.0)) < 0.05


def test_nearest_first_is_the_start_of_a_stable_sort() -> None:
    from bt_manip.bim.floor_grid import _nearest_first

    rng = np.random.default_rng(2)
    for _ in range(200):
        values = np.round(rng.uniform(0, 3, int(rng.integers(1, 60))), 1)  # many ties
        count = int(rng.integers(1, 12))
        assert _nearest_first(values, count) == np.argsort(values, kind="stable")[:count].tolist()


def test_nearest_clear_of_a_point_that_is_not_finite_is_the_whole_grids() -> None:
    grid = _grid(np.random.default_rng(4))
    within = Rect(3.0, 3.0, 4.0, 4.0)
    quick = grid.nearest_clear(math.nan, 1.0, 0.3, within=within)
    grid.clearance()
    assert grid.nearest_clear(math.nan, 1.0, 0.3, within=within) == quick
